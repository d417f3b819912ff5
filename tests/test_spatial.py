"""The spatial formulation: Euler-parameter kinematics, planar/spatial agreement, the four-legged walker."""

from __future__ import annotations

from typing import Any

import h5py
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from biped_sim import config_from_dict, load_config, run, simulate
from biped_sim.animate import WalkerDrawing
from biped_sim.errors import ConfigError
from biped_sim.io.trajectory import load_run
from biped_sim.multibody import euler_parameters as ep
from biped_sim.multibody.dispatch import formulation_of, make_workspace, system_rhs
from biped_sim.plots import plot_run
from biped_sim.testing import default_walker
from biped_sim.walkers import build_model

from .conftest import CONFIGS, plain_engine

SPATIAL = ["formulation.kind=spatial"]


def _matrix(fn, p: np.ndarray, n_in: int) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The matrix of a compiled linear map x -> fn(p, x) with n_in inputs."""
    return np.array([fn(tuple(p), tuple(e)) for e in np.eye(n_in)]).T


def _random_parameters(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit Euler parameters and a rate tangent to the unit sphere, from a generator of the test's own.

    Each test seeds its own: a shared generator would give a test different numbers depending on
    which tests ran before it (-k, reordering), so a failure could not be reproduced alone.
    """
    rng = np.random.default_rng(seed)
    p = rng.normal(size=4)
    p /= np.linalg.norm(p)
    pdot = rng.normal(size=4)
    return p, pdot - p * (p @ pdot)


@pytest.mark.parametrize("trial", range(5))
def test_euler_parameter_identities(trial: int) -> None:
    p, pdot = _random_parameters(seed=trial)
    a = _matrix(ep.rotate, p, 3)
    e = _matrix(ep.e_mul, p, 4)
    g = _matrix(ep.g_mul, p, 4)
    assert a @ a.T == pytest.approx(np.eye(3), abs=1e-14)
    assert np.linalg.det(a) == pytest.approx(1.0, abs=1e-14)
    assert e @ g.T == pytest.approx(a, abs=1e-14)  # A = E G^T
    assert e @ e.T == pytest.approx(np.eye(3), abs=1e-14)
    assert g @ g.T == pytest.approx(np.eye(3), abs=1e-14)
    assert e.T @ e == pytest.approx(np.eye(4) - np.outer(p, p), abs=1e-14)
    assert g.T @ g == pytest.approx(np.eye(4) - np.outer(p, p), abs=1e-14)
    assert e @ p == pytest.approx(np.zeros(3), abs=1e-15)
    assert g @ p == pytest.approx(np.zeros(3), abs=1e-15)
    assert np.array(ep.g_mul(tuple(pdot), tuple(pdot))) == pytest.approx(np.zeros(3), abs=1e-15)  # Gdot pdot = 0
    assert _matrix(ep.g_tmul, p, 3) == pytest.approx(g.T, abs=1e-15)
    assert _matrix(ep.rotate_t, p, 3) == pytest.approx(a.T, abs=1e-15)


@pytest.mark.parametrize("trial", range(3))
def test_angular_velocity_from_pdot(trial: int) -> None:
    """omega~ = Adot A^T (finite differences along a unit path) equals 2 E pdot; omega' = A^T omega = 2 G pdot."""
    p, pdot = _random_parameters(seed=100 + trial)
    h = 1e-6

    def unit(t: float) -> np.ndarray:
        q = p + t * pdot
        return q / np.linalg.norm(q)

    a = _matrix(ep.rotate, p, 3)
    a_dot = (_matrix(ep.rotate, unit(h), 3) - _matrix(ep.rotate, unit(-h), 3)) / (2 * h)
    skew = a_dot @ a.T
    assert skew == pytest.approx(-skew.T, abs=1e-8)
    omega = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
    assert omega == pytest.approx(2 * np.array(ep.e_mul(tuple(p), tuple(pdot))), abs=1e-8)
    assert a.T @ omega == pytest.approx(2 * np.array(ep.g_mul(tuple(p), tuple(pdot))), abs=1e-8)


def test_point_jacobian_is_exact() -> None:
    """B(p, s) = d(A(p) s)/dp for any p (A is quadratic: central differences are exact), B^T is its transpose."""
    rng = np.random.default_rng(7)
    p = rng.normal(size=4)  # not normalised: the Jacobian must hold off the unit sphere too
    s = rng.normal(size=3)
    h = 1e-3
    fd = np.array(
        [
            (np.array(ep.rotate(tuple(p + h * d), tuple(s))) - np.array(ep.rotate(tuple(p - h * d), tuple(s))))
            / (2 * h)
            for d in np.eye(4)
        ]
    ).T
    b = np.array([ep.b_mul(tuple(p), tuple(s), tuple(d)) for d in np.eye(4)]).T
    assert b == pytest.approx(fd, abs=1e-10)
    bt = np.array([ep.b_tmul(tuple(p), tuple(s), tuple(d)) for d in np.eye(3)]).T
    assert bt == pytest.approx(b.T, abs=1e-14)
    assert b @ p == pytest.approx(2 * np.array(ep.rotate(tuple(p), tuple(s))), abs=1e-12)  # Euler's theorem


def compass_in_both(t_end: float, rtol: float, atol: float) -> tuple[Any, Any]:
    """(planar, spatial) runs of the compass for ``t_end`` at dopri5 ``rtol`` and ``atol``, after checking that both
    walk the same steps."""
    tolerances = (f"integrator.rtol={rtol!r}", f"integrator.atol={atol!r}")
    planar = simulate(default_walker(*tolerances, t_end=t_end))
    spatial_run = simulate(default_walker(*SPATIAL, *tolerances, t_end=t_end))
    assert spatial_run.status == planar.status == "walking"
    assert spatial_run.summary["n_steps"] == planar.summary["n_steps"] >= 2 * t_end
    assert np.array_equal(spatial_run.steps.foot, planar.steps.foot)
    return planar, spatial_run


@pytest.mark.parametrize(
    ("t_end", "rtol", "atol"), [(2.0, 1e-11, 1e-13), pytest.param(10.0, 1e-12, 1e-14, marks=pytest.mark.slow)]
)  # 10 s: ~10 s of CPU
def test_spatial_compass_agrees_with_planar_and_balances_energy(t_end: float, rtol: float, atol: float) -> None:
    """Same walker, dopri5 at rtol 1e-11 over 2 s and 1e-12 over 10 s (23 steps; at 1e-11 their difference reaches
    1.2e-9 s there): heel strikes at the planar times to 1e-9 s (measured 8e-11 s both), dissipated energies to 1e-8
    relative (5e-11 normal, 8e-11 friction over 10 s)."""
    planar, spatial_run = compass_in_both(t_end, rtol, atol)
    np.testing.assert_allclose(spatial_run.steps.strike_time, planar.steps.strike_time, rtol=0, atol=1e-9)
    for kind in ("normal", "friction"):
        assert spatial_run.summary["energy_dissipated"][kind] == pytest.approx(
            planar.summary["energy_dissipated"][kind], rel=1e-8
        )
    m_g_l = spatial_run.model.total_mass * 9.81 * spatial_run.model.leg_length
    assert np.max(np.abs(spatial_run.energy.residual)) < 1e-9 * m_g_l
    assert spatial_run.summary["energy_dissipated"]["normal"] > 0.01 * t_end * m_g_l  # the balance is not trivial
    # the motion stays in the sagittal plane
    assert spatial_run.summary["lateral"]["roll_max"] < 1e-12
    assert spatial_run.summary["constraint_violation_max"]["normalization"] < 1e-8


@pytest.mark.slow
def test_the_spatial_and_planar_compass_differ_by_their_integration_errors_alone() -> None:
    """The two formulations write one motion: the feet are discs in the sagittal plane, whose lowest point is the
    planar arc's; the planar joint to the ground frame holds roll and yaw at 0, so the inertia across the plane does
    not act; Baumgarte holds the joints to 1e-13. What differs is the integration of two sets of coordinates, whose
    errors the tolerance sets (their difference as good as random at its level: atol 1e-13 against 9.999999999999999e-14
    moves it from 8e-11 to 3e-10 s): from rtol 1e-9 to 1e-11 the strike times come 40 times closer (3.5e-9 to
    8e-11 s)."""
    pairs = (compass_in_both(2.0, rtol, atol) for rtol, atol in ((1e-9, 1e-11), (1e-11, 1e-13)))
    loose, tight = (np.abs(spatial.steps.strike_time - planar.steps.strike_time).max() for planar, spatial in pairs)
    assert tight < 0.1 * loose


@pytest.mark.parametrize("overrides", [[], SPATIAL, ["walker.kind=four_legged", *SPATIAL]])
def test_state_layout_points_where_the_kernels_write(overrides: list[str]) -> None:
    """The formulation's named offsets: sliding the stance leg makes its feet's bristles and friction work move."""
    model = build_model(config_from_dict({}, [*overrides, "friction.model=lugre"]))
    layout = formulation_of(model.system).layout_of(model.system)
    assert layout.size == model.y0.size == len(model.state_names())
    assert model.state_names()[layout.work_normal] == "W_normal"
    y = model.y0.copy()
    y[layout.rate(0, "vx")] += 0.1
    ydot = np.zeros_like(y)
    with plain_engine():  # the right-hand side's source (the compiled one writes the same: the runs' tests)
        system_rhs(0.0, y, model.system, model.modes0, make_workspace(model.system), ydot)
    for foot in range(model.n_feet):
        assert np.any(ydot[layout.bristle(foot)] != 0.0) == (model.system.foot_body[foot] == 0)
    assert ydot[layout.work_friction] > 0.0


@pytest.mark.slow  # the bundled 12 s run: ~4 s (its first 1.5 s are pinned in test_golden)
def test_four_legged_walker_walks_20_steps() -> None:
    result = simulate(load_config(CONFIGS / "four_legged_walker.yaml"))
    assert result.status == "walking"
    assert result.summary["n_steps"] >= 20
    feet = result.steps.foot
    pairs = result.model.system.foot_body[feet]
    assert np.all(pairs[1:] != pairs[:-1])  # outer and inner pairs alternate
    last = result.step_periods[-5:]
    assert (last.max() - last.min()) / last.mean() < 1e-3
    assert np.all(result.step_lengths > 0.05)
    # four feet carry the walker: both feet of a pair share the load
    channels = result.summary["lateral"]
    assert channels["roll_max"] < 1e-6 and abs(channels["yaw_final"]) < 1e-6
    m_g_l = result.model.total_mass * 9.81 * result.model.leg_length
    assert result.summary["energy_residual_max"] < 1e-5 * m_g_l


@pytest.mark.slow  # two 10 s four-legged runs: ~5.5 s
def test_baumgarte_bounds_spatial_violations_standard_method_does_not() -> None:
    base = [*SPATIAL, "walker.kind=four_legged", "simulation.t_end=10", "integrator.rtol=1e-6", "integrator.atol=1e-8"]
    stabilised = simulate(config_from_dict({}, base))
    standard = simulate(config_from_dict({}, [*base, "formulation.baumgarte.alpha=0", "formulation.baumgarte.beta=0"]))
    assert stabilised.status == "walking" and stabilised.run.t_final == pytest.approx(10.0)
    b = stabilised.summary["constraint_violation_max"]
    s = standard.summary["constraint_violation_max"]
    for name in ("position", "velocity", "normalization"):
        assert b[name] < 1e-8
    assert s["position"] > 10 * b["position"]
    assert s["normalization"] > 10 * b["normalization"]
    for column in (0, 2):  # without stabilisation the drift grows with time
        drift = standard.violation[: len(standard.run.t) // 2 * 2, column].reshape(2, -1)
        assert drift[1].max() > drift[0].max()


def test_spatial_run_directory(tmp_path) -> None:  # type: ignore[no-untyped-def]
    config = config_from_dict({}, [*SPATIAL, "walker.kind=four_legged", "simulation.t_end=1"])
    run(config, tmp_path)
    data = load_run(tmp_path)
    assert data.hip.shape == (len(data.time), 3)
    assert data.normal_force.shape == (len(data.time), 4)
    assert data.violation_normalization is not None and data.attitude is not None
    assert set(data.attitude) == {"pitch", "roll", "yaw", "pitch_rate"}
    # the pitch rate integrates to the pitch (trapezoids over 1 ms samples; impacts make the rate steep, not jump)
    rate, pitch = data.attitude["pitch_rate"], data.attitude["pitch"]
    integrated = np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(data.time)[:, None], axis=0)
    assert integrated == pytest.approx(pitch[1:] - pitch[0], abs=5e-4)
    with h5py.File(tmp_path / "trajectory.h5") as f:
        assert f["contact/friction_force_lateral"].shape == (len(data.time), 4)
        assert f["state"].shape[1] == len(f["state_names"]) == 14 * 2 + 2 * 4 + 2
    assert set(data.summary["constraint_violation_max"]) == {"position", "velocity", "normalization"}
    # the single-run figures and the animation draw spatial runs too (sagittal view)
    assert data.leg_angles().shape == data.leg_rates().shape == (len(data.time), 2)
    written = plot_run(data, tmp_path / "figures")
    assert all(path.stat().st_size > 0 for path in written)
    fig = Figure()
    FigureCanvasAgg(fig)
    drawing = WalkerDrawing(data, fig)
    drawing.draw(0)
    assert len(drawing.walker.bodies) == 2 and len(drawing.arrows.U) == 4
    assert np.hypot(drawing.arrows.U, drawing.arrows.V).max() > 0  # feet on the ground carry the walker


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        (["walker.kind=four_legged"], "walker.kind"),
        ([*SPATIAL, "walker.kind=four_legged", "walker.foot_spacing_inner=0.3"], "walker.foot_spacing_inner"),
        ([*SPATIAL, "formulation.kind=cylindrical"], "formulation.kind"),
    ],
)
def test_four_legged_config_errors(overrides: list[str], field: str) -> None:
    with pytest.raises(ConfigError) as info:
        config_from_dict({}, overrides)
    assert info.value.field == field


def test_constraint_study_figure(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from biped_sim.report.constraint_study import study_runs, write_constraint_study

    base = [*SPATIAL, "walker.kind=four_legged", "simulation.t_end=0.3", "integrator.method=rk2"]
    for gains in (0, 10):
        overrides = [*base, f"formulation.baumgarte.alpha={gains}", f"formulation.baumgarte.beta={gains}"]
        run(config_from_dict({}, overrides), tmp_path / "sweep" / "runs" / f"gains{gains}")
    groups = study_runs(tmp_path / "sweep")
    assert list(groups) == ["rk2"] and [r.config.formulation.baumgarte.alpha for r in groups["rk2"]] == [0, 10]
    paths = write_constraint_study(tmp_path / "sweep", tmp_path / "figures")
    assert [p.name for p in paths] == ["constraint_violation.png", "constraint_violation.svg"]
    assert all(p.stat().st_size > 0 for p in paths)
    with pytest.raises(ConfigError):
        study_runs(tmp_path / "figures")
