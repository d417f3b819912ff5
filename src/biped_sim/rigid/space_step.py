"""The step map of the rigid walker in space: a stance phase from just after a strike to the next, the strike,
and the mirror that makes the landing leg the left leg again.

A step has two phases, as the planar model's: first until the swing leg passes the stance leg (the hinge angle
beta falls through zero: the swing foot comes from behind), then until the swing foot's lowest point reaches the
slope going down (:func:`~biped_sim.rigid.space_integration.space_clearance`). The first phase ignores the
mid-stance scuff, when a straight-legged walker's swing foot dips through the ground beside the stance foot
(MODEL.md 3: every passive-walking model ignores it). A fall (the hip below ``FALL_HIP_FRACTION`` of the leg
length, or the bank past ``FALL_BANK``) or a step longer than ``MAX_STEP_TIME`` natural periods ends the step
without a strike. The step map (:func:`space_step`) integrates each phase compiled: DOP853 at the rigid step map's
tolerances over the compiled flow, its end located on the dense output (:mod:`biped_sim.rigid.space_integration`,
scipy's ``solve_ivp`` with its events, compiled); a run's step (:mod:`biped_sim.rigid.space_walk`) takes the same
integration with samples and stops at its pushes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.space_dynamics import strike, swing_foot_point
from biped_sim.rigid.space_integration import GUARD, PHASE_NAMES, SpaceScratch, space_phase, space_scratch
from biped_sim.rigid.space_kernels import space_params
from biped_sim.rigid.space_model import SpaceModel
from biped_sim.rigid.step import MAX_STEP_TIME, StepStatus


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


def space_step(
    model: SpaceModel,
    x_start: np.ndarray,
    params: np.ndarray | None = None,
    scratch: SpaceScratch | None = None,
) -> SpaceStep:
    """One step of the map from the post-strike state ``x_start`` (its contact point taken as the origin), compiled;
    ``params`` and ``scratch`` (:func:`~biped_sim.rigid.space_integration.space_scratch`) made here if not given."""
    params = space_params(model) if params is None else params
    scratch = space_scratch() if scratch is None else scratch
    limit, fall_height = step_time_limit(model), FALL_HIP_FRACTION * model.leg_length
    x = np.array(x_start, dtype=float)
    x[8:] = 0.0
    how, t = space_phase(params, scratch, 0, 0.0, limit, limit, fall_height, 0.0, x)
    if how == GUARD:
        how, t = space_phase(params, scratch, 1, t, limit, limit, fall_height, 0.0, x)
    if how != GUARD:
        return SpaceStep(PHASE_NAMES[how], x, None, t, math.nan)  # type: ignore[arg-type]
    return struck(model, x, t)


def struck(model: SpaceModel, x_minus: np.ndarray, period: float) -> SpaceStep:
    """The step that ends in a strike from ``x_minus`` at time ``period``: the strike and the step's length."""
    length = float(np.linalg.norm(x_minus[8:] + swing_foot_point(model, x_minus)[:2]))
    return SpaceStep("strike", x_minus, strike(model, x_minus), period, length)
