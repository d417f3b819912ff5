"""Compiled explicit Runge-Kutta loop with contact events, sampling and heel-strike logging.

One numba function, :func:`advance`, runs every explicit method:

* fixed step (euler, rk2, rk4; dopri5/dop853 with step control off): discrete contact
  events (touchdown, lift-off, scuffing-guard switches) are applied at step boundaries;
* adaptive (dopri5, dop853): embedded error control (Hairer's norm and step-size rule, as in
  scipy: :func:`~biped_sim.integrate.stepper.step_factor`), and events located inside the step by root
  finding (Illinois) on the method's dense output, so that no touchdown is stepped over; the step is cut
  at the event.

Each pass of the loop takes a step (its stages: :func:`~biped_sim.integrate.stepper.stage_input`,
:func:`~biped_sim.integrate.stepper.propagate`), controls its error (:func:`_control`) and, when
an event function changed sign or a sample falls inside the step, locates the event and records
the samples (:func:`_locate_and_sample`) and applies the event (:func:`_update_at_event`); most
steps need neither. The loop is resumable: all of its state lives in the recorder and the arrays
of its :class:`~biped_sim.integrate.stepper.Loop`, so the caller may run it in chunks of
``step_budget`` steps (to draw a progress bar), or stop it when the contact log or the strike
buffer is full and enlarge them, without changing a single bit of the result.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.integrate import blowup
from biped_sim.integrate.dense import dense_coefficients, dense_eval, dop853_extra_stage_input, locate_event
from biped_sim.integrate.recorder import (
    COMPLETED,
    DIVERGED,
    MIN_STEP_REACHED,
    NONFINITE,
    RUNNING,
    STEPS_COLLAPSED,
    TOO_MANY_FORCED,
    apply_events,
    copy_vector,
    has_room,
    record_sample,
)
from biped_sim.integrate.stepper import SAFETY, Loop, error_norm, initial_step, propagate, stage_input, step_factor
from biped_sim.integrate.tableaus import DOPRI5, FIXED
from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import system_fall, system_rhs
from biped_sim.multibody.events import system_event_functions

MIN_STEP = 1e-13  # [s] a smaller step means the solution diverged
FORCED_STEP = 1e-11  # [s] steps this small are accepted whatever their error estimate
MAX_FORCED = 100_000  # more forced steps than this: the solution is diverging
STALL_CHECK_STEPS = 200_000  # after this many accepted adaptive steps, ...
MIN_MEAN_STEP = 1e-8  # [s] ... a mean step below this means the control is stuck (the walker's is ~1e-4 s)


class Settings(NamedTuple):
    """The integration's parameters, as the loop reads them."""

    t_end: float  # [s]
    dt: float  # [s] step of the fixed-step methods
    control: bool  # embedded error control and located events (adaptive dopri5 and dop853)
    rtol: float
    atol: float
    max_step: float  # [s]
    sample_dt: float  # [s]
    max_strikes: int  # heel strikes that complete the run (0: no limit)
    checks: blowup.Scales  # the blow-up checks' units (energy 0: none)


@njit(cache=True, inline="always")  # inlined: a compiled function would be compiled once per literal status
def _stop(st: np.record, status: int, t: float, reason: int = 0) -> None:
    """End the integration with ``status`` (DIVERGED, and why) at time t (``st``: the loop-state record)."""
    st.status = status
    st.stop_time = t
    st.reason = reason


@njit(cache=True, inline="always")
def _step_size(t: float, h: float, cfg: Settings) -> tuple[float, bool]:
    """The step to take from t: (h, whether it ends at t_end); h is the controller's proposal or dt."""
    if cfg.control:
        h = min(h, cfg.max_step)
    else:
        h = cfg.dt
    last = t + h >= cfg.t_end
    if last:
        h = cfg.t_end - t
    return h, last


@njit(cache=True, inline="always")
def _control(err: float, finite: bool, t: float, h: float, error_order: int, st: np.record) -> tuple[bool, float]:
    """Error control of a step with error norm ``err``: (accepted, next step) or (rejected, step to retry with).

    The controller :func:`~biped_sim.integrate.stepper.step_factor` (the step after a rejection may grow), but
    for a step of at most FORCED_STEP: accepted whatever its error, as if it were 1 (next step SAFETY h).
    Stops the integration as DIVERGED when the step falls below MIN_STEP or too many steps were forced.
    ``finite``: whether the step's end state is finite (else err is inf).
    """
    if finite and not err < 1.0 and h <= FORCED_STEP:
        # a force jump at the step start (Kelvin-Voigt touchdown on a step boundary) cannot be
        # resolved by shrinking the step: accept a tiny step across it
        st.forced += 1
        if st.forced > MAX_FORCED:
            _stop(st, DIVERGED, t, TOO_MANY_FORCED)
            return False, h
        return True, h * SAFETY
    accepted, factor = step_factor(err, error_order, False)
    h *= factor
    if not accepted:
        st.rejected += 1
        if not h >= MIN_STEP:  # a NaN step too
            _stop(st, DIVERGED, t, MIN_STEP_REACHED if math.isfinite(h) else NONFINITE)
    return accepted, h


@njit(cache=True, inline="always")
def _crossed(g_old: np.ndarray, g_new: np.ndarray) -> bool:
    """Whether an event function changed sign over the step."""
    for j in range(g_new.shape[0]):
        if (g_old[j] > 0.0) != (g_new[j] > 0.0):
            return True
    return False


@njit(cache=True, inline="always")
def _sample_tolerance(t_new: float, h: float, cfg: Settings) -> float:
    """How far past t_new a sample time may be and still be taken at the end of this step."""
    return 1e-12 * max(1.0, t_new) if cfg.control else 0.5 * h


@njit(cache=True, inline="always")
def _sample_due(n_samples: int, capacity: int, t_new: float, h: float, cfg: Settings) -> bool:
    """Whether the next sample time falls in the step ending at t_new (and the sample buffer has room)."""
    return n_samples < capacity and n_samples * cfg.sample_dt <= t_new + _sample_tolerance(t_new, h, cfg)


@njit(cache=True, inline="always")  # one call site: inlined, it compiles once with the loop
def _locate_and_sample(loop: Loop, t: float, h: float, crossed: bool, cfg: Settings) -> tuple[float, float]:
    """Cut the accepted step at its first event (adaptive methods) and record the samples inside it.

    Returns (t_new, theta_end): the end of the step and its fraction of h (1: not cut); a cut step's
    end state replaces sc.y_new. Samples at multiples of sample_dt in (t, t_new] come from the dense
    output (adaptive methods) or are the step's end (fixed steps).
    """
    tab, system, work, _, y, modes, sc, rec = loop
    st = rec.state[0]
    theta_end = 1.0
    if cfg.control:  # an event or a sample is inside the step: both read the dense output
        if tab.kind != DOPRI5:  # DOP853's interpolant needs three more stages
            for e in range(3):
                stage = dop853_extra_stage_input(tab, h, y, sc, e)
                system_rhs(t + tab.c_extra[e] * h, sc.y_stage, system, modes, work, sc.k[stage])
                st.rhs_evals += 1
        dense_coefficients(tab, h, y, sc)
        if crossed:
            theta_end = locate_event(tab, h, y, system, sc)
            if theta_end < 1.0:
                dense_eval(tab, theta_end, h, y, sc, sc.y_new)
    t_new = t + h if theta_end >= 1.0 else t + theta_end * h
    while _sample_due(st.n_samples, rec.sample_t.shape[0], t_new, h, cfg):
        ts = st.n_samples * cfg.sample_dt
        if cfg.control:
            dense_eval(tab, min((ts - t) / h, 1.0), h, y, sc, sc.y_dense)
            record_sample(rec, ts, sc.y_dense, modes)
        else:
            record_sample(rec, t_new, sc.y_new, modes)
    return t_new, theta_end


@njit(cache=True, inline="always")  # one call site: inlined, it compiles once with the loop
def _update_at_event(loop: Loop, t: float, max_strikes: int) -> bool:
    """Apply the event at t (y is there now); returns whether the recorder has room for one more."""
    y, sc, st = loop.y, loop.sc, loop.rec.state[0]
    if apply_events(t, y, loop.system, loop.modes, loop.contact, loop.rec, sc.touching_before, max_strikes):
        st.n_events += 1
        st.fsal_valid = 0
    system_event_functions(y, loop.system, sc.g_old)
    return has_room(loop.rec, loop.modes.shape[0])


@kernel(reference_counts=False)
def advance(loop: Loop, cfg: Settings, step_budget: int) -> None:
    """Integrate from the recorder's time to t_end, a stop, ``step_budget`` steps or a full buffer (in place).

    Stops set the status: COMPLETED (t_end or max_strikes heel strikes), FELL (the record's ``reason``: the
    fall kernel's criterion), DIVERGED (non-finite state or step, step below MIN_STEP, too many forced steps,
    steps collapsed, or the blow-up checks of :mod:`~biped_sim.integrate.blowup`: the record's ``reason``).
    It returns RUNNING after ``step_budget`` steps or when one more event might not fit in the recorder
    (:func:`~biped_sim.integrate.recorder.has_room`).
    """
    tab, system, work, _, y, modes, sc, rec = loop
    st = rec.state[0]
    t, h = st.time, st.step
    if st.n_samples == 0:  # the start: its sample and the energy the blow-up checks measure from
        record_sample(rec, t, y, modes)
        if cfg.checks.energy > 0.0:
            st.energy_reference = blowup.energy_reference(y, system, modes)
    system_event_functions(y, system, sc.g_old)
    steps, room = 0, has_room(rec, modes.shape[0])
    while st.status == RUNNING and steps < step_budget and room:
        if t >= cfg.t_end:
            st.status = COMPLETED
            break
        if st.fsal_valid == 0 or tab.kind == FIXED:  # first stage k[0] = f(t, y), unless FSAL kept it
            system_rhs(t, y, system, modes, work, sc.k[0])
            st.rhs_evals += 1
            st.fsal_valid = 1
        if cfg.control and h <= 0.0:
            h = initial_step(tab, t, y, system, modes, work, sc, st, cfg.rtol, cfg.atol, cfg.max_step)
        h, last = _step_size(t, h, cfg)
        for s in range(1, tab.stages):  # the step: stages k[s] = f(t + c_s h, y + h sum_j a_sj k[j])
            stage_input(tab.a, s, h, y, sc.k, sc.y_stage)
            system_rhs(t + tab.c[s] * h, sc.y_stage, system, modes, work, sc.k[s])
            st.rhs_evals += 1
        finite = propagate(tab.b, tab.stages, h, y, sc.k, sc.y_new)
        if tab.kind != FIXED and finite:  # FSAL stage f(t + h, y_new), the next step's k[0]
            system_rhs(t + h, sc.y_new, system, modes, work, sc.k[tab.stages])
            st.rhs_evals += 1
        steps += 1
        h_next = h
        if cfg.control:
            err = error_norm(tab, h, y, sc, cfg.rtol, cfg.atol) if finite else math.inf
            accepted, h_next = _control(err, finite, t, h, tab.error_order, st)
            if not accepted:
                h = h_next
                continue
        elif not finite:
            _stop(st, DIVERGED, t, NONFINITE)
            break
        st.accepted += 1
        if cfg.control and st.accepted >= STALL_CHECK_STEPS and t < st.accepted * MIN_MEAN_STEP:
            _stop(st, DIVERGED, t, STEPS_COLLAPSED)
            break
        system_event_functions(sc.y_new, system, sc.g_new)
        crossed = _crossed(sc.g_old, sc.g_new)
        t_new, theta_end = t + h, 1.0
        if crossed or _sample_due(st.n_samples, rec.sample_t.shape[0], t_new, h, cfg):  # else nothing happens inside
            t_new, theta_end = _locate_and_sample(loop, t, h, crossed, cfg)
        t = t_new if not last or theta_end < 1.0 else cfg.t_end
        copy_vector(y, sc.y_new)
        if theta_end < 1.0:
            st.fsal_valid = 0
        if crossed:
            room = _update_at_event(loop, t, cfg.max_strikes)
        else:
            copy_vector(sc.g_old, sc.g_new)
        if tab.kind != FIXED and st.fsal_valid == 1:
            copy_vector(sc.k[0], sc.k[tab.stages])
        h = h_next
        criterion = system_fall(y, system)
        if criterion:
            blowup.fall(t, y, system, modes, work, rec.state, cfg.checks, criterion)
        else:
            blowup.check(t, y, system, modes, work, rec.state, cfg.checks, False)
    if st.status == COMPLETED:  # the state the run ends on
        blowup.check(t, y, system, modes, work, rec.state, cfg.checks, True)
    st.time = t
    st.step = h
