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
scipy's ``solve_ivp`` with its events, compiled); a run's step (:mod:`biped_sim.rigid.space_walk`: samples, stops at
pushes) takes scipy's ``solve_ivp`` itself (:func:`phase`), the same steps and event times to rounding.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.integrate import OdeSolution, solve_ivp

from biped_sim.integrate.stepper import Scratch
from biped_sim.integrate.tableaus import Tableau
from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.space_dynamics import strike, swing_foot_point
from biped_sim.rigid.space_integration import FALL_BANK, GUARD, PHASE_NAMES, space_phase, space_scratch
from biped_sim.rigid.space_kernels import space_flow, space_params
from biped_sim.rigid.space_model import SpaceModel, pose, swing_clearance
from biped_sim.rigid.step import ATOL, MAX_STEP_TIME, RTOL, StepStatus


@dataclass
class SpaceStep:
    """A step from a post-strike state: how it ended, the states before and after the strike (mirrored), its
    duration and the distance between the two contact points."""

    status: StepStatus
    x_minus: np.ndarray
    x_plus: np.ndarray | None
    period: float
    length: float


def _event(function: Callable[[float, np.ndarray], float], direction: float) -> Callable[[float, np.ndarray], float]:
    function.terminal = True  # type: ignore[attr-defined]
    function.direction = direction  # type: ignore[attr-defined]
    return function


def step_time_limit(model: SpaceModel) -> float:
    """The longest step: ``MAX_STEP_TIME`` natural periods sqrt(l / g)."""
    return MAX_STEP_TIME * math.sqrt(model.leg_length / model.gravity)


class Phase(NamedTuple):
    """How a phase ended ('guard' | 'fell' | 'stalled' | 'until'), its end time and state, the dense output (or None)
    and the integrator's counters."""

    how: str
    t: float
    x: np.ndarray
    solution: OdeSolution | None
    rhs_evals: int
    accepted_steps: int


def phase(
    model: SpaceModel,
    params: np.ndarray,
    x0: np.ndarray,
    t0: float,
    guard: Callable[[float, np.ndarray], float],
    until: float | None = None,
    dense: bool = False,
) -> Phase:
    """Integrate from (t0, x0) until ``guard`` falls through zero ('guard'), a fall, the step's time limit
    ('stalled') or time ``until`` ('until'); the dense output if ``dense`` (DOP853's costs 3 more flow calls a
    step)."""
    limit = step_time_limit(model)
    end = limit if until is None else min(until, limit)

    def fell(t: float, x: np.ndarray) -> float:
        hip = pose(model, x).origin[2] - FALL_HIP_FRACTION * model.leg_length
        return min(hip, FALL_BANK - abs(x[1]))

    events = [_event(guard, -1.0), _event(fell, -1.0)]
    sol = solve_ivp(
        lambda t, x: space_flow(params, x),
        (t0, end),
        x0,
        method="DOP853",
        rtol=RTOL,
        atol=ATOL,
        events=events,
        dense_output=dense,
    )
    counters = (int(sol.nfev), len(sol.t) - 1)
    if sol.status == 1 and len(sol.t_events[0]):
        return Phase("guard", float(sol.t_events[0][0]), sol.y_events[0][0], sol.sol, *counters)
    how = "fell" if sol.status == 1 else ("stalled" if end == limit else "until")
    return Phase(how, float(sol.t[-1]), sol.y[:, -1], sol.sol, *counters)


def passed(t: float, x: np.ndarray) -> float:
    """The first phase's guard: the hinge angle (the swing foot passes the stance foot as it falls through 0)."""
    return float(x[3])


def clearance(model: SpaceModel) -> Callable[[float, np.ndarray], float]:
    """The second phase's guard: the swing foot's clearance."""
    return lambda t, x: swing_clearance(model, x)


def space_step(
    model: SpaceModel,
    x_start: np.ndarray,
    params: np.ndarray | None = None,
    scratch: tuple[Tableau, Scratch] | None = None,
) -> SpaceStep:
    """One step of the map from the post-strike state ``x_start`` (its contact point taken as the origin), compiled;
    ``params`` and ``scratch`` (:func:`~biped_sim.rigid.space_integration.space_scratch`) made here if not given."""
    params = space_params(model) if params is None else params
    tab, sc = space_scratch() if scratch is None else scratch
    limit, fall_height = step_time_limit(model), FALL_HIP_FRACTION * model.leg_length
    x = np.array(x_start, dtype=float)
    x[8:] = 0.0
    how, t = space_phase(params, tab, sc, 0, 0.0, limit, fall_height, x)
    if how == GUARD:
        how, t = space_phase(params, tab, sc, 1, t, limit, fall_height, x)
    if how != GUARD:
        return SpaceStep(PHASE_NAMES[how], x, None, t, math.nan)  # type: ignore[arg-type]
    return struck(model, x, t)


def struck(model: SpaceModel, x_minus: np.ndarray, period: float) -> SpaceStep:
    """The step that ends in a strike from ``x_minus`` at time ``period``: the strike and the step's length."""
    length = float(np.linalg.norm(x_minus[8:] + swing_foot_point(model, x_minus)[:2]))
    return SpaceStep("strike", x_minus, strike(model, x_minus), period, length)
