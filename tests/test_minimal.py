"""The minimal-coordinate formulation: the same walker as the absolute-coordinate one, without constraints."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from biped_sim import config_from_dict, load_config, run, simulate
from biped_sim.animate import WalkerDrawing
from biped_sim.errors import ConfigError
from biped_sim.io.trajectory import load_run
from biped_sim.multibody.dispatch import formulation_of, make_workspace, system_rhs
from biped_sim.multibody.minimal import HIP, MinimalSystem, tree_system
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.tree import STAR, TREE, tree_state
from biped_sim.plots import plot_run
from biped_sim.testing import default_walker
from biped_sim.walkers import build_model

from .conftest import CONFIGS, invoke, one_line_error, plain_engine

MINIMAL = ["formulation.kind=minimal"]
TIGHT = ["integrator.rtol=1e-10", "integrator.atol=1e-13"]


def _rotate(phi: float, v: np.ndarray) -> np.ndarray:
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _planar_state(y: np.ndarray, minimal: MinimalSystem) -> np.ndarray:
    """The absolute-coordinate state of a minimal state (each body's centre of mass hangs from the hip)."""
    nb = minimal.body_mass.shape[0]
    n = HIP + nb
    q, qd = np.zeros((nb, 3)), np.zeros((nb, 3))
    for b in range(nb):
        phi, omega = y[HIP + b], y[n + HIP + b]
        arm = _rotate(phi, minimal.body_com[b])
        q[b] = (*(y[0:2] + arm), phi)
        qd[b] = (*(y[n : n + 2] + omega * np.array([-arm[1], arm[0]])), omega)
    return np.concatenate([q.ravel(), qd.ravel(), y[2 * n :]])


def _off_axis_star(planar: PlanarSystem) -> PlanarSystem:
    """The compass with a third body on the hip and centres of mass and feet off the leg axes (a general star)."""
    return planar._replace(
        body_mass=np.array([1.3, 1.1, 0.7]),
        body_inertia=np.array([0.006, 0.004, 0.002]),
        joint_bodies=np.array([[0, 1], [0, 2]], dtype=np.int64),
        joint_points=np.array([[0.02, 0.08, -0.01, 0.09], [0.02, 0.08, 0.03, -0.05]]),
        foot_center=np.array([[0.015, -0.21], [-0.01, -0.2]]),
    )


def _two_feet_per_leg(planar: PlanarSystem) -> PlanarSystem:
    """The compass with a second, smaller foot arc ahead of each leg's (several feet on one body)."""
    ahead = planar.foot_center + np.array([0.03, 0.005])
    return planar._replace(
        foot_body=np.array([0, 0, 1, 1], dtype=np.int64),
        foot_center=np.array([planar.foot_center[0], ahead[0], planar.foot_center[1], ahead[1]]),
        foot_radius=np.array([planar.foot_radius[0], 0.8 * planar.foot_radius[0]] * 2),
        foot_partner=np.array([2, 3, 0, 1], dtype=np.int64),
    )


def _random_states(minimal: MinimalSystem, seed: int, count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """(y, modes) near standing, both feet armed, about half of them pressed into the ground."""
    rng = np.random.default_rng(seed)
    nb, nf = minimal.body_mass.shape[0], minimal.foot_body.shape[0]
    states = []
    for _ in range(count):
        y = np.zeros(2 * (HIP + nb) + nf + 2)
        y[HIP : HIP + nb] = rng.uniform(-0.3, 0.3, nb)
        y[0] = rng.normal(0.0, 0.1)
        centre = minimal.foot_center[0]  # foot 0 between 3 mm in the air and 3 mm in the ground
        y[1] = minimal.foot_radius[0] - _rotate(y[HIP + minimal.foot_body[0]], centre)[1] + rng.uniform(-3e-3, 3e-3)
        y[HIP + nb : 2 * (HIP + nb)] = rng.normal(0.0, 1.0, HIP + nb)
        y[2 * (HIP + nb) : -2] = rng.normal(0.0, 1e-6, nf)
        modes = np.column_stack([np.ones(nf), rng.integers(0, 2, nf), rng.uniform(0.01, 1.0, nf)])
        states.append((y, modes))
    return states


@pytest.mark.parametrize("solve", ["arrow", "tree"])
@pytest.mark.parametrize("friction", ["ambrosio", "lugre"])
@pytest.mark.parametrize("star", ["compass", "off_axis_three_bodies", "two_feet_per_leg"])
def test_rhs_agrees_with_absolute_coordinates(friction: str, star: str, solve: str) -> None:
    """On random states satisfying the joints, both formulations give the same hip and leg accelerations, by the
    star's arrow solve and by the tree's (the general mass matrix and Cholesky, run on the same star): their
    equations, as plain Python (conftest.plain_engine; the compiled runs agree in the tests of walks below)."""
    planar = build_model(default_walker(f"friction.model={friction}")).system
    if star != "compass":
        planar = _off_axis_star(planar) if star == "off_axis_three_bodies" else _two_feet_per_leg(planar)
    minimal = tree_system(planar)
    assert minimal.star
    minimal = minimal._replace(topology=STAR if solve == "arrow" else TREE)
    nb, nf = minimal.body_mass.shape[0], minimal.foot_body.shape[0]
    n = HIP + nb
    hip_in_body0 = -minimal.body_com[0]
    loaded = 0
    with plain_engine():
        for y, modes in _random_states(minimal, seed=11, count=40):
            y_planar = _planar_state(y, minimal)
            assert tree_state(y_planar, planar) == pytest.approx(y, abs=1e-14)
            fast, full = np.zeros_like(y), np.zeros_like(y_planar)
            system_rhs(0.0, y, minimal, modes, make_workspace(minimal), fast)
            system_rhs(0.0, y_planar, planar, modes, make_workspace(planar), full)
            phi0, omega0, alpha0 = y[HIP], y[n + HIP], full[3 * nb + 2]
            arm = _rotate(phi0, hip_in_body0)
            hip_acceleration = full[3 * nb : 3 * nb + 2] + alpha0 * np.array([-arm[1], arm[0]]) - omega0**2 * arm
            expected = np.concatenate([hip_acceleration, full[3 * nb + 2 : 6 * nb : 3], full[6 * nb :]])
            scale = np.max(np.abs(expected))
            np.testing.assert_allclose(fast[n:], expected, rtol=1e-12, atol=1e-12 * scale)
            loaded += int(np.count_nonzero(full[6 * nb + nf :]))
    assert loaded > 10  # the contact forces took part


def test_layout_names_and_no_constraints() -> None:
    model = build_model(default_walker(*MINIMAL))
    assert model.state_names() == [
        *("x_hip", "y_hip", "phi_leg0", "phi_leg1", "vx_hip", "vy_hip", "omega_leg0", "omega_leg1"),
        *("z_foot0", "z_foot1", "W_normal", "W_friction"),
    ]
    layout = formulation_of(model.system).layout_of(model.system)
    assert layout.coordinate(1, "phi") == 3 and layout.rate(1, "omega") == 7 and layout.bristle(0) == slice(8, 9)
    assert formulation_of(model.system).measures.violation(model.y0, model.system) == (0.0, 0.0)


def _agreement(t_end: float) -> None:
    planar = simulate(default_walker(*TIGHT, t_end=t_end))
    minimal = simulate(default_walker(*MINIMAL, *TIGHT, t_end=t_end))
    assert minimal.status == planar.status == "walking"
    assert np.array_equal(minimal.steps.foot, planar.steps.foot) and len(minimal.steps.foot) >= 2 * t_end
    assert minimal.step_periods == pytest.approx(planar.step_periods, rel=1e-8)
    for kind in ("normal", "friction"):
        dissipated = minimal.summary["energy_dissipated"][kind]
        assert dissipated == pytest.approx(planar.summary["energy_dissipated"][kind], rel=1e-7)
    m_g_l = minimal.model.total_mass * 9.81 * minimal.model.leg_length
    assert np.max(np.abs(minimal.energy.residual)) < 1e-8 * m_g_l
    assert minimal.summary["energy_dissipated"]["normal"] > 0.01 * t_end * m_g_l  # the balance is not trivial
    assert minimal.summary["constraint_violation_max"] == {"position": 0.0, "velocity": 0.0}


def test_agrees_with_absolute_coordinates_short() -> None:
    _agreement(t_end=2.0)


@pytest.mark.slow
def test_agrees_with_absolute_coordinates_over_10_s() -> None:
    """The issue's check: step periods within 1e-8, dissipated energies within 1e-7 at dopri5 rtol 1e-10."""
    _agreement(t_end=10.0)


@pytest.mark.parametrize("method", [pytest.param("radau", marks=pytest.mark.slow), "rk4"])
def test_other_integrators(method: str) -> None:
    """The stiff (scipy) and fixed-step paths run the minimal formulation too."""
    sets = [f"integrator.method={method}", "integrator.dt=2e-5", "integrator.rtol=1e-6", "integrator.atol=1e-9"]
    planar = simulate(default_walker(*sets, t_end=1.0))
    minimal = simulate(default_walker(*MINIMAL, *sets, t_end=1.0))
    assert minimal.status == "walking" and minimal.summary["n_steps"] == planar.summary["n_steps"] >= 1
    assert minimal.step_periods == pytest.approx(planar.step_periods, rel=1e-3)


@pytest.mark.parametrize("name", ["round_foot_walker.yaml", "compass_goswami.yaml", "four_legged_walker.yaml"])
def test_cli_runs_the_planar_configs(name: str, tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "run"
    result = invoke("run", str(CONFIGS / name), "--set", "formulation.kind=minimal", "--set", "simulation.t_end=1.5",
                    "--out", str(out))  # fmt: skip
    assert result.exit_code == 0, result.output
    assert (out / "summary.json").is_file()


@pytest.mark.parametrize("sets", [["dynamics=rigid"], ["walker.kind=simplest", "dynamics=rigid"]])
def test_rigid_dynamics_refuse_it(sets: list[str]) -> None:
    with pytest.raises(ConfigError, match=r"formulation\.kind"):
        config_from_dict({}, [*MINIMAL, *sets])


@pytest.mark.slow
def test_four_legged_sagittal_motion_agrees_with_spatial() -> None:
    """The four-legged walker's laterally symmetric gait is sagittal: the minimal star (two pairs, two feet per
    pair at one sagittal place) walks as the spatial machine, to the integration error at rtol 1e-10."""
    runs = [
        simulate(
            load_config(CONFIGS / "four_legged_walker.yaml", [f"formulation.kind={kind}", "simulation.t_end=6", *TIGHT])
        )
        for kind in ("spatial", "minimal")
    ]
    spatial, minimal = runs
    assert (
        minimal.status == spatial.status == "walking" and minimal.summary["n_steps"] == spatial.summary["n_steps"] >= 12
    )
    assert minimal.step_periods == pytest.approx(spatial.step_periods, rel=3e-8)
    for kind in ("normal", "friction"):
        dissipated = minimal.summary["energy_dissipated"][kind]
        assert dissipated == pytest.approx(spatial.summary["energy_dissipated"][kind], rel=1e-7)
    assert np.max(np.abs(minimal.energy.residual)) < 1e-8 * minimal.model.total_mass * 9.81 * minimal.model.leg_length


def test_limit_cycle_refuses_minimal() -> None:
    result = invoke("limit-cycle", str(CONFIGS / "round_foot_walker.yaml"), "--set", "formulation.kind=minimal")
    assert result.exit_code == 2
    assert "formulation.kind" in one_line_error(result.stderr)


def test_bundled_config_starts_as_planar() -> None:
    """The builder converts the planar walker: the same start, hip and angles."""
    planar = build_model(load_config(CONFIGS / "round_foot_walker.yaml"))
    minimal = build_model(load_config(CONFIGS / "round_foot_walker.yaml", MINIMAL))
    assert isinstance(minimal.system, MinimalSystem)
    assert np.array_equal(minimal.y0, tree_state(planar.y0, planar.system))
    assert np.array_equal(minimal.modes0, planar.modes0)


def test_run_directory_reads_back_plots_and_animates(tmp_path) -> None:  # type: ignore[no-untyped-def]
    run(default_walker(*MINIMAL, t_end=1.0), tmp_path)
    data = load_run(tmp_path)
    assert data.body_names == ["leg0", "leg1"]  # x_hip is no body
    assert data.leg_angles().shape == data.leg_rates().shape == (len(data.time), 2)
    np.testing.assert_array_equal(data.hip, data.state[:, :2])
    assert np.all(data.violation_position == 0.0) and np.all(data.violation_velocity == 0.0)
    assert all(path.stat().st_size > 0 for path in plot_run(data, tmp_path / "figures"))
    fig = Figure()
    FigureCanvasAgg(fig)
    drawing = WalkerDrawing(data, fig)
    drawing.draw(0)
    assert np.hypot(drawing.arrows.U, drawing.arrows.V).max() > 0  # the stance foot carries the walker
