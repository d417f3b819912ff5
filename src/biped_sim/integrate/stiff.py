"""Implicit stiff methods (``radau``, ``bdf``) from scipy over the compiled right-hand side.

Pick these when the contact is very stiff (hard materials, small friction regularisation
velocities): explicit methods are then limited by stability, not accuracy, and take steps far
smaller than the accuracy needs. The Jacobian is a compiled forward-difference Jacobian; the Newton matrices are
factored by LAPACK directly (:mod:`~biped_sim.integrate.newton_lu`, scipy's solvers otherwise). Contact
events are scipy terminal events on the same event functions as the explicit loop; at each event
the integration restarts after the discrete update, and the same compiled bookkeeping
(:func:`~biped_sim.integrate.recorder.apply_events`) logs touchdowns and heel strikes.
:func:`integrate_scipy` is that event-restart driver for any solve_ivp method; the benchmark's
baseline runs it with RK45 over plain-Python functions.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import OdeSolver

from biped_sim.config import IntegratorConfig
from biped_sim.contact.response import ContactBuffers
from biped_sim.integrate import blowup
from biped_sim.integrate.newton_lu import DirectBDF, DirectRadau
from biped_sim.integrate.recorder import (
    COMPLETED,
    DIVERGED,
    EVALUATION_BUDGET,
    EVENT_SEARCH_FAILED,
    FELL,
    NONFINITE,
    RUNNING,
    SOLVER_FAILED,
    TIMEOUT,
    Recorder,
    apply_events,
    record_sample,
    with_room,
)
from biped_sim.integrate.segment import SegmentEvents, ivp_segment, sample_steps, stepped_segment
from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import contact_buffers, make_workspace, system_fall, system_rhs
from biped_sim.multibody.events import event_count, system_event_functions

EVENT_NUDGE = 1e-12  # [s] step past a located event so that its function has its new sign
EVENT_NOISE = 1e-12  # [m, m/s] an event function closer to zero at a segment's start is on its boundary (a retry's)
MAX_STIFF_EVALS = 20_000_000  # right-hand sides a stiff run may evaluate (about 10 minutes of scipy)


class StoppedError(Exception):
    """Raised by a right-hand side to end a scipy integration with a status (and a divergence reason)."""

    def __init__(self, status: int, reason: int = 0) -> None:
        super().__init__(status, reason)
        self.status = status
        self.reason = reason


@kernel
def stiff_derivatives(
    t: float,
    y: np.ndarray,
    system: tuple,
    modes: np.ndarray,
    work: tuple,
    f: np.ndarray,
    jac: np.ndarray,
    with_jacobian: bool,
) -> None:
    """f(t, y) into ``f`` and, ``with_jacobian``, its forward-difference Jacobian df/dy into ``jac`` (steps
    sqrt(eps) max(|y_j|, 1e-3)): scipy's ``fun`` and ``jac`` in one function, so that a first run compiles the
    right-hand side once for both."""
    system_rhs(t, y, system, modes, work, f)
    if not with_jacobian:
        return
    ny = y.shape[0]
    y_pert = y.copy()
    f_pert = np.empty(ny)
    for j in range(ny):
        step = 1.4901161193847656e-08 * max(abs(y[j]), 1e-3)
        y_pert[j] = y[j] + step
        system_rhs(t, y_pert, system, modes, work, f_pert)
        for i in range(ny):
            jac[i, j] = (f_pert[i] - f[i]) / step
        y_pert[j] = y[j]


def integrate_stiff(
    system: tuple,
    rec: Recorder,
    y: np.ndarray,
    modes: np.ndarray,
    integrator: IntegratorConfig,
    t_end: float,
    interval: float,
    max_strikes: int,
    progress: Callable[[float], None] | None,
    deadline: float = math.inf,
    checks: blowup.Scales = blowup.NO_CHECKS,
) -> Recorder:
    """Integrate with scipy's Radau or BDF, restarting at every contact event; returns the (enlarged) recorder.

    The run stops as 'timeout' past ``deadline`` (``time.monotonic()``) and as diverged after
    ``MAX_STIFF_EVALS`` right-hand sides or when the blow-up checks (``checks``) fail. scipy calls the compiled
    right-hand side and event functions through their entries for this run's argument types
    (:meth:`~biped_sim.kernel.Kernel.entry_for`), without numba's typing of the system at every call.
    """
    ny = y.shape[0]
    work = make_workspace(system)
    counts = {"jac": 0, "fun": 0}
    unused_jacobian = np.empty((ny, ny))
    derivatives = stiff_derivatives.entry_for(0.0, y, system, modes, work, y, unused_jacobian, False)

    def evaluated(t: float, state: np.ndarray, jacobian: np.ndarray) -> np.ndarray:
        counts["fun"] += 1
        if counts["fun"] > MAX_STIFF_EVALS:
            raise StoppedError(DIVERGED, EVALUATION_BUDGET)
        if time.monotonic() > deadline:
            raise StoppedError(TIMEOUT)
        out = np.empty(ny)
        derivatives(t, np.ascontiguousarray(state), system, modes, work, out, jacobian, jacobian is not unused_jacobian)
        return out

    def fun(t: float, state: np.ndarray) -> np.ndarray:
        return evaluated(t, state, unused_jacobian)

    def jac(t: float, state: np.ndarray) -> np.ndarray:
        out = np.empty((ny, ny))
        evaluated(t, state, out)
        counts["jac"] += 1
        return out

    compiled_events = system_event_functions.entry_for(y, system, np.empty(event_count(system)))

    def event_values(state: np.ndarray, system: tuple, g: np.ndarray) -> None:
        """The event functions at ``state`` into ``g``: all of them, once per step (the stepped segment asks them
        together; its root search asks one at each state it tries)."""
        compiled_events(np.ascontiguousarray(state), system, g)

    method = DirectRadau if integrator.method == "radau" else DirectBDF
    rec = integrate_scipy(
        system, rec, y, modes, contact_buffers(system), method, integrator.rtol, integrator.atol, integrator.max_step,
        t_end, interval, max_strikes, progress, fun, jac=jac, checks=checks, work=work,
        event_values=event_values, segment=stepped_segment,
    )  # fmt: skip
    rec.state[0].rhs_evals += counts["jac"] * (ny + 1)
    return rec


def integrate_scipy(
    system: tuple,
    rec: Recorder,
    y: np.ndarray,
    modes: np.ndarray,
    contact: ContactBuffers,
    method: str | type[OdeSolver],
    rtol: float,
    atol: float,
    max_step: float,
    t_end: float,
    interval: float,
    max_strikes: int,
    progress: Callable[[float], None] | None,
    fun: Callable[[float, np.ndarray], np.ndarray],
    *,
    jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
    event_values: Callable[[np.ndarray, tuple, np.ndarray], None] = system_event_functions,
    apply_events: Callable[..., bool] = apply_events,
    checks: blowup.Scales = blowup.NO_CHECKS,
    work: tuple | None = None,
    segment: Callable[..., Any] = ivp_segment,
) -> Recorder:
    """Drive ``solve_ivp(method)`` over ``fun`` with the events as terminal events (``segment``: one segment of it,
    :func:`~biped_sim.integrate.segment.ivp_segment` or its stepped twin); returns the recorder.

    Each event stops the integration; the discrete update (``apply_events``) then runs on the
    state just past the event and the integration restarts. ``fun`` reads ``modes``, which the
    update changes in place. The stiff methods pass the compiled kernels; the benchmark's
    baseline passes plain-Python ones (``event_values`` and ``apply_events`` as ``.py_func``).
    The returned recorder is ``rec`` or, when its contact log or strike buffers had to grow, its
    enlarged copy; its rhs_evals adds solve_ivp's count of ``fun`` calls. The integration starts where the
    recorder stands (t = 0 for a new one, which records the first sample), so a driver may resume it.
    With ``checks`` (and the right-hand side's ``work``), the blow-up checks run at solve_ivp's accepted
    steps, as in the compiled loop.
    """
    nf = modes.shape[0]
    touching_before = np.zeros(nf)
    watched = WatchedEvents(system, event_values)
    options = {"rtol": rtol, "atol": atol, "max_step": max_step, **({"jac": jac} if jac is not None else {})}
    st = rec.state[0]
    t = float(st.time)
    if st.n_samples == 0:
        record_sample(rec, t, y, modes)
    nfev = 0
    while st.status == RUNNING:
        if t >= t_end:
            st.status = COMPLETED
            break
        try:
            wanted = sample_steps(int(st.n_samples), interval)
            sol = segment(fun, t, t_end, y, method, options, SegmentEvents(watched.events, watched.values_at, wanted))
        except StoppedError as stop:
            st.status, st.reason, st.stop_time = stop.status, stop.reason, t
            break
        except ValueError as error:  # scipy's root search on its interpolant: no sign change where its step saw one
            if watched.retry_holding(error, y):
                continue  # the segment again, the events at zero held on their side
            st.status, st.reason, st.stop_time = DIVERGED, EVENT_SEARCH_FAILED, t
            break
        watched.held[:] = 0.0
        nfev += sol.nfev
        st.accepted += len(sol.t) - 1
        t_stop = float(sol.t[-1])
        if sol.status == -1 or not np.all(np.isfinite(sol.y[:, -1])):
            st.status, st.reason = DIVERGED, NONFINITE if sol.status != -1 else SOLVER_FAILED
            st.stop_time = t_stop
            t = t_stop
            break
        hit_event = sol.status == 1
        if hit_event:
            t_stop = min(t_stop + EVENT_NUDGE, t_end)
        blown = _check_steps(sol, system, modes, work, rec, checks)  # the accepted step where a check failed
        if blown is not None:
            t_stop, hit_event = float(sol.t[blown]), False
        _record_samples(rec, sol, t, t_stop, y, modes, interval)
        y[:] = sol.sol(t_stop) if hit_event else sol.y[:, -1 if blown is None else blown]
        t = t_stop
        if blown is not None:
            break
        rec = with_room(rec, nf)
        if hit_event and apply_events(t, y, system, modes, contact, rec, touching_before, max_strikes):
            st.n_events += 1
        _stop_if_fallen(t, y, system, modes, work, rec, checks)
        if progress is not None:
            progress(t)
        if not math.isfinite(t):
            st.status, st.reason = DIVERGED, NONFINITE
    if st.status == COMPLETED and work is not None:  # the state the run ends on
        blowup.check(t, y, system, modes, work, rec.state, checks, True)
    st.rhs_evals += nfev
    st.time = t
    return rec


class WatchedEvents:
    """The terminal events scipy watches, one per event function of ``system`` (``event_values`` computes them all),
    and the sides a retried segment holds those at zero on (:meth:`retry_holding`; 0: not held)."""

    def __init__(self, system: tuple, event_values: Callable[[np.ndarray, tuple, np.ndarray], None]) -> None:
        n = event_count(system)
        self.system, self.event_values = system, event_values
        self.values, self.held = np.empty(n), np.zeros(n)
        self.events = [self._event(j) for j in range(n)]

    def values_at(self, t: float, state: np.ndarray) -> np.ndarray:
        """Every event's value at ``state``, as each of :attr:`events` gives it."""
        self.event_values(state, self.system, self.values)
        held = (self.held != 0.0) & (np.abs(self.values) < EVENT_NOISE)
        return np.where(held, self.held * EVENT_NOISE, self.values)

    def _event(self, j: int) -> Callable[[float, np.ndarray], float]:
        def event(t: float, state: np.ndarray) -> float:
            self.event_values(state, self.system, self.values)
            value, side = self.values[j], self.held[j]
            return side * EVENT_NOISE if side != 0.0 and abs(value) < EVENT_NOISE else value

        event.terminal = True  # type: ignore[attr-defined]
        return event

    def retry_holding(self, error: ValueError, y: np.ndarray) -> bool:
        """After scipy's root search failed (``error``; any other ValueError is raised again): hold the events within
        ``EVENT_NOISE`` of zero at ``y``, the segment's start, on their side (the explicit loop's: zero counts as not
        positive) until they leave that band; whether the segment may be tried again (some were at zero, and none was
        held already). An event function at zero (a joint at its stop's angle) flickers in sign by round-off, and
        scipy's root search on its interpolant then finds no sign change where its step's end states had one."""
        if "different signs" not in str(error):
            raise error
        if self.held.any():
            return False
        self.event_values(y, self.system, self.values)
        at_zero = np.abs(self.values) < EVENT_NOISE
        self.held[:] = np.where(at_zero, np.where(self.values > 0.0, 1.0, -1.0), 0.0)
        return bool(at_zero.any())


def _stop_if_fallen(
    t: float, y: np.ndarray, system: tuple, modes: np.ndarray, work: tuple | None, rec: Recorder, checks: blowup.Scales
) -> None:
    """End the run at a fall (FELL and its criterion; the blow-up checks' verdict when they run)."""
    criterion = system_fall(y, system)
    if criterion and work is not None:
        blowup.fall(t, y, system, modes, work, rec.state, checks, criterion)
    elif criterion:
        st = rec.state[0]
        st.status, st.stop_time, st.reason = FELL, t, criterion


def _record_samples(
    rec: Recorder, sol: Any, t: float, t_stop: float, y: np.ndarray, modes: np.ndarray, interval: float
) -> None:
    """The samples of a solve_ivp segment from t (state ``y``) to ``t_stop``, from its dense output."""
    st = rec.state[0]
    while st.n_samples < rec.sample_t.shape[0] and st.n_samples * interval <= t_stop:
        ts = st.n_samples * interval
        if ts > t:
            record_sample(rec, ts, sol.sol(ts), modes)
        else:
            record_sample(rec, ts, y, modes)


def _check_steps(
    sol: Any, system: tuple, modes: np.ndarray, work: tuple | None, rec: Recorder, checks: blowup.Scales
) -> int | None:
    """Run the blow-up checks due at the accepted steps of a solve_ivp segment; the step where one failed, or None."""
    st = rec.state[0]
    if checks.energy <= 0.0 or work is None:
        return None
    for k in range(1, len(sol.t)):
        if sol.t[k] >= st.check_time:
            blowup.check(
                float(sol.t[k]), np.ascontiguousarray(sol.y[:, k]), system, modes, work, rec.state, checks, True
            )
            if st.status != RUNNING:
                return k
    return None
