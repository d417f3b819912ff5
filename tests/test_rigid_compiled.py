"""The compiled rigid step map of every rigid walker: energy through a step, falls, walks of many starts, stalls."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import load_config
from biped_sim.config import Config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import FELL, STALLED, STRIKE, rigid_step, walk_starts
from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.limit_cycle import rigid_limit_cycle

from .conftest import CONFIGS

# (config, overrides, a post-impact start near its gait)
CASES = {
    "simplest": (CONFIGS / "simplest_walker.yaml", [], [0.2, -0.2, -0.2, -0.2 * math.cos(0.4)]),
    "compass": (CONFIGS / "compass_goswami.yaml", ["dynamics=rigid"], [0.2, -0.2, -1.0, -0.4]),
    "round_foot": (CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid"], [0.25, -0.25, -1.6, -0.5]),
    "rimless_wheel": (CONFIGS / "rimless_wheel.yaml", ["dynamics=rigid"], [math.pi / 8, -1.0]),
    "offsets": (
        CONFIGS / "round_foot_walker.yaml",
        ["dynamics=rigid", "walker.foot_offset=0.002", "walker.leg_com_offset=-0.001"],
        [0.25, -0.25, -1.6, -0.5],
    ),
}


def _config(name: str) -> Config:
    path, overrides, _ = CASES[name]
    return load_config(path, overrides)


@pytest.mark.parametrize("name", CASES)
def test_a_step_keeps_its_energy_until_the_plastic_strike_takes_some(name: str) -> None:
    walker = rigid_walker(_config(name))
    step = rigid_step(walker, np.array(CASES[name][2]), sample_rate=200.0)
    assert step.status == "strike" and step.x_plus is not None and len(step.samples_t) > 20
    energy = np.array([sum(walker.energy(x)) for x in [*step.samples_x, step.x_minus]])
    assert np.ptp(energy) < 1e-10 * walker.reference_mass * walker.gravity * walker.leg_length
    assert walker.energy(step.x_plus)[0] < walker.energy(step.x_minus)[0]


def test_a_fall_is_a_status_ended_on_a_fall_criterion() -> None:
    walker = rigid_walker(_config("compass"))
    x0 = np.array([0.3, -0.3, 0.5, 2.0])  # rocking back uphill with the swing leg flung forward
    step = rigid_step(walker, x0)
    assert step.status == "fell" and step.x_plus is None and 0.0 < step.period < 5.0
    leg_margin = walker.fall_leg_angle - np.max(np.abs(step.x_minus[:2]))
    hip_margin = walker.hip_height(step.x_minus) - FALL_HIP_FRACTION * walker.leg_length
    assert min(abs(leg_margin), abs(hip_margin)) < 1e-12  # located on the criterion it crossed


def test_walk_from_the_fixed_point_keeps_it_and_from_far_away_falls() -> None:
    config = _config("simplest")
    cycle = rigid_limit_cycle(config)
    walker = rigid_walker(config)
    on_cycle = walker.from_section(cycle.section_point)
    starts = np.array([on_cycle, walker.from_section(np.array([0.2, -0.6]))])
    outcome = walk_starts(walker, starts, 20)
    assert outcome.status[0] == STRIKE and outcome.steps[0] == 20
    assert np.max(np.abs(outcome.last[0] - on_cycle)) < 1e-9
    assert outcome.status[1] == FELL and outcome.steps[1] < 20


def test_a_walk_from_legs_together_stalls_instead_of_striking_in_no_time() -> None:
    walker = rigid_walker(_config("simplest"))
    outcome = walk_starts(walker, np.array([[0.0, 0.0, -0.4, -0.4]]), 5)
    assert outcome.status[0] == STALLED and outcome.steps[0] == 0


def _offset_compass_energy(config: Config, x: np.ndarray) -> float:
    """Kinetic + potential energy of the compass with offsets, from the positions of the config's spec (the rates
    by central differences): legs' mass at c along and w across, the hip mass, feet arcs rolling, centred d across."""
    w = config.walker
    l, r, d, c, off = w.leg_length, w.foot_radius, w.foot_offset, w.leg_com_from_hip, w.leg_com_offset
    gravity = config.gravity * np.array([math.sin(config.ground.slope), -math.cos(config.ground.slope)])

    def positions(q: np.ndarray) -> list[np.ndarray]:
        th = q[0]
        hip = np.array(
            [-r * th - (l - r) * math.sin(th) - d * math.cos(th), r + (l - r) * math.cos(th) - d * math.sin(th)]
        )
        legs = [hip + c * np.array([math.sin(t), -math.cos(t)]) + off * np.array([math.cos(t), math.sin(t)]) for t in q]
        return [hip, *legs]

    q, qd, h = x[:2], x[2:], 1e-6
    masses = [w.hip_mass, w.leg_mass, w.leg_mass]
    ahead, behind = positions(q + h * qd), positions(q - h * qd)
    energy = 0.5 * w.leg_inertia * float(qd @ qd)
    for m, p, pa, pb in zip(masses, positions(q), ahead, behind, strict=True):
        v = (pa - pb) / (2 * h)
        energy += 0.5 * m * v @ v - m * gravity @ p
    return energy


def test_compass_with_offsets_conserves_energy_between_strikes() -> None:
    """The offsets' flow (Kane's equations with w, d != 0) conserves the energy of the spec's own positions."""
    config = load_config(CONFIGS / "compass_goswami.yaml", ["walker.leg_com_offset=0.03", "walker.foot_offset=0.02"])
    walker = rigid_walker(config)
    x0 = np.array(CASES["compass"][2])
    step = rigid_step(walker, x0)
    plain = rigid_step(rigid_walker(_config("compass")), x0)
    assert step.status == "strike" and abs(step.period - plain.period) > 1e-3  # the offsets change the gait
    assert _offset_compass_energy(config, step.x_minus) == pytest.approx(_offset_compass_energy(config, x0), abs=1e-8)
