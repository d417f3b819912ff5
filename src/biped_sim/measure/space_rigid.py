"""Measures of a rigid run of a walker in space: its step table with the lateral columns, and its samples in the
run's frame (state, hip, energy terms).

The step map's states live in each step's frame (:mod:`biped_sim.rigid.space_walk`: mirrored when the right leg
stands); every measure here is in the run's slope frame. The step table's columns are the compliant spatial runs'
(:func:`~biped_sim.measure.steps.lateral_steps`): touchdown pitch angles and rates of the landing ('stance') and
trailing ('swing') legs as the spatial formulation measures them (the leg's angle from the slope normal, positive
with the foot downhill, its rate about the lateral axis), and row k's width (the lateral distance between the
contact points strikes k and k + 1 put down), heading and bank (the new stance leg's at strike k) and sway (the
hip's lateral excursion over the step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from biped_sim.measure.rigid import RigidEnergy, RigidTrace
from biped_sim.measure.steps import StepTable
from biped_sim.rigid.space_dynamics import ground_point
from biped_sim.rigid.space_model import SpaceModel, pose, rot_y
from biped_sim.rigid.space_walk import MIRRORED, Frame, frame_energy
from biped_sim.walkers.space_geometry import TO_SPATIAL, attitude


@dataclass
class SpaceTrace(RigidTrace):
    """What the stepping loop collects (states in their step's frame: a post-strike state in the next step's, its
    contact point at the origin), and each step's frame (one more than the strikes: the first step's, then one after
    each strike)."""

    frames: list[Frame] = field(default_factory=list)


def _touchdown(x: np.ndarray) -> tuple[float, float, float, float]:
    """(landing leg's pitch, its rate, trailing leg's pitch, its rate) of a pre-strike state (module docstring)."""
    stance = attitude(x[0], x[1], x[2])
    landing = stance @ rot_y(x[3])
    omega = x[4:7]
    landing_omega = omega + x[7] * stance[:, 1]
    pitch = [math.atan2(-r[0, 2], r[2, 2]) for r in (landing, stance)]
    return pitch[0], -float(landing_omega[1]), pitch[1], -float(omega[1])


def space_step_table(model: SpaceModel, trace: SpaceTrace, hip_lateral: np.ndarray) -> StepTable:
    """One row per strike, the step it begins (period, length, width and sway nan for the last); ``hip_lateral``
    the hip's lateral position at the samples (run's frame)."""
    n = len(trace.strike_time)
    period, length, slip, width, sway = (np.full(n, np.nan) for _ in range(5))
    if n > 1:
        period[:-1] = np.diff(trace.strike_time)
        length[:-1] = trace.step_lengths[1:n]
        slip[:-1] = 0.0
    frames = trace.frames
    heading = np.array([frames[k + 1].sign * trace.strike_post[k][0] for k in range(n)])
    bank = np.array([frames[k + 1].sign * trace.strike_post[k][1] for k in range(n)])
    sample_step = np.concatenate(trace.sample_step) if trace.sample_step else np.zeros(0, dtype=int)
    strike_hip = [frames[k + 1].point(pose(model, trace.strike_post[k]).origin)[1] for k in range(n)]
    for k in range(n - 1):
        width[k] = abs(frames[k + 2].contact[1] - frames[k + 1].contact[1])
        inside = hip_lateral[sample_step == k + 1]
        sway[k] = float(np.ptp(np.concatenate([inside, strike_hip[k : k + 2]])))
    angles = np.array([_touchdown(x) for x in trace.strike_pre]).reshape(n, 4)
    feet = np.arange(1, n + 1) % 2  # the right foot (1) strikes first: the left leg stands at the start
    return StepTable(np.array(trace.strike_time), feet, period, length, slip, *angles.T, width, heading, sway, bank)


@dataclass
class SpaceSamples:
    """The samples in the run's frame: the state, the hip (the hinge's midpoint, spatial slope frame: x downhill,
    y the normal, z right) and the energy terms."""

    state: np.ndarray
    hip: np.ndarray
    energy: RigidEnergy


def space_samples(
    model: SpaceModel, trace: SpaceTrace, start: np.ndarray, times: np.ndarray, states: np.ndarray
) -> SpaceSamples:
    """The samples' state, hip and energy terms in the run's frame (module docstring of
    :mod:`biped_sim.rigid.space_walk`); ``start``: the run's first state, the energy balance's reference (a torso's
    elements' work integrated in the state: ``TORSO_NAMES``)."""
    sample_step = np.concatenate(trace.sample_step)
    frames = trace.frames
    signs = np.array([frames[k].sign for k in sample_step])
    world = np.where(signs[:, None] < 0, states * MIRRORED[: states.shape[1]], states)
    world[:, 8:10] += np.array([frames[k].contact[:2] for k in sample_step])
    hip = np.array(
        [frames[k].point(ground_point(x) + pose(model, x).origin) for k, x in zip(sample_step, states, strict=True)]
    )
    terms = np.array([frame_energy(model, frames[k], x) for k, x in zip(sample_step, states, strict=True)])
    losses = [
        sum(frame_energy(model, frames[k], pre)) - sum(frame_energy(model, frames[k + 1], post))
        for k, (pre, post) in enumerate(zip(trace.strike_pre, trace.strike_post, strict=True))
    ]
    dissipated = np.concatenate([[0.0], np.cumsum(losses)])[sample_step]
    for at, loss in trace.stop_losses:  # the knee strikes; a sample at one's time holds the state after it
        dissipated[times >= at] += loss
    push_work = np.zeros(len(times))
    for at, work, _ in trace.pushes:
        push_work[times >= at] += work  # a sample at a push's time holds the state after it
    elements = states[:, model.torso_angle + 2] - start[model.torso_angle + 2] if model.torso else np.zeros(len(times))
    residual = terms.sum(axis=1) - sum(frame_energy(model, frames[0], start)) + dissipated + elements - push_work
    energy = RigidEnergy(terms[:, 0], terms[:, 1], dissipated, elements, push_work, residual)
    return SpaceSamples(world, hip @ TO_SPATIAL.T, energy)


def leg_attitudes(state: np.ndarray, stance: np.ndarray) -> dict[str, np.ndarray]:
    """Each leg's (left, right) pitch, roll, yaw and pitch rate at the samples, as the spatial formulation measures
    a body's (:func:`~biped_sim.multibody.euler_parameters.attitude`: the leg's angle from the slope normal, positive
    with its foot downhill; the elevation of its axis to the right above the slope; that axis's heading; the rate
    about the lateral axis), from the run's state (its frame) and the stance leg of each sample (0 left, 1 right)."""
    out = {name: np.empty((len(state), 2)) for name in ("pitch", "roll", "yaw", "pitch_rate")}
    for i, (x, leg) in enumerate(zip(state, stance, strict=True)):
        rotation = attitude(x[0], x[1], x[2])
        turns = {leg: (rotation, x[4:7]), 1 - leg: (rotation @ rot_y(x[3]), x[4:7] + x[7] * rotation[:, 1])}
        for k, (r, omega) in turns.items():
            out["pitch"][i, k] = math.atan2(-r[0, 2], r[2, 2])
            out["roll"][i, k] = math.asin(max(-1.0, min(1.0, -r[2, 1])))
            out["yaw"][i, k] = math.atan2(r[0, 1], r[1, 1])
            out["pitch_rate"][i, k] = -omega[1]
    return out
