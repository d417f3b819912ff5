"""Rigid walkers with a body off the legs (a torso hinged at the hip): the flow, the heel strike, the section, the
limit cycle and falls named by what fell."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from biped_sim import config_from_dict, load_config
from biped_sim.errors import ConfigError
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.step import RTOL
from biped_sim.rigid.tree import RigidWalker
from biped_sim.simulate import simulate
from biped_sim.simulate.rigid import RigidRunResult, fall_reason

from .conftest import ROOT
from .test_joint_elements import held_in_the_world

# compass legs with a heavy hip and a torso hanging below the hip on a free joint (a pendulum: no spring holds it)
TORSO_WALKER: dict[str, Any] = {
    "dynamics": "rigid",
    "gravity": 9.81,
    "ground": {"slope": 0.02},
    "walker": {
        "kind": "description",
        "description": {
            "leg": {
                "bodies": [{"name": "leg", "mass": 1.0, "inertia": 0.02, "com": [0.0, -0.5]}],
                "feet": [{"name": "foot", "body": "leg", "centre": [0.0, -1.0], "radius": 0.0}],
            },
            "bodies": [{"name": "torso", "mass": 1.0, "inertia": 0.01, "com": [0.0, -0.2]}],
            "point_masses": [{"name": "hip", "body": "leg_1", "at": [0.0, 0.0], "mass": 5.0}],
            "joints": [{"name": "waist", "parent": "leg_1", "child": "torso", "at": [0.0, 0.0]}],
        },
    },
    "simulation": {"t_end": 5.0, "initial": "rigid_limit_cycle"},
}
TORSO_COMPASS = ROOT / "tests" / "data" / "torso_compass.yaml"  # springs and dampers hold its torso upright
START = np.array([0.2, -0.2, 0.05, -0.9, -0.7, -1.2])  # stance, swing, torso angles; their rates


def torso_config(com_y: float = -0.2, stiffness: float = 0.0) -> dict[str, Any]:
    """The torso walker with its torso's centre of mass at com_y and, if ``stiffness``, a spring of it to each leg."""
    config = copy.deepcopy(TORSO_WALKER)
    config["walker"]["description"]["bodies"][0]["com"] = [0.0, com_y]
    if stiffness:
        config["walker"]["description"]["joints"][0]["elements"] = [
            {"name": "spring_1", "law": "linear_spring", "stiffness": stiffness},
            {"name": "spring_2", "law": "linear_spring", "stiffness": stiffness, "against": "leg_2"},
        ]
    return config


@pytest.fixture(scope="module")
def torso() -> RigidWalker:
    return rigid_walker(config_from_dict(TORSO_WALKER))


def test_the_torso_is_a_coordinate_after_the_legs_and_in_the_section(torso: RigidWalker) -> None:
    assert torso.state_names == ("stance_angle", "swing_angle", "torso_angle", "stance_rate", "swing_rate",
                                 "torso_rate")  # fmt: skip
    assert torso.section_names == ("stance_angle", "stance_rate", "swing_rate", "torso_angle", "torso_rate")
    z = np.array([0.2, -0.9, -0.7, 0.05, -1.2])
    np.testing.assert_array_equal(torso.to_section(torso.from_section(z)), z)
    np.testing.assert_array_equal(torso.from_section(z)[[2, 5]], [0.05, -1.2])


def test_energy_is_conserved_through_the_swing_with_a_torso(torso: RigidWalker) -> None:
    step = rigid_step(torso, START, sample_rate=1000.0)
    assert step.status == "strike"
    energy = np.array([sum(torso.energy(x)) for x in step.samples_x])
    kinetic = np.array([torso.energy(x)[0] for x in step.samples_x])
    assert np.ptp(kinetic) > 0.1 * kinetic.max()
    assert np.ptp(energy) < 1e-10 * np.abs(energy).max()
    assert np.ptp(step.samples_x[:, 2]) > 0.05  # the torso swings on its own


def test_the_heel_strike_keeps_the_torso_angle_and_its_angular_momentum_about_the_hip(torso: RigidWalker) -> None:
    step = rigid_step(torso, START)
    x_minus, x_plus = step.x_minus, torso.impact(step.x_minus)
    assert x_plus[2] == x_minus[2]  # the torso keeps its coordinate through the relabelling
    hip = torso.hip(x_minus[:3])
    shift = torso.hip(x_plus[:3]) - hip  # the new state lives in its own contact frame
    before = torso.angular_momentum(x_minus, hip, coordinates={2})
    after = torso.angular_momentum(x_plus, hip + shift, coordinates={2})
    assert after == pytest.approx(before, rel=1e-12)  # the hip's impulse has no moment about the hip
    assert abs(x_plus[5] - x_minus[5]) > 1e-3  # but its rate jumps with the hip's velocity (com off the hip)
    new_contact = np.array(torso.swing_foot(x_minus, 0.0, 0.0))
    total_before = torso.angular_momentum(x_minus, new_contact)
    total_after = torso.angular_momentum(x_plus, new_contact + shift)
    assert total_after == pytest.approx(total_before, rel=1e-12)


def test_the_torso_walker_finds_its_limit_cycle_and_multipliers() -> None:
    cycle = rigid_limit_cycle(config_from_dict(TORSO_WALKER))
    assert cycle.converged
    assert len(cycle.multipliers) == 5
    assert set(cycle.fixed_point) >= {"torso_angle", "torso_rate"}
    assert cycle.step_period > 0.0


def test_an_unheld_upright_torso_falls_and_is_named() -> None:
    walker = rigid_walker(config_from_dict(torso_config(com_y=0.3)))
    step = rigid_step(walker, START)
    assert step.status == "fell"
    assert fall_reason(walker, step) == "the body 'torso' (off the legs) past its fall_angle from the slope normal"


def test_a_rigid_torso_falls_past_its_own_fall_angle_named_as_in_compliant_runs() -> None:
    """The torso's own fall_angle (0.8 here, the legs' limit 1.4) ends the rigid run, with the compliant wording."""
    config = load_config(TORSO_COMPASS, ["dynamics=rigid", "walker.parameters.torso_stiffness=0",
                                         "walker.parameters.torso_damping=0", "simulation.t_end=3",
                                         "walker.description.bodies.torso.fall_angle=0.8"])  # fmt: skip
    result = simulate(config)
    assert isinstance(result, RigidRunResult) and result.status == "fell"
    assert result.status_reason == "the body 'torso' (off the legs) past its fall_angle from the slope normal"
    torso = np.abs(result.state[:, result.walker.state_names.index("torso_angle")])
    assert 0.7 < np.max(torso) < 0.8 + 1e-6  # stopped at its own limit, not the legs' 1.4


def test_a_rigid_torso_started_past_its_fall_angle_is_one_line() -> None:
    overrides = ["dynamics=rigid", "walker.description.bodies.torso.fall_angle=0.4",
                 "simulation.initial.torso_angle=0.5"]  # fmt: skip
    with pytest.raises(ConfigError) as error:
        simulate(load_config(TORSO_COMPASS, overrides))
    message = str(error.value)
    assert message.startswith("simulation.initial.torso_angle: beyond the fall_angle of the body 'torso'")
    assert "\n" not in message


def test_hip_springs_hold_an_upright_torso_and_their_energy_closes_the_swing() -> None:
    walker = rigid_walker(config_from_dict(torso_config(com_y=0.2, stiffness=20.0)))
    step = rigid_step(walker, START, sample_rate=1000.0)
    assert step.status == "strike"
    energy = np.array([sum(walker.energy(x)) for x in step.samples_x])
    assert np.ptp(energy) < 1e-10 * np.abs(energy).max()  # the springs' potential in the energy: conserved
    theta = step.samples_x[:, 2] - step.samples_x[:, 0], step.samples_x[:, 2] - step.samples_x[:, 1]
    stored = 0.5 * 20.0 * (theta[0] ** 2 + theta[1] ** 2)
    assert np.ptp(stored) > 1e-3 * np.abs(energy).max()  # the springs really store and release energy
    unheld = rigid_step(rigid_walker(config_from_dict(torso_config(com_y=0.2))), START)
    assert unheld.status == "fell"  # without the springs the same torso falls


def test_a_spring_against_the_ground_holds_the_torso_s_absolute_angle_and_its_energy_closes_the_swing() -> None:
    """``against: ground`` (the bundled torso walker's torso held in the world, from the compass's gait): the
    spring's energy is k phi_t^2 / 2 of the torso's own angle, in the conserved total."""
    data = load_config(ROOT / "configs" / "torso_walker.yaml", ["dynamics=rigid"]).model_dump(mode="json")
    held_in_the_world(data, 40.0, 0.0)
    walker = rigid_walker(config_from_dict(data))
    start = np.array([0.2764, -0.2764, 0.0, -1.0898, -0.3776, 0.0])  # the compass's gait, the torso upright, still
    step = rigid_step(walker, start, sample_rate=1000.0)
    assert step.status == "strike"
    energy = np.array([sum(walker.energy(x)) for x in step.samples_x])
    assert np.ptp(energy) < 1e-10 * np.abs(energy).max()
    stored = 0.5 * 40.0 * step.samples_x[:, 2] ** 2
    assert np.ptp(stored) > 1e-6 * np.abs(energy).max()  # the spring stores and releases energy
    held_in_the_world(data, 0.0, 0.0)
    free = rigid_walker(config_from_dict(data))
    x = step.samples_x[-1]
    assert sum(walker.energy(x)) - sum(free.energy(x)) == pytest.approx(stored[-1], rel=1e-9)


def test_a_rigid_run_books_the_dampers_work() -> None:
    result = simulate(load_config(TORSO_COMPASS, ["dynamics=rigid", "simulation.t_end=0.6"]))
    assert isinstance(result, RigidRunResult)
    worked = result.energy.dissipated_elements
    assert worked[-1] > 0.01 * abs(result.energy.kinetic).max() and np.all(np.diff(worked) >= 0.0)
    # integrated with the flow: the balance closes to the integration's tolerance
    assert np.abs(result.energy.residual).max() < 10.0 * RTOL * np.abs(result.energy.potential).max()
