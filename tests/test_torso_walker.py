"""The bundled torso walker (configs/torso_walker.yaml): it walks in compliant and rigid dynamics (a stable rigid
cycle and its basin), and its torso held still is a mass at the hip."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from biped_sim.config import config_from_dict, load_config
from biped_sim.contact.joint_element import JOINT_ELEMENT_LAWS, element_parameters, make_elements
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.simulate import CompliantRunResult, simulate
from biped_sim.simulate.compliant import simulate_compliant
from biped_sim.studies.basin import CONVERGED, FELL, BasinSpec, GridAxis, map_basin
from biped_sim.studies.limit_cycle import limit_cycle
from biped_sim.walkers import build_model

from .conftest import CONFIGS

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


def _compass_with_the_torso_at_the_hip(t_end: str) -> CompliantRunResult:
    """The torso walker without its torso, the torso's mass added to the hip's, from the same leg state."""
    data = load_config(TORSO_WALKER, [t_end]).model_dump(mode="json")
    described, parameters = data["walker"]["description"], data["walker"]["parameters"]
    described["bodies"], described["joints"] = [], []
    values = {p["name"]: p["value"] for p in parameters}
    for p in parameters:
        p["value"] = values["hip_mass"] + values["torso_mass"] if p["name"] == "hip_mass" else p["value"]
    data["simulation"]["initial"] = {k: v for k, v in data["simulation"]["initial"].items() if "torso" not in k}
    return simulate(config_from_dict(data))


def _torso_held_upright(stiffness: float, t_end: str) -> CompliantRunResult:
    """The torso walker with its torso held at the slope normal by a spring of ``stiffness`` and a critically
    damped damper to the ground (elements against -1), instead of its springs to the legs."""
    loose = ["walker.parameters.torso_stiffness=0", "walker.parameters.torso_damping=0"]
    config = load_config(
        TORSO_WALKER, [t_end, *loose, "simulation.initial.torso_angle=0", "simulation.initial.torso_rate=0"]
    )
    model = build_model(config)
    nb, torso = len(model.body_names), model.body_names.index("torso")
    values = {p.name: p.value for p in config.walker.parameters}  # type: ignore[union-attr]
    hip_inertia = values["torso_inertia"] + values["torso_mass"] * values["torso_com"] ** 2
    laws = [JOINT_ELEMENT_LAWS[name].index for name in ("linear_spring", "linear_damper")]
    held = make_elements(
        np.array([[3 * torso + 2, -1, 3 * nb + 3 * torso + 2, -1]] * 2),
        np.array(laws),
        np.array([element_parameters("linear_spring", stiffness=stiffness),
                  element_parameters("linear_damper", damping=2.0 * np.sqrt(stiffness * hip_inertia))]),
    )  # fmt: skip
    return simulate_compliant(config, dataclasses.replace(model, system=model.system._replace(elements=held)))


@pytest.mark.slow
def test_a_very_stiff_torso_spring_approaches_the_compass_with_the_torso_mass_at_the_hip() -> None:
    """A torso held still in the world moves with the hip: its centre of mass is the hip's plus a constant, so it
    is a point mass at the hip. The limit is a torso held upright by a stiff spring (and a damper, critically
    damping its sway) to the slope normal; stiff springs to the legs would lock the legs together (each pulls the
    torso to its leg). The step periods agree within 1e-4 at k = 1e5 N m/rad, 8 s (about 10 steps), and the
    largest difference falls as k grows (measured: 5.7e-4, 4.7e-4, 2.4e-4, 7e-5 for k = 1e2 ... 1e5)."""
    t_end = "simulation.t_end=8"
    compass = np.array(_compass_with_the_torso_at_the_hip(t_end).summary["step_periods"])
    gaps = []
    for stiffness in (1e2, 1e3, 1e4, 1e5):
        held = _torso_held_upright(stiffness, t_end)
        periods = np.array(held.summary["step_periods"])
        assert held.status == "walking" and len(periods) == len(compass) >= 8
        gaps.append(float(np.max(np.abs(periods - compass) / compass)))
    assert gaps == sorted(gaps, reverse=True) and gaps[-1] < 1e-4 and gaps[0] > 3 * gaps[-1]
