"""Rigid reference walkers: energy during the swing, momentum through the impact, known limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import config_from_dict, load_config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.tree import RigidWalker

from .conftest import CONFIGS


@pytest.fixture(scope="module")
def round_foot() -> RigidWalker:
    walker = rigid_walker(load_config(CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid"]))
    assert isinstance(walker, RigidWalker)
    return walker


def test_energy_is_conserved_during_the_swing(round_foot: RigidWalker) -> None:
    step = rigid_step(round_foot, np.array([0.25, -0.25, -1.6, -0.5]), sample_rate=1000.0)
    assert step.status == "strike"
    energy = np.array([sum(round_foot.energy(x)) for x in step.samples_x])
    kinetic = np.array([round_foot.energy(x)[0] for x in step.samples_x])
    assert np.ptp(kinetic) > 0.1 * kinetic.max()  # energy really moves between kinetic and potential
    assert np.ptp(energy) < 1e-10 * energy.max()


def test_heel_strike_is_located_on_the_guard(round_foot: RigidWalker) -> None:
    step = rigid_step(round_foot, np.array([0.25, -0.25, -1.6, -0.5]))
    assert abs(step.x_minus[0] + step.x_minus[1]) < 1e-12
    assert step.x_minus[1] > 0 > step.x_minus[0]  # swing foot ahead, mid-stance scuffing skipped


def test_impact_conserves_angular_momentum_about_the_new_contact(round_foot: RigidWalker) -> None:
    step = rigid_step(round_foot, np.array([0.25, -0.25, -1.6, -0.5]))
    x_minus, x_plus = step.x_minus, round_foot.impact(step.x_minus)
    l, R = round_foot.leg_length, round_foot.foot_radius
    hip = round_foot.hip(x_minus[:2])
    new_contact = hip + (l - R) * np.array([math.sin(x_minus[1]), -math.cos(x_minus[1])]) - [0.0, R]
    shift = new_contact - round_foot.contact_point(x_plus[:2])  # the new state lives in its own contact frame
    before = round_foot.angular_momentum(x_minus, new_contact)
    after = round_foot.angular_momentum(x_plus, new_contact - shift)
    assert after == pytest.approx(before, rel=1e-12)
    # the trailing leg keeps its angular momentum about the hip: body 0 (on coordinate 0, the stance leg)
    # before, body 1 (on coordinate 1, now the swing leg; the legs are identical) after
    trailing_before = round_foot.angular_momentum(x_minus, hip, coordinates={0})
    trailing_after = round_foot.angular_momentum(x_plus, hip - shift, coordinates={1})
    assert trailing_after == pytest.approx(trailing_before, rel=1e-12)
    # about the old contact point the impulse has a moment: not conserved (the check can fail)
    old_contact = round_foot.contact_point(x_minus[:2])
    assert (
        abs(
            round_foot.angular_momentum(x_plus, old_contact - shift) - round_foot.angular_momentum(x_minus, old_contact)
        )
        > 1e-3
    )
    # kinetic energy is lost in a plastic impact
    assert round_foot.energy(x_plus)[0] < round_foot.energy(x_minus)[0]


def test_compass_with_vanishing_leg_mass_tends_to_the_simplest_walker() -> None:
    """The multibody compass (point feet, legs' mass at the feet -> 0) reproduces Garcia's equations."""
    config = config_from_dict(
        {
            "dynamics": "rigid",
            "walker": {
                "kind": "compass",
                "leg_length": 1.0,
                "foot_radius": 0.0,
                "leg_mass": 1e-6,
                "leg_com_from_hip": 1.0,
                "leg_inertia": 0.0,
                "hip_mass": 1.0,
            },
            "gravity": 1.0,
            "ground": {"slope": 0.009},
            "contact": {"stiffness": 1e6},
        }
    )
    guess = {"stance_angle": 0.2, "stance_rate": -0.2, "swing_angle": -0.2, "swing_rate": -0.18}
    cycle = rigid_limit_cycle(config, guess)
    assert cycle.fixed_point["stance_angle"] == pytest.approx(0.20031090049483, abs=1e-6)
    assert cycle.fixed_point["stance_rate"] == pytest.approx(-0.19983247291764, abs=1e-6)


@pytest.mark.parametrize(("spokes", "slope"), [(8, 0.1), (12, 0.2)])
def test_rimless_wheel_analytic_fixed_point_and_multiplier(spokes: int, slope: float) -> None:
    config = config_from_dict(
        {
            "dynamics": "rigid",
            "walker": {"kind": "rimless_wheel", "spokes": spokes, "leg_length": 1.0},
            "ground": {"slope": slope},
        }
    )
    alpha = math.pi / spokes
    rate = math.sqrt(4 * 9.81 * math.sin(alpha) * math.sin(slope)) / math.tan(2 * alpha)
    cycle = rigid_limit_cycle(
        config, {"stance_angle": alpha, "stance_rate": -1.3 * rate, "swing_angle": 0, "swing_rate": 0}
    )
    assert cycle.fixed_point["stance_angle"] == pytest.approx(alpha, abs=1e-12)
    assert -cycle.fixed_point["stance_rate"] == pytest.approx(rate, abs=1e-8)
    assert cycle.multipliers[0].real == pytest.approx(math.cos(2 * alpha) ** 2, abs=1e-6)


def test_rigid_dynamics_is_simulated_by_the_rigid_model() -> None:
    from biped_sim import simulate
    from biped_sim.rigid.start import INTEGRATOR
    from biped_sim.simulate.rigid import RigidRunResult

    result = simulate(load_config(CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid", "simulation.t_end=1"]))
    assert isinstance(result, RigidRunResult) and result.summary["integrator"] == INTEGRATOR
