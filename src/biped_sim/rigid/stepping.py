"""One rigid step, and a rigid run of many: event-located integration of the flow between heel strikes.

The flow is integrated by scipy's DOP853 (8th order, 7th-order dense output) at rtol = atol = 1e-12.
Each guard phase ends at a downward zero crossing of its guard function, found by root finding on the
dense output (scipy's brentq, to 4 machine epsilon) and then polished by Newton steps on the exact flow
direction, dt = -g / (grad g . f), until |g| <= 1e-14: the heel strike is located to about 1e-12 in
time and state (the integration error), not to the step size. Falls (a leg past
``simulation.fall_leg_angle``, the hip on the ground) and stalls (no strike within ``MAX_STEP_TIME``
natural periods) end the step with a status instead of a strike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from biped_sim.rigid.models import RigidWalker

RTOL = 1e-12
ATOL = 1e-12
MAX_STEP_TIME = 20.0  # in units of sqrt(l / g)
GUARD_TOLERANCE = 1e-14

StepStatus = Literal["strike", "fell", "stalled"]


@dataclass
class RigidStep:
    """A step from a post-impact state to the next strike."""

    status: StepStatus
    x_start: np.ndarray
    x_minus: np.ndarray  # just before the strike (or the state when the step ended otherwise)
    x_plus: np.ndarray | None  # just after the strike
    period: float
    length: float
    rhs_evals: int
    samples_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    samples_x: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    accepted_steps: int = 0  # DOP853 steps taken


def _guard_event(guard, direction: float):  # type: ignore[no-untyped-def]
    def event(_t: float, x: np.ndarray) -> float:
        return guard(x)

    event.terminal = True  # type: ignore[attr-defined]
    event.direction = direction  # type: ignore[attr-defined]
    return event


def _polish(walker: RigidWalker, guard, t: float, x: np.ndarray) -> tuple[float, np.ndarray]:  # type: ignore[no-untyped-def]
    """Newton on the guard along the flow: a few dt = -g / (grad g . f) steps of a Taylor expansion."""
    eps = 1e-7
    for _ in range(4):
        g = guard(x)
        if abs(g) <= GUARD_TOLERANCE:
            break
        f = walker.rhs(x)
        slope = (guard(x + eps * f) - guard(x - eps * f)) / (2 * eps)
        if slope == 0.0:
            break
        dt = -g / slope
        # second-order Taylor step of the flow over the (tiny) correction
        f_mid = walker.rhs(x + 0.5 * dt * f)
        x = x + dt * f_mid
        t += dt
    return t, x


def rigid_step(walker: RigidWalker, x_start: np.ndarray, sample_rate: float | None = None) -> RigidStep:
    """Integrate one step from a post-impact state; sample it at ``sample_rate`` (per unit time) if given.

    The samples fall on the grid k / sample_rate of the step's own clock (t = 0 at its start) and are kept
    whatever the step's outcome (strike, fall or stall).
    """
    from scipy.integrate import solve_ivp  # imported here: scipy.integrate costs 0.3 s of every CLI start-up

    scale = math.sqrt(walker.leg_length / walker.gravity)
    t_limit = MAX_STEP_TIME * scale
    fall_events = [_guard_event(lambda x, i=i: walker.fall_leg_angle - abs(x[i]), 0.0) for i in range(walker.n_q)] + [
        _guard_event(lambda x: walker.hip_height(x) - 0.05 * walker.leg_length, 0.0)
    ]
    t, x = 0.0, np.asarray(x_start, dtype=float)
    evals = 0
    accepted = 0
    samples_t: list[np.ndarray] = []
    samples_x: list[np.ndarray] = []

    def finish(step: RigidStep) -> RigidStep:
        # every outcome keeps its samples and counters (a run records the fall's trajectory too)
        step.accepted_steps = accepted
        if samples_t:
            step.samples_t = np.concatenate(samples_t)
            step.samples_x = np.vstack(samples_x)
        return step

    for _, guard in walker.guard_phases():
        strike = _guard_event(guard, -1.0)
        sol = solve_ivp(
            lambda _t, y: walker.rhs(y),
            (t, t_limit),
            x,
            method="DOP853",
            rtol=RTOL,
            atol=ATOL,
            events=[strike, *fall_events],
            dense_output=sample_rate is not None,
        )
        evals += sol.nfev
        accepted += len(sol.t) - 1
        if sample_rate is not None and sol.sol is not None:
            t_end = sol.t[-1]
            grid = np.arange(math.ceil(t * sample_rate), math.floor(t_end * sample_rate) + 1) / sample_rate
            grid = grid[(grid >= t) & (grid < t_end)]
            if len(grid):
                samples_t.append(grid)
                samples_x.append(sol.sol(grid).T)
        if sol.status != 1:  # no event: ran to the time limit
            return finish(RigidStep("stalled", x_start, sol.y[:, -1], None, sol.t[-1], math.nan, evals))
        if len(sol.t_events[0]) == 0:
            return finish(RigidStep("fell", x_start, sol.y[:, -1], None, sol.t[-1], math.nan, evals))
        t, x = _polish(walker, guard, float(sol.t_events[0][0]), sol.y_events[0][0])
    x_plus = walker.impact(x)
    return finish(RigidStep("strike", x_start, x, x_plus, t, walker.step_length(x_start, x), evals))
