"""The step map of the rigid walker in space: a stance phase from just after a strike to the next, the strike,
and the mirror that makes the landing leg the left leg again.

A step has two phases, as the planar model's: first until the swing leg passes the stance leg (the hinge angle
beta falls through zero: the swing foot comes from behind), then until the swing foot's lowest point reaches the
slope going down (:func:`~biped_sim.rigid.space_integration.space_clearance`). The first phase ignores the
mid-stance scuff, when a straight-legged walker's swing foot dips through the ground beside the stance foot
(MODEL.md 3: every passive-walking model ignores it). Each phase is DOP853 at the rigid step map's tolerances over
the compiled flow, its end located on the dense output (:mod:`biped_sim.rigid.space_integration`, scipy's
``solve_ivp`` compiled). A fall (the hip below ``FALL_HIP_FRACTION`` of the leg length, or the bank past
``FALL_BANK``) or a step longer than ``MAX_STEP_TIME`` natural periods ends the step without a strike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.integrate.stepper import Scratch
from biped_sim.integrate.tableaus import Tableau
from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.space_dynamics import strike, swing_foot_point
from biped_sim.rigid.space_integration import GUARD, PHASE_NAMES, space_phase, space_scratch
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


def space_step(
    model: SpaceModel,
    x_start: np.ndarray,
    params: np.ndarray | None = None,
    scratch: tuple[Tableau, Scratch] | None = None,
) -> SpaceStep:
    """One step of the map from the post-strike state ``x_start`` (its contact point taken as the origin);
    ``params`` and ``scratch`` (:func:`~biped_sim.rigid.space_integration.space_scratch`) made here if not given."""
    params = space_params(model) if params is None else params
    tab, sc = space_scratch() if scratch is None else scratch
    limit = MAX_STEP_TIME * math.sqrt(model.leg_length / model.gravity)
    fall_height = FALL_HIP_FRACTION * model.leg_length
    x = np.array(x_start, dtype=float)
    x[8:] = 0.0
    how, t = space_phase(params, tab, sc, 0, 0.0, limit, fall_height, x)
    if how == GUARD:
        how, t = space_phase(params, tab, sc, 1, t, limit, fall_height, x)
    if how != GUARD:
        return SpaceStep(PHASE_NAMES[how], x, None, t, math.nan)  # type: ignore[arg-type]
    length = float(np.linalg.norm(x[8:] + swing_foot_point(model, x)[:2]))
    return SpaceStep("strike", x, strike(model, x), t, length)
