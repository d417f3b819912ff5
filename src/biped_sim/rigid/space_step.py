"""The step map of the rigid walker in space: a stance phase from just after a strike to the next, the strike,
and the mirror that makes the landing leg the left leg again.

A step has two phases, as the planar model's: first until the swing leg passes the stance leg (the hinge angle
beta falls through zero: the swing foot comes from behind), then until the swing foot's lowest point reaches the
slope going down (:func:`~biped_sim.rigid.space_integration.space_clearance`). The first phase ignores the
mid-stance scuff, when a straight-legged walker's swing foot dips through the ground beside the stance foot
(MODEL.md 3: every passive-walking model ignores it). A kneed walker's step starts with a third, as the planar
kneed walker's: its swing knee unlocks just after the strike (if its free flexion then accelerates; else it stays
locked through the step), swings free until it strikes straight (the knee strike, plastic:
:func:`~biped_sim.rigid.space_dynamics.knee_strike`) and stays locked; the hinge's phase is skipped when the swing
foot passed the stance foot before the knee strike. A fall (the hip below ``FALL_HIP_FRACTION`` of the leg length,
or the bank past ``FALL_BANK``) or a step longer than ``MAX_STEP_TIME`` natural periods ends the step without a
strike; a swing foot that meets the slope while not ahead of the stance foot (the hinge angle above -``ALIGNED``:
the walker rocked back over its stance foot, or the legs in line, where the strike's equations are singular) ends
it ``tripped``. The step map (:func:`space_step`) integrates each phase compiled: DOP853 at the rigid step map's
tolerances over the compiled flow, its end located on the dense output (:mod:`biped_sim.rigid.space_integration`,
scipy's ``solve_ivp`` with its events, compiled); a run's step (:mod:`biped_sim.rigid.space_walk`) takes the same
integration with samples and stops at its pushes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.space_dynamics import knee_strike, strike, swing_foot_point
from biped_sim.rigid.space_integration import (
    GUARD,
    KNEE_PHASE,
    PHASE_NAMES,
    SpaceScratch,
    space_phase,
    space_scratch,
)
from biped_sim.rigid.space_kernels import KNEE_FREE, space_flow, space_params
from biped_sim.rigid.space_model import KNEE_RATE, SpaceModel
from biped_sim.rigid.step import MAX_STEP_TIME, StepStatus

ALIGNED = 1e-6  # [rad] a strike needs the swing foot ahead: the hinge angle below -ALIGNED
# what a step raises when the walker's mass matrix is singular (a motion no mass resists: e.g. legs with no inertia
# about their own axes, in line), and why a run so stopped
SINGULAR = (ZeroDivisionError, np.linalg.LinAlgError)
SINGULAR_REASON = (
    "the equations of motion became singular: a motion no mass resists (a leg without inertia about its axis?)"
)


@dataclass
class SpaceStep:
    """A step from a post-strike state: how it ended, the states before and after the strike (mirrored), its
    duration and the distance between the two contact points."""

    status: StepStatus
    x_minus: np.ndarray
    x_plus: np.ndarray | None
    period: float
    length: float


def step_time_limit(model: SpaceModel) -> float:
    """The longest step: ``MAX_STEP_TIME`` natural periods sqrt(l / g)."""
    return MAX_STEP_TIME * math.sqrt(model.leg_length / model.gravity)


def begin_step(model: SpaceModel, params: np.ndarray, x_start: np.ndarray) -> tuple[int, ...]:
    """The phases of a step from post-strike state ``x_start`` (module docstring): the knee's first if the swing
    knee unlocks, which ``params`` then says (:data:`~biped_sim.rigid.space_kernels.KNEE_FREE`)."""
    params[KNEE_FREE] = 0.0
    if model.knee is not None:
        params[KNEE_FREE] = 1.0
        if model.knee.flexion * space_flow(params, x_start)[KNEE_RATE] > 0.0:
            return KNEE_PHASE, 0, 1
        params[KNEE_FREE] = 0.0
    return 0, 1


def after_phase(model: SpaceModel, params: np.ndarray, phase: int, x: np.ndarray) -> tuple[np.ndarray, bool]:
    """The state after ``phase``'s guard (the knee strike locks the swing knee) and whether the next phase has
    nothing to wait for (the hinge's, when the swing foot passed the stance foot before the knee strike)."""
    if phase != KNEE_PHASE:
        return x, False
    params[KNEE_FREE] = 0.0
    x = knee_strike(model, x)
    return x, x[3] <= 0.0


def space_step(
    model: SpaceModel,
    x_start: np.ndarray,
    params: np.ndarray | None = None,
    scratch: SpaceScratch | None = None,
) -> SpaceStep:
    """One step of the map from the post-strike state ``x_start`` (its contact point taken as the origin), compiled;
    ``params`` and ``scratch`` (:func:`~biped_sim.rigid.space_integration.space_scratch`) made here if not given."""
    params = space_params(model) if params is None else params
    scratch = space_scratch(0, model.n_state) if scratch is None else scratch
    limit, fall_height = step_time_limit(model), FALL_HIP_FRACTION * model.leg_length
    x = np.array(x_start, dtype=float)
    x[8:10] = 0.0
    how, t, skip = GUARD, 0.0, False
    for phase in begin_step(model, params, x):
        if not skip:
            how, t = space_phase(params, scratch, phase, t, limit, limit, fall_height, 0.0, x)
        if how != GUARD:
            return SpaceStep(PHASE_NAMES[how], x, None, t, math.nan)  # type: ignore[arg-type]
        x, skip = after_phase(model, params, phase, x)
    return struck(model, x, t)


def struck(model: SpaceModel, x_minus: np.ndarray, period: float) -> SpaceStep:
    """The step that ends in a strike from ``x_minus`` at time ``period``: the strike and the step's length."""
    length = float(np.linalg.norm(x_minus[8:10] + swing_foot_point(model, x_minus)[:2]))
    if x_minus[3] > -ALIGNED:  # the swing foot met the ground not ahead of the stance foot: the walker rocked back
        return SpaceStep("tripped", x_minus, None, period, length)
    return SpaceStep("strike", x_minus, strike(model, x_minus), period, length)
