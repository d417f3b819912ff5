"""The bundled torso walker (configs/torso_walker.yaml): it walks in compliant and rigid dynamics (a stable rigid
cycle and its basin), and its torso held still is a mass at the hip."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from biped_sim.config import Config, config_from_dict, load_config
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.rigid.step import RTOL
from biped_sim.simulate import CompliantRunResult, RigidRunResult, simulate
from biped_sim.studies.basin import CONVERGED, FELL, BasinSpec, GridAxis, map_basin
from biped_sim.studies.convergence import converge
from biped_sim.studies.limit_cycle import limit_cycle

from .conftest import CONFIGS
from .test_joint_elements import held_in_the_world

TORSO_WALKER = CONFIGS / "torso_walker.yaml"


@pytest.mark.slow
def test_the_torso_walker_walks_a_periodic_gait_held_by_its_springs() -> None:
    result = simulate(load_config(TORSO_WALKER, ["simulation.t_end=15"]))
    periods = np.array(result.summary["step_periods"])
    assert result.status == "walking" and len(periods) >= 18
    assert np.ptp(periods[-6:]) < 1e-4 * periods[-1]  # period-1, settled
    layout = formulation_of(result.model.system).layout_of(result.model.system)
    torso = result.run.y[:, layout.coordinate(result.model.body_names.index("torso"), "phi")]
    assert 0.1 < np.max(np.abs(torso)) < 0.4  # it sways, held up by the springs
    audit = result.energy
    assert np.max(np.abs(audit.residual)) < 1e-6 * result.model.total_mass * 9.81 * result.model.leg_length


@pytest.mark.slow
def test_the_torso_walker_has_a_stable_rigid_cycle_near_its_compliant_gait_and_a_basin_around_it() -> None:
    """Rigid dynamics, the same file: a stable period-1 gait (measured: period 0.70926 s against the compliant
    0.7149 s, multipliers 0.289 +- 0.590i, 0.075, 0.011 +- ...), and its basin: on a 3 x 3 grid over the stance
    angle and rate around it (+-0.02 rad, +-0.1 rad/s; the other keys its fixed point's) the fixed point's cell and
    four others come back to the gait within 20 steps, and the corner of the larger angle and slower rate falls."""
    config = load_config(TORSO_WALKER, ["dynamics=rigid"])
    cycle = limit_cycle(config)
    assert cycle.converged and cycle.stable and np.max(np.abs(cycle.multipliers)) < 0.7
    assert cycle.step_period == pytest.approx(0.7149, rel=0.01)  # the compliant gait's period
    start = load_config(TORSO_WALKER, ["dynamics=rigid", f"simulation.initial={dict(cycle.fixed_point)}"])
    angle, rate = cycle.fixed_point["stance_angle"], cycle.fixed_point["stance_rate"]
    spec = BasinSpec(start, GridAxis("stance_angle", angle - 0.02, angle + 0.02, 3),
                     GridAxis("stance_rate", rate - 0.1, rate + 0.1, 3), steps=20, tolerance=1e-3)  # fmt: skip
    basin = map_basin(spec, None)
    assert basin.outcome[1, 1] == CONVERGED and np.count_nonzero(basin.outcome == CONVERGED) >= 5  # measured: 5
    assert basin.outcome[2, 2] == FELL  # a larger step angle with a slower stance leg: bounded


@pytest.mark.slow
def test_the_compliant_torso_walker_approaches_its_rigid_gait_as_the_contact_stiffens() -> None:
    """``converge`` on the torso walker (contact 1e7, 1e8, 1e9 N/m^1.5, restitution and LuGre slip falling with
    it, 8 steps from the rigid fixed point): the compliant step period and touchdown state (the legs' and the
    torso's angles and rates) approach the rigid gait's level after level."""
    _, rows = converge(load_config(TORSO_WALKER), levels=3, steps=8)
    assert all(row.status == "walking" for row in rows)
    periods = [abs(row.period_difference) for row in rows]
    touchdowns = [row.touchdown_difference for row in rows]
    assert periods == sorted(periods, reverse=True) and touchdowns == sorted(touchdowns, reverse=True)
    assert periods[0] > 1e-3 and periods[-1] < 2e-5  # measured: 5.6e-3, 2.3e-4, 9.5e-6 s
    assert touchdowns[-1] < 5e-4  # measured: 5.2e-2, 3.6e-3, 2.5e-4


def _compass_with_the_torso_at_the_hip(t_end: str) -> CompliantRunResult:
    """A run of :func:`_compass_with_the_torso_at_the_hip_config`."""
    result = simulate(_compass_with_the_torso_at_the_hip_config([t_end]))
    assert isinstance(result, CompliantRunResult)
    return result


def _compass_with_the_torso_at_the_hip_config(overrides: list[str]) -> Config:
    """The torso walker without its torso, the torso's mass added to the hip's, from the same leg state."""
    data = load_config(TORSO_WALKER, overrides).model_dump(mode="json")
    described, parameters = data["walker"]["description"], data["walker"]["parameters"]
    described["bodies"], described["joints"] = [], []
    values = {p["name"]: p["value"] for p in parameters}
    for p in parameters:
        p["value"] = values["hip_mass"] + values["torso_mass"] if p["name"] == "hip_mass" else p["value"]
    data["simulation"]["initial"] = {k: v for k, v in data["simulation"]["initial"].items() if "torso" not in k}
    return config_from_dict(data)


def _torso_held_upright(stiffness: float, overrides: list[str]) -> Config:
    """The torso walker with its torso held at the slope normal by a spring of ``stiffness`` and a critically damped
    damper (c = 2 sqrt(k I), I the torso's inertia about the hip) against the ground, instead of its springs to the
    legs; started upright and at rest unless ``overrides`` say otherwise."""
    upright = ["simulation.initial.torso_angle=0", "simulation.initial.torso_rate=0"]
    data = load_config(TORSO_WALKER, [*upright, *overrides]).model_dump(mode="json")
    values = {p["name"]: p["value"] for p in data["walker"]["parameters"]}
    hip_inertia = values["torso_inertia"] + values["torso_mass"] * values["torso_com"] ** 2
    held_in_the_world(data, stiffness, 2.0 * np.sqrt(stiffness * hip_inertia))
    return config_from_dict(data)


@pytest.mark.slow
def test_a_very_stiff_torso_spring_approaches_the_compass_with_the_torso_mass_at_the_hip() -> None:
    """A torso held still in the world moves with the hip: its centre of mass is the hip's plus a constant, so it
    is a point mass at the hip (docs/guide/rigid.md: why this limit and not the springs to the legs'). Held by a
    spring of k and a critically damped damper against the ground, the settled step period (the mean of the last
    three of 9 steps, 8 s) approaches the compass's with the torso's mass added to the hip's as 1/k once the
    torso's sway (sqrt(k / I)) is fast against the heel strike's contact (measured: 2.1e-4, 4.3e-5, 4.6e-6 apart
    at k = 1e4, 1e5, 1e6 N m/rad; at 1e1 to 1e3 it is not monotone yet: -1.8e-3, 2.8e-4, 3.6e-4); the energy
    audit closes with the stiffest spring as with the bundled walker's."""
    t_end = "simulation.t_end=8"
    compass = np.array(_compass_with_the_torso_at_the_hip(t_end).summary["step_periods"])
    gaps = []
    for stiffness in (1e4, 1e5, 1e6):
        held = simulate(_torso_held_upright(stiffness, [t_end]))
        periods = np.array(held.summary["step_periods"])
        assert held.status == "walking" and len(periods) == len(compass) >= 8
        gaps.append(float(np.mean(np.abs(periods[-3:] - compass[-3:]) / compass[-3:])))
    assert gaps[0] < 3e-4 and gaps[1] < 0.3 * gaps[0] and gaps[2] < 0.15 * gaps[1]  # 1/k: 0.2, 0.11 per decade
    audit, model = held.energy, held.model
    assert np.max(np.abs(audit.residual)) < 1e-6 * model.total_mass * 9.81 * model.leg_length
    assert audit.dissipated_elements[-1] > 1e4 * np.max(np.abs(audit.residual))  # measured: 6.7e-4 J, 1.7e-8 J


@pytest.mark.slow
def test_a_very_stiff_torso_spring_approaches_the_rigid_compass_with_the_torso_mass_at_the_hip() -> None:
    """Rigid dynamics, the same walkers: a finite spring passes no impulse through the instantaneous heel strike,
    so the strike kicks the torso (its rate just after it, on the section, stays near -2.4 rad/s for every k) and
    the critically damped spring then locks it within about sqrt(I / k): a second, plastic impact in effect. The
    limit cycle's period approaches the rigid compass's as 1/k (measured: 1.6e-4, 1.5e-5, 1.5e-6 at k = 1e2, 1e3,
    1e4 N m/rad)."""
    compass = limit_cycle(_compass_with_the_torso_at_the_hip_config(["dynamics=rigid"]))
    gaps = []
    for stiffness in (1e2, 1e3, 1e4):
        cycle = limit_cycle(_torso_held_upright(stiffness, ["dynamics=rigid"]))
        assert cycle.converged and cycle.stable
        gaps.append(abs(cycle.step_period - compass.step_period) / compass.step_period)
    assert gaps[0] < 3e-4 and all(0.05 < b / a < 0.2 for a, b in itertools.pairwise(gaps))


def test_the_rigid_audit_closes_with_a_stiff_damper_at_any_sampling() -> None:
    """The torso held in the world by k = 1e4 N m/rad, critically damped, 1 s from its gait (just after a heel
    strike, the torso kicked, and through the next): the damper's work is integrated with the flow, so the balance
    closes to the integrator's tolerance whether or not the samples resolve the torso's relaxation after each strike
    (about sqrt(I / k) = 1.6 ms; the trapezoidal rule over the samples left 0.15 J at 1 kHz against the damper's
    0.134 J; measured now: 1.3e-13 J at 100 Hz and 1 kHz), and the work at the coarse samples is the fine ones'."""
    gait = {"stance_angle": 0.2764, "swing_angle": -0.2764, "torso_angle": 0.0, "stance_rate": -1.0655,
            "swing_rate": -0.3362, "torso_rate": -2.384}  # fmt: skip
    start = [f"simulation.initial.{key}={value}" for key, value in gait.items()]
    runs = []
    for rate in (1000.0, 100.0):  # the default sampling, and ten times coarser
        result = simulate(_torso_held_upright(1e4, ["dynamics=rigid", "simulation.t_end=1", *start,
                                                    f"output.sample_rate={rate}"]))  # fmt: skip
        assert isinstance(result, RigidRunResult) and result.status == "walking"
        scale = float(np.max(np.abs(result.energy.kinetic) + np.abs(result.energy.potential)))
        assert np.max(np.abs(result.energy.residual)) < 10.0 * RTOL * scale
        runs.append(result)
    fine, coarse = runs
    common = np.isin(fine.time, coarse.time)  # the coarse grid is every tenth point of the fine one, step by step
    assert common.sum() == len(coarse.time) and len(coarse.steps.strike_time) >= 1
    worked = fine.energy.dissipated_elements[common]
    assert worked[-1] > 0.1
    np.testing.assert_allclose(coarse.energy.dissipated_elements, worked, rtol=0.0, atol=10.0 * RTOL * worked[-1])
