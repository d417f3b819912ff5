"""A rigid walker in space walked step after step: each step's samples on its own clock, pushes at their times,
and where each step's model frame sits in the run's frame.

The step map (:mod:`biped_sim.rigid.space_step`) mirrors the walker after every strike so that the left leg always
stands; a run undoes that: step k's frame has its contact point at ``Frame.contact`` of the run's slope frame (the
rigid model's: x downhill, y left, z the slope's normal) and is that frame mirrored (y -> -y) when the right leg
stands (``Frame.sign`` -1). A state of the model in a mirrored frame is the run's with heading, bank and the
angular velocity's x and z negated (a mirror turns an angular velocity into minus its image), the lateral position
mirrored (:meth:`Frame.world`). Gravity has no lateral part, so the energy of a state is the model's
(:func:`~biped_sim.rigid.space_dynamics.energy`, potential zero at the frame's origin) less the whole weight's
downhill part times the frame's downhill offset.

A push (``simulation.pushes``: an impulse on the hinge's midpoint) stops the step's flow at its time and changes the
walker's velocities there (:func:`~biped_sim.rigid.space_dynamics.hip_push`); the flow then goes on in the same
phase. A sample at a push's time holds the state after it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.space_dynamics import energy, energy_terms, hip_push
from biped_sim.rigid.space_integration import (
    ACCEPTED,
    FLOWS,
    GUARD,
    KNEE_PHASE,
    PHASE_NAMES,
    REACHED,
    SAMPLED,
    SpaceScratch,
    space_phase,
)
from biped_sim.rigid.space_kernels import KNEE_FREE
from biped_sim.rigid.space_model import MIRROR, SpaceModel
from biped_sim.rigid.space_step import SpaceStep, after_phase, begin_step, step_time_limit, struck

MIRRORED = np.array([-1.0, -1.0, 1.0, 1.0, -1.0, 1.0, -1.0, 1.0, 1.0, -1.0, 1.0, 1.0, 1.0, 1.0, 1.0])  # a state's
# signs under the mirror (then a kneed walker's knee angle and rate, a torso's angle, rate and work: about y, kept)


@dataclass(frozen=True)
class Frame:
    """Where a step's model frame sits in the run's: its origin (the stance contact point at the step's start) and
    +1 (the left leg stands) or -1 (the right leg stands: the model is mirrored)."""

    contact: np.ndarray  # (3,) in the run's slope frame
    sign: float

    @property
    def turn(self) -> np.ndarray:
        """The frame's axes in the run's: the identity or the mirror."""
        return np.eye(3) if self.sign > 0 else MIRROR

    def world(self, x: np.ndarray) -> np.ndarray:
        """A model state (or states, rows) in the run's frame: attitude, rates, the contact point (module docstring)."""
        out = np.array(x, dtype=float)
        out *= MIRRORED[: out.shape[-1]] if self.sign < 0 else 1.0
        out[..., 8:10] += self.contact[:2]
        return out

    def point(self, local: np.ndarray) -> np.ndarray:
        """A point of the model's frame (from its origin) in the run's."""
        return self.contact + self.turn @ local

    def after(self, x_plus: np.ndarray) -> Frame:
        """The next step's frame, from the post-strike state (its contact point in this frame, mirrored)."""
        turn = MIRROR @ self.turn
        return Frame(self.contact + turn @ np.array([x_plus[8], x_plus[9], 0.0]), -self.sign)

    def impulse(self, p: np.ndarray) -> np.ndarray:
        """A push given as [px, py, pz] in the spatial slope frame (x downhill, y the normal, z right), in the
        model's frame."""
        return self.turn @ np.array([p[0], -p[2], p[1]], dtype=float)


def frame_energy(model: SpaceModel, frame: Frame, x: np.ndarray) -> tuple[float, float]:
    """(kinetic, potential) energy of model state ``x`` in the run's frame (module docstring)."""
    weight = sum(part.mass for part in model.parts) * model.gravity_vector[0]
    kinetic, potential = energy_terms(model, x)
    return kinetic, potential - weight * frame.contact[0]


@dataclass
class WalkStep:
    """A step of a run: the step map's result, the samples on the step's clock (post-strike state first, the strike
    or fall state not among them), the pushes applied (time on the step's clock, work, ground normal impulse), the
    knee strikes (time on the step's clock, kinetic energy lost) and the integrator's counters."""

    step: SpaceStep
    samples_t: np.ndarray
    samples_x: np.ndarray
    pushes: list[tuple[float, float, float]] = field(default_factory=list)
    knee_strikes: list[tuple[float, float]] = field(default_factory=list)
    rhs_evals: int = 0
    accepted_steps: int = 0


def walk_step(
    model: SpaceModel,
    params: np.ndarray,
    scratch: SpaceScratch,
    x_start: np.ndarray,
    sample_rate: float,
    pushes: Sequence[tuple[float, np.ndarray]] = (),
) -> WalkStep:
    """One step from post-strike state ``x_start`` (its contact point the origin) with the samples and the pushes
    pending (time on the step's clock, impulse in the model's frame, in time order; those after the step's end
    stay pending), integrated as the step map's (``scratch``: :func:`~biped_sim.rigid.space_integration.space_scratch`
    with room for a step's samples)."""
    x = np.array(x_start, dtype=float)
    x[8:10] = 0.0
    limit, fall_height = step_time_limit(model), FALL_HIP_FRACTION * model.leg_length
    record = scratch.record
    record.counts[:] = 0
    t, how, applied, skip, knee_strikes = 0.0, GUARD, [], False, []
    for phase in begin_step(model, params, x):
        how = GUARD if skip else REACHED
        while how == REACHED:
            stop = min(pushes[len(applied)][0], limit) if len(applied) < len(pushes) else limit
            if stop > t:
                how, t = space_phase(params, scratch, phase, t, stop, limit, fall_height, sample_rate, x)
            if how == REACHED:
                before = energy(model, x)
                x, normal = hip_push(model, x, pushes[len(applied)][1], params[KNEE_FREE] == 1.0)
                applied.append((t, energy(model, x) - before, normal))
        if how != GUARD:
            break
        before = energy(model, x) if phase == KNEE_PHASE else 0.0
        x, skip = after_phase(model, params, phase, x)
        if phase == KNEE_PHASE:
            knee_strikes.append((t, before - energy(model, x)))
    step = struck(model, x, t) if how == GUARD else SpaceStep(PHASE_NAMES[how], x, None, t, math.nan)  # type: ignore[arg-type]
    n = record.counts[SAMPLED]
    samples = record.samples_t[:n].copy(), record.samples_x[:n].copy()
    return WalkStep(step, *samples, applied, knee_strikes, int(record.counts[FLOWS]), int(record.counts[ACCEPTED]))
