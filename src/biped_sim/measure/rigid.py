"""Measures of a rigid run: its heel-strike trace, step table, energy terms and hip path.

Step k's models measure positions from their own origin; :func:`rigid_energy_and_hip` puts every sample in
one slope frame so that the energy balance E(t) - E(0) + W_impact(t) + W_element(t) - W_push(t) is checked across
steps (W_element: the dampers' work, integrated with the flow by the step map, exact to its tolerance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from biped_sim.config import LEG_KEYS
from biped_sim.measure.loops import rigid_loop
from biped_sim.measure.steps import StepTable
from biped_sim.rigid.start import RigidStart, touchdown_legs
from biped_sim.rigid.tree import RigidWalker


@dataclass
class RigidEnergy:
    """Energy terms at the samples; residual = E(t) - E(0) + W_impact(t) + W_element(t) - W_push(t) (J, J/kg or
    nondimensional; E's potential holds the joint elements' springs)."""

    kinetic: np.ndarray
    potential: np.ndarray
    dissipated_impact: np.ndarray
    dissipated_elements: np.ndarray  # W_element(t): the joint elements' (dampers') work, integrated with the flow
    push_work: np.ndarray  # W_push(t): work of the pushes so far (their kinetic energy jumps)
    residual: np.ndarray


@dataclass
class RigidTrace:
    """What the stepping loop collects: samples (with the step each belongs to) and strikes."""

    times: list[np.ndarray] = field(default_factory=list)
    states: list[np.ndarray] = field(default_factory=list)
    sample_step: list[np.ndarray] = field(default_factory=list)
    element_work: list[np.ndarray] = field(default_factory=list)  # W_element at the samples, since the run's start
    strike_time: list[float] = field(default_factory=list)
    strike_pre: list[np.ndarray] = field(default_factory=list)
    strike_post: list[np.ndarray] = field(default_factory=list)
    step_lengths: list[float] = field(default_factory=list)  # of the completed steps, the first from t = 0
    strike_levels: list[float] = field(default_factory=list)  # on a ground profile: the new stance foot's level
    pushes: list[tuple[float, float, float]] = field(default_factory=list)  # (time, work, ground normal impulse)
    stop_losses: list[tuple[float, float]] = field(default_factory=list)  # joint stops struck: (time, energy lost)

    def add_samples(self, t: np.ndarray, x: np.ndarray, step_index: int, work: np.ndarray | float = 0.0) -> None:
        """Samples (t, x) of step ``step_index``, with the joint elements' work since the run's start (0 without)."""
        if not len(t):
            return
        self.times.append(t)
        self.states.append(x.reshape(len(t), -1))
        self.sample_step.append(np.full(len(t), step_index))
        self.element_work.append(np.broadcast_to(np.asarray(work, dtype=float), t.shape))


def strike_feet(walker: RigidWalker, n: int) -> np.ndarray:
    """Foot (spoke) of strikes 1..n, the initial stance foot being 0."""
    return np.arange(1, n + 1) % walker.n_feet


def rigid_step_table(walker: RigidWalker, trace: RigidTrace) -> StepTable:
    """One row per strike: the step it begins (period and length nan for the last), touchdown angles and rates."""
    n = len(trace.strike_time)
    strike_time = np.array(trace.strike_time)
    period = np.full(n, np.nan)
    length = np.full(n, np.nan)
    slip = np.full(n, np.nan)
    if n > 1:
        period[:-1] = np.diff(strike_time)
        length[:-1] = trace.step_lengths[1:n]
        slip[:-1] = 0.0
    touchdown = [touchdown_legs(walker, x) for x in trace.strike_pre]
    legs = {key: np.array([state[key] for state in touchdown], dtype=float) for key in LEG_KEYS}
    return StepTable(strike_time, strike_feet(walker, n), period, length, slip, **legs)


def rigid_energy_and_hip(
    walker: RigidWalker, start: RigidStart, trace: RigidTrace, times: np.ndarray, states: np.ndarray
) -> tuple[RigidEnergy, np.ndarray]:
    """Energy terms and hip position at the samples, in one slope frame for the whole run.

    Step k's models measure positions from its own origin O_k, where its contact point would be at zero angle of
    the stance foot's body (theta): the contact point is at x = O_k - R theta. O_0 = R theta_0 (contact at x = 0 at
    the start). A step's length is its contact point's advance from the step's start to the next one's, so
    O_{k+1} - R theta_{k+1}+ = O_k - R theta_k+ + length_k. Potentials shift by -(weight) sin(gamma) O_k, and on
    a ground profile by (weight) cos(gamma) h_k with h_k step k's stance level (the hip rises by h_k). The hip is
    the model's own (:meth:`RigidWalker.hip`, through the stance leg's joints to its foot's centre, off the leg's
    axis or not) moved by O_k.
    """
    R = walker.foot_radius
    step_start = np.vstack([start.state, *trace.strike_post])[:, walker.params.rolling[0]]
    origin = np.zeros(len(step_start))
    origin[0] = R * step_start[0]
    for k, length in enumerate(trace.step_lengths):
        origin[k + 1] = origin[k] + length + R * (step_start[k + 1] - step_start[k])
    weight = walker.reference_mass * walker.gravity  # hip mass 1 and g = 1 for the simplest walker
    losses = [
        walker.energy(pre)[0] - walker.energy(post)[0]
        for pre, post in zip(trace.strike_pre, trace.strike_post, strict=True)
    ]
    dissipated_by_step = np.concatenate([[0.0], np.cumsum(losses)])
    step_of_sample = np.concatenate(trace.sample_step)
    sample_origin = origin[step_of_sample]
    terms, hip = np.empty((len(times), 2)), np.empty((len(times), 2))
    rigid_loop(walker.params, np.ascontiguousarray(states, dtype=np.float64), walker.n_points, terms, hip)
    elements = np.concatenate(trace.element_work)
    kinetic = terms[:, 0]
    potential = terms[:, 1] - weight * math.sin(walker.slope) * sample_origin
    sample_level = np.concatenate([[0.0], trace.strike_levels])[step_of_sample] if trace.strike_levels else None
    if sample_level is not None:  # a ground profile: the stance level of each sample's step
        potential = potential + weight * math.cos(walker.slope) * sample_level
    kinetic_0, potential_0 = walker.energy(start.state)
    energy_0 = kinetic_0 + potential_0 - weight * math.sin(walker.slope) * origin[0]
    dissipated = dissipated_by_step[step_of_sample]
    for at, loss in trace.stop_losses:  # a sample at a stop strike's time holds the state after it
        dissipated[times >= at] += loss
    push_work = np.zeros(len(times))
    for at, work, _ in trace.pushes:
        push_work[times >= at] += work  # a sample at a push's time holds the state after it
    residual = kinetic + potential - energy_0 + dissipated + elements - push_work
    hip[:, 0] += sample_origin
    if sample_level is not None:
        hip[:, 1] += sample_level
    return RigidEnergy(kinetic, potential, dissipated, elements, push_work, residual), hip
