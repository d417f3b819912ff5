"""One segment of the stiff methods' event-restart integration: scipy's ``solve_ivp`` with terminal events, or the
same loop over the solver's steps without its per-event and per-step Python costs.

:func:`ivp_segment` calls ``solve_ivp`` (the benchmark's baseline keeps it). :func:`stepped_segment` runs the loop
``solve_ivp`` runs for terminal events on the solver's public stepping interface (``step``, ``dense_output``) and
returns the same times, states, status, evaluation count and dense output, bit for bit (tests/test_segment.py),
with three costs fewer: the event functions are evaluated once per step for all of them (``solve_ivp`` calls each
in turn), their sign changes are found in one pass, and a step's dense output is made only where it is read (a step
that holds a sample time or an event; ``solve_ivp`` makes one at every step and keeps them all).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np
from scipy.integrate import OdeSolver, solve_ivp
from scipy.optimize import brentq

EPS = float(np.finfo(float).eps)
ROOT_TOLERANCE = 4 * EPS  # solve_ivp's xtol and rtol of its event root search (scipy.integrate._ivp.ivp)

Event = Callable[[float, np.ndarray], float]


class Segment(NamedTuple):
    """What the driver reads of a segment, as solve_ivp's result names it."""

    t: np.ndarray  # the steps' times, the segment's start first and its first event's time last
    y: np.ndarray  # (ny, len(t)) the states there
    status: int  # 0: reached its end, 1: a terminal event, -1: the solver failed
    nfev: int  # right-hand sides the solver evaluated
    sol: Callable[[float], np.ndarray]  # the dense output of the step that holds a time


class SegmentEvents(NamedTuple):
    """The segment's terminal events: each one's function (scipy's root search calls it), all of them at once
    (``values(t, y)``, the same numbers), and which steps' dense output the driver will read (``wanted(t_old, t)``)."""

    each: Sequence[Event]
    values: Callable[[float, np.ndarray], np.ndarray]
    wanted: Callable[[float, float], bool]


def ivp_segment(
    fun: Any, t0: float, t_end: float, y0: np.ndarray, method: Any, options: dict, events: SegmentEvents
) -> Any:
    """``solve_ivp`` from ``t0`` to ``t_end`` with the events terminal and its dense output."""
    return solve_ivp(fun, (t0, t_end), y0, method=method, events=list(events.each), dense_output=True, **options)


def stepped_segment(
    fun: Any, t0: float, t_end: float, y0: np.ndarray, method: type[OdeSolver], options: dict, events: SegmentEvents
) -> Segment:
    """:func:`ivp_segment`'s result, bit for bit, by solve_ivp's loop over ``method``'s steps (terminal events)."""
    solver = method(fun, t0, y0, t_end, vectorized=False, **options)
    ts, ys, dense = [t0], [y0], _DenseSteps(events.wanted)
    g = events.values(t0, y0)
    status = None
    while status is None:
        solver.step()
        if solver.status == "failed":
            status = -1
            break
        status = 0 if solver.status == "finished" else None
        t_old, t, y = solver.t_old, solver.t, solver.y
        g_new = events.values(t, y)
        active = np.nonzero(((g <= 0) & (g_new >= 0)) | ((g >= 0) & (g_new <= 0)))[0]
        step_output = None
        if active.size:  # scipy finds every active event's root, then stops at the first
            step_output = solver.dense_output()
            t = min(_root(events.each[j], step_output, t_old, t) for j in active)
            y, status = step_output(t), 1
        g = g_new
        if len(ts) > 1 and ts[-1] == t:  # solve_ivp keeps neither a step of no length nor its dense output
            dense.cover(len(ts) - 2, step_output)
            continue
        dense.keep(len(ts) - 1, solver, t_old, t, step_output)
        ts.append(t)
        ys.append(y)
    times = np.array(ts)
    return Segment(times, np.vstack(ys).T, status, solver.nfev, dense.solution(times))


def _root(event: Event, step_output: Callable[[float], np.ndarray], t_old: float, t: float) -> float:
    """The event's time in the step, as solve_ivp's ``solve_event_equation`` finds it."""
    return brentq(lambda s: event(s, step_output(s)), t_old, t, xtol=ROOT_TOLERANCE, rtol=ROOT_TOLERANCE)


class _DenseSteps:
    """The steps' dense outputs the driver may read, by step index (step k runs from t[k] to t[k + 1])."""

    def __init__(self, wanted: Callable[[float, float], bool]) -> None:
        self.wanted, self.outputs = wanted, {}

    def keep(self, k: int, solver: OdeSolver, t_old: float, t: float, made: Any) -> None:
        """Keep step ``k``'s dense output when it was made or is wanted."""
        if made is not None or self.wanted(t_old, t):
            self.outputs[k] = made if made is not None else solver.dense_output()

    def cover(self, k: int, made: Any) -> None:
        """Step ``k``'s dense output where it was not kept and a step of no length after it, dropped, ended the
        segment on an event (solve_ivp then reads step k's past its end): the dropped step's, the one made. Not
        solve_ivp's bit for bit, a case only an event held on its side reaches (one at zero stops the step before)."""
        if made is not None:
            self.outputs.setdefault(k, made)

    def solution(self, times: np.ndarray) -> Callable[[float], np.ndarray]:
        """y(t) from the dense output of the step solve_ivp's ``OdeSolution`` picks (the first step whose end is at
        or past t, the last past the end, the first before the start)."""
        last = len(times) - 2

        def at(t: float) -> np.ndarray:
            k = min(max(int(np.searchsorted(times, t, side="left")) - 1, 0), last)
            return self.outputs[k](t)

        return at


def sample_steps(n_start: int, interval: float) -> Callable[[float, float], bool]:
    """Whether a step from t_old to t holds a sample time ``n * interval`` (n >= ``n_start``), the times the driver
    samples the dense output at; every step when there is no interval."""
    if not interval > 0.0 or not math.isfinite(interval):
        return lambda t_old, t: True

    def holds(t_old: float, t: float) -> bool:
        if t - t_old >= interval:
            return True
        n = max(n_start, math.floor(t_old / interval))
        return any(t_old < k * interval <= t for k in (n, n + 1, n + 2))

    return holds
