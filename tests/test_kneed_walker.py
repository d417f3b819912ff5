"""Chen's kneed walker, the first walker that is only data: its rigid phases, strikes and gait.

Reference: H. Chen (2007), "Passive dynamic walking with knees: a point foot model", M.Eng. thesis, MIT, Ch. 3,
Table 3.1 (the masses and lengths in configs/kneed_walker.yaml) and the fixed point it prints just after heel strike
(angles from the vertical): q1 = 0.1877, q2 = q3 = -0.2884, q1dot = -1.1014, q2dot = q3dot = -0.0399, computed by
explicit Euler at a 1 ms step with g = 9.8 and the slope asin(7.25 / 144) (issue 19 states the digits and the
scheme).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from biped_sim.config import derive, load_config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.tree import RigidWalker
from biped_sim.rigid.tree_kernels import (
    PAST,
    STOP,
    tree_impact,
    tree_rhs,
)
from biped_sim.rigid.tree_layout import point
from biped_sim.simulate import initial_state, prepare_model
from biped_sim.studies.basin import CONVERGED, BasinSpec, map_basin, parse_axis
from biped_sim.studies.continuation import continue_cycle, flip_margin
from biped_sim.studies.robustness import gait_start, largest_disturbance, trial
from biped_sim.walkers import BuiltModel, describe

from .conftest import CONFIGS

KNEED = CONFIGS / "kneed_walker.yaml"
CHEN_SLOPE = math.asin(7.25 / 144.0)
CHEN_FIXED_POINT = np.array([0.1877, -0.2884, -1.1014, -0.0399])  # q1, q2 = q3, q1dot, q2dot = q3dot
EULER_STEP = 1e-3


def chen_walker() -> RigidWalker:
    walker = rigid_walker(derive(load_config(KNEED), {"gravity": 9.8, "ground.slope": CHEN_SLOPE}))
    assert isinstance(walker, RigidWalker)
    return walker


def chen_state(walker: RigidWalker, q: np.ndarray) -> np.ndarray:
    """Chen's (q1, q2, q1dot, q2dot), angles from the vertical, as a post-impact state (slope-normal angles)."""
    return walker.from_section(np.array([q[0] + CHEN_SLOPE, q[2], q[3]]))


def chen_coordinates(walker: RigidWalker, x: np.ndarray) -> np.ndarray:
    n = walker.n_q
    return np.array([x[0] - CHEN_SLOPE, x[2] - CHEN_SLOPE, x[n], x[n + 2]])


def euler_step(walker: RigidWalker, x: np.ndarray, dt: float) -> np.ndarray:
    """One step by explicit Euler at a fixed dt, each phase ending at the first step past its guard, where the
    strike is applied (the same flow, guards and strike maps as the compiled step)."""
    x = np.array(x, dtype=float)
    walker.begin_step()
    for index, (name, guard) in enumerate(walker.guard_phases()):
        if walker.skip_phase(index, x):
            continue
        for _ in range(round(2.0 / dt)):  # a phase is shorter than 2 s
            if guard(x) < 0.0:
                break
            x = x + dt * walker.rhs(x)
        assert guard(x) < 0.0 and not walker.fallen(x), name
        x = walker.after_phase(index, x)
    return walker.impact(x)


def test_explicit_euler_at_1_ms_reproduces_chens_printed_fixed_point() -> None:
    walker = chen_walker()
    after = chen_coordinates(walker, euler_step(walker, chen_state(walker, CHEN_FIXED_POINT), EULER_STEP))
    # Euler's fixed-step strikes quantise the step time (1 ms), so the map jitters by a few 1e-4 between steps:
    # Chen's printed point comes back to within 5 units of its last digit
    assert np.abs(after - CHEN_FIXED_POINT).max() < 5e-4
    # and it is Euler's: the accurate fixed point is far from it in the swing rate (README: the difference)
    cycle = rigid_limit_cycle(derive(load_config(KNEED), {"gravity": 9.8, "ground.slope": CHEN_SLOPE}))
    accurate = chen_coordinates(walker, walker.from_section(np.array(list(cycle_section(cycle)))))
    assert abs(accurate[3] - CHEN_FIXED_POINT[3]) > 1e-2 and np.abs(accurate - CHEN_FIXED_POINT)[:3].max() < 1e-2


def cycle_section(cycle) -> tuple[float, float, float]:  # type: ignore[no-untyped-def]
    fp = cycle.fixed_point
    return fp["stance_thigh_angle"], fp["stance_thigh_rate"], fp["swing_thigh_rate"]


def test_the_compiled_step_is_scipys_integration_of_the_same_equations_phase_by_phase() -> None:
    walker = chen_walker()
    x = chen_state(walker, CHEN_FIXED_POINT)
    compiled = rigid_step(walker, x)
    walker.begin_step()
    for phase in range(len(walker.phases())):  # solve_ivp to each guard (brentq on its dense output), the strikes
        if not walker.skip_phase(phase, x):
            x = walker.after_phase(phase, _phase_flow(walker, x, phase, 2.0)[-1])
    assert compiled.status == "strike" and compiled.x_plus is not None
    assert np.allclose(compiled.x_plus, walker.impact(x), rtol=0, atol=1e-10)


def _phase_flow(walker: RigidWalker, x: np.ndarray, phase: int, span: float) -> np.ndarray:
    """The flow of one phase to its guard (rtol 1e-12), the energy along it."""
    guard = walker.guard_phases()[phase][1]
    event = lambda _t, y: guard(y)  # noqa: E731
    event.terminal, event.direction = True, -1  # type: ignore[attr-defined]
    sol = solve_ivp(lambda _t, y: walker.rhs(y), (0, span), x, method="DOP853", rtol=1e-12, atol=1e-12,
                    events=event, dense_output=True)  # fmt: skip
    return sol.y.T


def test_energy_is_conserved_in_both_swing_phases() -> None:
    walker = chen_walker()
    walker.begin_step()
    x = chen_state(walker, CHEN_FIXED_POINT)
    phases = [kind for kind, _ in walker.phases()]
    assert phases[:2] == [STOP, PAST]
    for phase in (0, 2):  # the unlocked three-link swing, then the locked swing to the heel strike
        states = _phase_flow(walker, x, phase, 2.0)
        energies = np.array([sum(walker.energy(s)) for s in states])
        assert np.abs(energies - energies[0]).max() < 1e-10 * abs(energies[0])
        x = walker.after_phase(phase, states[-1])


def _momentum(walker: RigidWalker, x: np.ndarray, about: tuple[float, float], coordinates: set[int] | None) -> float:
    """Angular momentum of the points whose inertia turns with ``coordinates`` (None: all) about a point."""
    return walker.angular_momentum(x, np.asarray(about), coordinates)


def test_the_strikes_conserve_the_angular_momenta_they_should() -> None:
    walker = chen_walker()
    n, npts = walker.n_q, walker.n_points
    walker.begin_step()
    x = _phase_flow(walker, chen_state(walker, CHEN_FIXED_POINT), 0, 2.0)[-1]  # just before the knee strike
    hip = point(walker.params, npts, x[:n])
    after = walker.after_phase(0, x)
    # knee strike: the whole walker about the stance foot, the swing leg about the hip
    for about, legs in (((0.0, 0.0), None), (hip, {2, 3})):
        assert _momentum(walker, after, about, legs) == pytest.approx(_momentum(walker, x, about, legs), rel=1e-13)
    x = _phase_flow(walker, after, 2, 2.0)[-1]  # just before the heel strike
    foot, hip = point(walker.params, npts + 1, x[:n]), point(walker.params, npts, x[:n])
    plus = walker.impact(x)  # the new stance foot at the origin, the legs' roles exchanged
    new_hip = point(walker.params, npts, plus[:n])
    assert _momentum(walker, plus, (0.0, 0.0), None) == pytest.approx(_momentum(walker, x, foot, None), rel=1e-12)
    trailing_before, trailing_after = _momentum(walker, x, hip, {0, 1}), _momentum(walker, plus, new_hip, {2, 3})
    assert trailing_after == pytest.approx(trailing_before, rel=1e-12)
    assert plus[n + 2] == plus[n + 3] and plus[n] == plus[n + 1]  # both knees rigid through it


def test_kneed_walker_has_a_stable_gait_with_three_multipliers() -> None:
    cycle = rigid_limit_cycle(load_config(KNEED))
    assert cycle.converged and cycle.stable and len(cycle.multipliers) == 3
    assert cycle.fixed_point["stance_thigh_angle"] == cycle.fixed_point["stance_shank_angle"]


def _compass_as_knees(shank_mass: float) -> str:
    """Goswami's compass (configs/compass_goswami.yaml's masses, point feet) as a kneed walker: the knee 0.6 m below
    the hip, locked (two stops at one angle), the shank of the given mass."""
    return f"""
dynamics: rigid
gravity: 9.81
ground: {{slope: 0.0523598775598}}
walker:
  kind: description
  description:
    bodies:
      - {{name: thigh_1, mass: 5.0, com: [0.0, -0.5]}}
      - {{name: thigh_2, mass: 5.0, com: [0.0, -0.5]}}
      - {{name: shank_1, mass: {shank_mass}, com: [0.0, -0.2]}}
      - {{name: shank_2, mass: {shank_mass}, com: [0.0, -0.2]}}
    point_masses: [{{name: hip, body: thigh_1, mass: 10.0}}]
    joints:
      - {{name: hip, parent: thigh_1, child: thigh_2}}
      - {{name: knee_1, parent: thigh_1, child: shank_1, at: [0.0, -0.6],
         stops: [{{side: upper, angle: 0.0}}, {{side: lower, angle: 0.0}}]}}
      - {{name: knee_2, parent: thigh_2, child: shank_2, at: [0.0, -0.6],
         stops: [{{side: upper, angle: 0.0}}, {{side: lower, angle: 0.0}}]}}
    feet:
      - {{name: foot_1, body: shank_1, centre: [0.0, -0.4]}}
      - {{name: foot_2, body: shank_2, centre: [0.0, -0.4]}}
    legs: [[thigh_1, shank_1], [thigh_2, shank_2]]
simulation:
  initial: rigid_limit_cycle
"""


def test_a_massless_shank_and_a_locked_knee_make_the_compass_gait(tmp_path: Path) -> None:
    path = tmp_path / "compass_with_knees.yaml"
    path.write_text(_compass_as_knees(0.0))
    kneed = rigid_limit_cycle(load_config(path))
    point_feet = ["dynamics=rigid", "walker.foot_radius=0", "contact.stiffness=1e7"]
    compass = rigid_limit_cycle(load_config(CONFIGS / "compass_goswami.yaml", point_feet))
    assert kneed.stable and kneed.step_period == pytest.approx(0.7344, abs=1e-3)  # Goswami's, as in test_limit_cycle
    assert kneed.step_period == pytest.approx(compass.step_period, abs=1e-10)
    got = np.array([kneed.fixed_point[k] for k in ("stance_thigh_angle", "stance_thigh_rate", "swing_thigh_rate")])
    want = np.array([compass.fixed_point[k] for k in ("stance_angle", "stance_rate", "swing_rate")])
    assert np.allclose(got, want, rtol=0, atol=1e-9)
    assert np.allclose(sorted(abs(kneed.multipliers)), sorted(abs(compass.multipliers)), atol=1e-6)


HEAVY_KNEED = """
# a kneed walker written only as YAML: Chen's geometry, a heavier hip and legs with inertia
dynamics: rigid
ground: {slope: 0.05}
walker:
  kind: description
  description:
    bodies:
      - {name: thigh_1, mass: 0.5, inertia: 0.001, com: [0.0, -0.325]}
      - {name: thigh_2, mass: 0.5, inertia: 0.001, com: [0.0, -0.325]}
      - {name: shank_1, mass: 0.05, inertia: 0.0005, com: [0.0, -0.125]}
      - {name: shank_2, mass: 0.05, inertia: 0.0005, com: [0.0, -0.125]}
    point_masses: [{name: hip, body: thigh_1, mass: 0.6}]
    joints:
      - {name: hip, parent: thigh_1, child: thigh_2}
      - {name: knee_1, parent: thigh_1, child: shank_1, at: [0.0, -0.5], stops: [{side: upper, angle: 0.0}]}
      - {name: knee_2, parent: thigh_2, child: shank_2, at: [0.0, -0.5], stops: [{side: upper, angle: 0.0}]}
    feet:
      - {name: foot_1, body: shank_1, centre: [0.0, -0.5]}
      - {name: foot_2, body: shank_2, centre: [0.0, -0.5]}
    legs: [[thigh_1, shank_1], [thigh_2, shank_2]]
simulation:
  initial: {stance_thigh_angle: 0.24, stance_thigh_rate: -1.1, stance_shank_angle: 0.24, stance_shank_rate: -1.1,
            swing_thigh_angle: -0.24, swing_thigh_rate: -0.05, swing_shank_angle: -0.24, swing_shank_rate: -0.05}
"""


def test_a_new_walker_written_only_as_yaml_finds_its_gait_and_basin(tmp_path: Path) -> None:
    path = tmp_path / "heavy_kneed.yaml"
    path.write_text(HEAVY_KNEED)
    config = load_config(path)
    cycle = rigid_limit_cycle(config)
    assert cycle.converged and cycle.step_period > 0 and cycle.step_length > 0
    axes = parse_axis("x", "stance_thigh_angle=0.2:0.28:3"), parse_axis("y", "stance_thigh_rate=-1.3:-0.9:3")
    basin = map_basin(BasinSpec(config, *axes, steps=20), None)
    converged = basin.outcome == CONVERGED
    assert converged[1, 1] == cycle.stable and converged.any()


def test_kneed_walker_loses_its_period_one_gait_by_a_flip_on_steeper_slopes() -> None:
    config = load_config(CONFIGS / "kneed_walker.yaml")
    gait = rigid_limit_cycle(config)
    for slope in (0.07, 0.095, 0.12):  # natural continuation in slope, each cycle the next guess
        gait = continue_cycle(config, slope, gait.fixed_point)
        assert gait.converged
    assert not gait.stable and flip_margin(gait) < 0  # a real multiplier past -1: period doubling


def test_the_tree_kernels_run_as_plain_python_give_the_same_bits() -> None:
    """The slow reference of the compiled equations is their own code run uncompiled (``.py_func``)."""
    walker = chen_walker()
    x = chen_state(walker, CHEN_FIXED_POINT) + np.array([0.0, 0.0, 0.05, -0.1, 0.0, 0.0, 0.3, -0.2])
    for function, args in ((tree_rhs, (x,)), (tree_impact, (x, True))):
        compiled, plain = np.zeros_like(x), np.zeros_like(x)
        function(walker.params.copy(), *args, compiled)
        getattr(function, "py_func", function)(walker.params.copy(), *args, plain)
        assert np.array_equal(compiled, plain) and np.all(np.isfinite(compiled))


def test_a_described_walker_runs_pushed_and_down_a_step_with_its_energy_booked() -> None:
    from biped_sim import simulate  # the run API, above the rigid layer

    def run(*overrides: str):  # type: ignore[no-untyped-def]
        return simulate(load_config(CONFIGS / "kneed_walker.yaml", ["simulation.t_end=3", *overrides]))

    pushed = run("simulation.pushes=[{time: 1.3, impulse: [0.05, 0.0]}]")
    stepped = run("ground.profile={kind: steps, steps: [{at: 1.0, height: -0.005}]}")
    for result in (pushed, stepped):  # the push's work and the strikes' losses close the energy balance
        assert result.status == "walking" and result.summary["energy_residual_max_relative"] < 1e-9
    assert stepped.summary["step_periods"] != run().summary["step_periods"]  # the step down changed the gait


def test_robustness_finds_the_kneed_walkers_largest_push() -> None:
    gait = gait_start(load_config(CONFIGS / "kneed_walker.yaml"))
    survived, failed = largest_disturbance(gait, "push", 1.0)
    assert 0.0 < survived < (failed if failed is not None else math.inf)
    assert trial(gait, "push", survived).survived and not trial(gait, "push", failed or 10.0).survived


def test_the_compliant_kneed_walker_starts_on_its_rigid_limit_cycle() -> None:
    config = derive(load_config(CONFIGS / "kneed_walker_compliant.yaml"), {"simulation.initial": "rigid_limit_cycle"})
    start = initial_state(config)
    assert isinstance(start, dict) and set(start) == set(describe(config).state_keys())  # a kneed walker's keys
    assert start == rigid_limit_cycle(config).fixed_point
    model = prepare_model(config)
    assert isinstance(model, BuiltModel) and np.isfinite(model.y0).all()
