"""Compiled explicit Runge-Kutta loop with contact events, sampling and heel-strike logging.

One numba function, :func:`advance`, runs every explicit method:

* fixed step (euler, rk2, rk4; dopri5/dop853 with step control off): discrete contact
  events (touchdown, lift-off, scuffing-guard switches) are applied at step boundaries;
* adaptive (dopri5, dop853): embedded error control (Hairer's norm and step-size rule, as in
  scipy), and events located inside the step by root finding (Illinois) on the method's
  dense output, so that no touchdown is stepped over; the step is cut at the event.

The loop is resumable: all of its state lives in the :class:`Recorder` and the arrays passed
in, so the caller may run it in chunks of ``step_budget`` steps (to draw a progress bar)
without changing a single bit of the result.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.integrate.tableaus import DOP853_KIND, DOPRI5, FIXED, Tableau
from biped_sim.multibody.dispatch import (
    system_approach_velocity,
    system_event_functions,
    system_has_fallen,
    system_is_leading,
    system_rhs,
    system_update_modes,
)

TOUCHING = 1  # column of the per-foot mode table (shared by every formulation)

# Recorder.istate entries
N_SAMPLES, N_STRIKES, N_LOG, RHS_EVALS, ACCEPTED, REJECTED, STATUS, LAST_STRIKE_FOOT, FSAL_VALID, N_EVENTS, FORCED = (
    range(11)
)
N_ISTATE = 11
# Recorder.fstate entries
TIME, STEP, FALL_TIME = range(3)
# status codes
RUNNING, COMPLETED, FELL, DIVERGED = 0, 1, 2, 3
EVENT_TIME_TOL = 1e-12  # [s] width of the bracket that locates an event
MIN_STEP = 1e-13  # [s] a smaller step means the solution diverged
FORCED_STEP = 1e-11  # [s] steps this small are accepted whatever their error estimate
MAX_FORCED = 100_000  # more forced steps than this: the solution is diverging


class Recorder(NamedTuple):
    """Loop state and output buffers (preallocated by the caller)."""

    istate: np.ndarray  # (N_ISTATE,) int64 counters and flags
    fstate: np.ndarray  # (3,) time, current step size, fall time
    sample_t: np.ndarray  # (ns,)
    sample_y: np.ndarray  # (ns, ny)
    sample_modes: np.ndarray  # (ns, nf, 3)
    strike_t: np.ndarray  # (nk,)
    strike_foot: np.ndarray  # (nk,) int64
    strike_y: np.ndarray  # (nk, ny)
    strike_modes: np.ndarray  # (nk, nf, 3)
    log: np.ndarray  # (nl, 4): time, foot, +1 touchdown / -1 lift-off, approach velocity deltadot


class Scratch(NamedTuple):
    """Per-integration buffers of the loop (allocated once)."""

    k: np.ndarray  # (16, ny) stage derivatives
    y_stage: np.ndarray  # (ny,)
    y_new: np.ndarray  # (ny,)
    y_dense: np.ndarray  # (ny,)
    dense: np.ndarray  # (7, ny) dense-output coefficients
    g_old: np.ndarray  # (n_events,) event functions at the start of the step
    g_new: np.ndarray  # (n_events,)
    g_mid: np.ndarray  # (n_events,)
    touching_before: np.ndarray  # (nf,)


def make_scratch(ny: int, nf: int, n_events: int) -> Scratch:
    """Allocate the loop buffers."""
    return Scratch(
        np.zeros((16, ny)),
        np.zeros(ny),
        np.zeros(ny),
        np.zeros(ny),
        np.zeros((7, ny)),
        np.zeros(n_events),
        np.zeros(n_events),
        np.zeros(n_events),
        np.zeros(nf),
    )


@njit(cache=True)
def _record_sample(rec: Recorder, t: float, y: np.ndarray, modes: np.ndarray) -> None:
    k = rec.istate[N_SAMPLES]
    if k < rec.sample_t.shape[0]:
        rec.sample_t[k] = t
        rec.sample_y[k, :] = y
        rec.sample_modes[k, :, :] = modes
        rec.istate[N_SAMPLES] = k + 1


@njit(cache=True)
def _apply_events(
    t: float,
    y: np.ndarray,
    system: object,
    modes: np.ndarray,
    work: tuple,
    rec: Recorder,
    sc: Scratch,
    max_strikes: int,
) -> bool:
    """Update contact modes at an event; log touchdowns/lift-offs and heel strikes.

    A heel strike is the touchdown of a foot that is ahead of its partner and is not the foot
    of the previous strike: bounces of the same foot after touchdown belong to that strike.
    """
    nf = modes.shape[0]
    for i in range(nf):
        sc.touching_before[i] = modes[i, TOUCHING]
    changed = system_update_modes(y, system, modes, work)
    if not changed:
        return False
    for i in range(nf):
        now = modes[i, TOUCHING]
        if now != sc.touching_before[i]:
            n = rec.istate[N_LOG]
            if n < rec.log.shape[0]:
                rec.log[n, 0] = t
                rec.log[n, 1] = i
                rec.log[n, 2] = 1.0 if now > 0.5 else -1.0
                rec.log[n, 3] = system_approach_velocity(y, system, i)
                rec.istate[N_LOG] = n + 1
        if work.onset[i] == 1 and i != rec.istate[LAST_STRIKE_FOOT] and system_is_leading(y, system, i):
            k = rec.istate[N_STRIKES]
            if k < rec.strike_t.shape[0]:
                rec.strike_t[k] = t
                rec.strike_foot[k] = i
                rec.strike_y[k, :] = y
                rec.strike_modes[k, :, :] = modes
            rec.istate[N_STRIKES] = k + 1
            rec.istate[LAST_STRIKE_FOOT] = i
            if max_strikes > 0 and k + 1 >= max_strikes:
                rec.istate[STATUS] = COMPLETED
    return True


@njit(cache=True)
def _prepare_dense(
    tab: Tableau,
    t: float,
    h: float,
    y: np.ndarray,
    system: object,
    modes: np.ndarray,
    work: tuple,
    sc: Scratch,
    rec: Recorder,
) -> None:
    """Dense-output coefficients of the last step (dop853 needs three extra stages)."""
    ny = y.shape[0]
    k = sc.k
    if tab.kind == DOPRI5:
        for j in range(4):
            for i in range(ny):
                v = 0.0
                for s in range(tab.stages + 1):
                    v += k[s, i] * tab.p[s, j]
                sc.dense[j, i] = v
    else:
        n_st = 12
        for e in range(3):
            s_idx = n_st + 1 + e
            for i in range(ny):
                v = 0.0
                for s in range(s_idx):
                    v += k[s, i] * tab.a_extra[e, s]
                sc.y_stage[i] = y[i] + h * v
            system_rhs(t + tab.c_extra[e] * h, sc.y_stage, system, modes, work, k[s_idx])
            rec.istate[RHS_EVALS] += 1
        for i in range(ny):
            dy = sc.y_new[i] - y[i]
            sc.dense[0, i] = dy
            sc.dense[1, i] = h * k[0, i] - dy
            sc.dense[2, i] = 2.0 * dy - h * (k[n_st, i] + k[0, i])
            for r in range(4):
                v = 0.0
                for s in range(16):
                    v += tab.d[r, s] * k[s, i]
                sc.dense[3 + r, i] = h * v


@njit(cache=True)
def _dense_eval(tab: Tableau, theta: float, h: float, y: np.ndarray, sc: Scratch, out: np.ndarray) -> None:
    """Interpolated state at t + theta h of the last step."""
    ny = y.shape[0]
    if tab.kind == DOPRI5:
        for i in range(ny):
            v = 0.0
            power = theta
            for j in range(4):
                v += sc.dense[j, i] * power
                power *= theta
            out[i] = y[i] + h * v
    else:
        for i in range(ny):
            v = 0.0
            for r in range(6, -1, -1):
                v += sc.dense[r, i]
                v *= theta if (6 - r) % 2 == 0 else 1.0 - theta
            out[i] = y[i] + v


@njit(cache=True)
def _locate_event(tab: Tableau, h: float, y: np.ndarray, system: object, sc: Scratch) -> float:
    """Earliest sign change of the event functions inside the step, as theta in (0, 1].

    Returns the right end of the final bracket (the side where the function has its new sign),
    so that the event is not found again when the integration restarts there.
    """
    m = sc.g_old.shape[0]
    theta_event = 2.0
    for j in range(m):
        if (sc.g_old[j] > 0.0) == (sc.g_new[j] > 0.0):
            continue
        lo, hi = 0.0, 1.0
        g_lo, g_hi = sc.g_old[j], sc.g_new[j]
        side = 0
        for _ in range(100):
            if (hi - lo) * h <= EVENT_TIME_TOL:
                break
            denom = g_hi - g_lo
            mid = lo - g_lo * (hi - lo) / denom if denom != 0.0 else 0.5 * (lo + hi)
            if not (lo < mid < hi):
                mid = 0.5 * (lo + hi)
            _dense_eval(tab, mid, h, y, sc, sc.y_dense)
            system_event_functions(sc.y_dense, system, sc.g_mid)
            g = sc.g_mid[j]
            if (g > 0.0) == (g_lo > 0.0):
                lo, g_lo = mid, g
                if side == -1:
                    g_hi *= 0.5
                side = -1
            else:
                hi, g_hi = mid, g
                if side == 1:
                    g_lo *= 0.5
                side = 1
        theta_event = min(theta_event, hi)
    return theta_event


@njit(cache=True)
def _rms_norm(v: np.ndarray, scale: np.ndarray) -> float:
    s = 0.0
    for i in range(v.shape[0]):
        s += (v[i] / scale[i]) ** 2
    return math.sqrt(s / v.shape[0])


@njit(cache=True)
def _error_norm(tab: Tableau, h: float, y: np.ndarray, sc: Scratch, rtol: float, atol: float) -> float:
    """Hairer's scaled RMS error norm of the embedded estimate (dop853: combined 5th/3rd order)."""
    ny = y.shape[0]
    n_k = tab.stages + 1 if tab.kind == DOPRI5 else 13
    err5 = 0.0
    err3 = 0.0
    for i in range(ny):
        scale = atol + rtol * max(abs(y[i]), abs(sc.y_new[i]))
        e5 = 0.0
        e3 = 0.0
        for s in range(n_k):
            e5 += sc.k[s, i] * tab.e[s]
            e3 += sc.k[s, i] * tab.e3[s]
        err5 += (e5 / scale) ** 2
        err3 += (e3 / scale) ** 2
    if tab.kind == DOPRI5:
        return abs(h) * math.sqrt(err5 / ny)
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return abs(h) * err5 / math.sqrt((err5 + 0.01 * err3) * ny)


@njit(cache=True)
def initial_step(
    tab: Tableau,
    t: float,
    y: np.ndarray,
    system: object,
    modes: np.ndarray,
    work: tuple,
    sc: Scratch,
    rtol: float,
    atol: float,
    max_step: float,
    rec: Recorder,
) -> float:
    """Hairer, Norsett & Wanner's starting step (Solving ODEs I, II.4); uses k[0] = f(t, y)."""
    ny = y.shape[0]
    for i in range(ny):
        sc.y_dense[i] = atol + rtol * abs(y[i])
    d0 = _rms_norm(y, sc.y_dense)
    d1 = _rms_norm(sc.k[0], sc.y_dense)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, max_step)
    for i in range(ny):
        sc.y_stage[i] = y[i] + h0 * sc.k[0, i]
    system_rhs(t + h0, sc.y_stage, system, modes, work, sc.k[1])
    rec.istate[RHS_EVALS] += 1
    for i in range(ny):
        sc.y_stage[i] = sc.k[1, i] - sc.k[0, i]
    d2 = _rms_norm(sc.y_stage, sc.y_dense) / h0
    q = tab.error_order + 1
    if max(d1, d2) <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / q)
    return min(100.0 * h0, h1, max_step)


@njit(cache=True)
def advance(
    system: object,
    work: tuple,
    tab: Tableau,
    rec: Recorder,
    sc: Scratch,
    y: np.ndarray,
    modes: np.ndarray,
    t_end: float,
    dt: float,
    adaptive: bool,
    rtol: float,
    atol: float,
    max_step: float,
    sample_dt: float,
    max_strikes: int,
    step_budget: int,
) -> None:
    """Integrate from rec.fstate[TIME] until t_end, a stop condition, or ``step_budget`` steps.

    Updates y, modes and the recorder in place. Stop conditions set rec.istate[STATUS]:
    COMPLETED (t_end or max_strikes heel strikes), FELL, DIVERGED (non-finite state or a step
    below MIN_STEP).
    """
    ny = y.shape[0]
    k = sc.k
    t = rec.fstate[TIME]
    h = rec.fstate[STEP]
    use_control = adaptive and tab.kind != FIXED
    fsal = tab.kind != FIXED
    n_k = tab.stages if tab.kind == DOPRI5 else (12 if tab.kind == DOP853_KIND else tab.stages)
    q_exp = -1.0 / (tab.error_order + 1) if tab.kind != FIXED else 0.0
    steps = 0
    if rec.istate[N_SAMPLES] == 0:
        _record_sample(rec, t, y, modes)
    system_event_functions(y, system, sc.g_old)
    while rec.istate[STATUS] == RUNNING and steps < step_budget:
        if t >= t_end:
            rec.istate[STATUS] = COMPLETED
            break
        if rec.istate[FSAL_VALID] == 0 or not fsal:
            system_rhs(t, y, system, modes, work, k[0])
            rec.istate[RHS_EVALS] += 1
            rec.istate[FSAL_VALID] = 1
        if use_control:
            if h <= 0.0:
                h = initial_step(tab, t, y, system, modes, work, sc, rtol, atol, max_step, rec)
            h = min(h, max_step)
        else:
            h = dt
        last = t + h >= t_end
        if last:
            h = t_end - t
        for s in range(1, n_k):
            for i in range(ny):
                v = 0.0
                for j in range(s):
                    v += tab.a[s, j] * k[j, i]
                sc.y_stage[i] = y[i] + h * v
            system_rhs(t + tab.c[s] * h, sc.y_stage, system, modes, work, k[s])
            rec.istate[RHS_EVALS] += 1
        finite = True
        for i in range(ny):
            v = 0.0
            for s in range(n_k):
                v += tab.b[s] * k[s, i]
            sc.y_new[i] = y[i] + h * v
            if not math.isfinite(sc.y_new[i]):
                finite = False
        if fsal and finite:
            system_rhs(t + h, sc.y_new, system, modes, work, k[n_k])
            rec.istate[RHS_EVALS] += 1
        steps += 1
        if use_control:
            err = _error_norm(tab, h, y, sc, rtol, atol) if finite else math.inf
            forced = finite and err > 1.0 and h <= FORCED_STEP
            if forced:
                # a force jump at the step start (Kelvin-Voigt touchdown on a step boundary) cannot
                # be resolved by shrinking the step: accept a tiny step across it
                rec.istate[FORCED] += 1
                if rec.istate[FORCED] > MAX_FORCED:
                    rec.istate[STATUS] = DIVERGED
                    rec.fstate[FALL_TIME] = t
                    break
                err = 1.0
            if not (err <= 1.0):
                rec.istate[REJECTED] += 1
                factor = 0.2 if not math.isfinite(err) else max(0.2, 0.9 * err**q_exp)
                h *= factor
                if h < MIN_STEP:
                    rec.istate[STATUS] = DIVERGED
                    rec.fstate[FALL_TIME] = t
                continue
            h_next = h * (10.0 if err == 0.0 else min(10.0, 0.9 * err**q_exp))
        else:
            if not finite:
                rec.istate[STATUS] = DIVERGED
                rec.fstate[FALL_TIME] = t
                break
            h_next = h
        rec.istate[ACCEPTED] += 1
        system_event_functions(sc.y_new, system, sc.g_new)
        crossed = False
        for j in range(sc.g_new.shape[0]):
            if (sc.g_old[j] > 0.0) != (sc.g_new[j] > 0.0):
                crossed = True
        theta_end = 1.0
        dense_ready = False
        if crossed and use_control:
            _prepare_dense(tab, t, h, y, system, modes, work, sc, rec)
            dense_ready = True
            theta_end = _locate_event(tab, h, y, system, sc)
            if theta_end < 1.0:
                _dense_eval(tab, theta_end, h, y, sc, sc.y_new)
        t_new = t + h if theta_end >= 1.0 else t + theta_end * h
        # samples inside (t, t_new]
        while True:
            ks = rec.istate[N_SAMPLES]
            ts = ks * sample_dt
            tol = 1e-12 * max(1.0, t_new) if use_control else 0.5 * h
            if ks >= rec.sample_t.shape[0] or ts > t_new + tol:
                break
            if use_control:
                if not dense_ready:
                    _prepare_dense(tab, t, h, y, system, modes, work, sc, rec)
                    dense_ready = True
                _dense_eval(tab, min((ts - t) / h, 1.0), h, y, sc, sc.y_dense)
                _record_sample(rec, ts, sc.y_dense, modes)
            else:
                _record_sample(rec, t_new, sc.y_new, modes)
        t = t_new if not last or theta_end < 1.0 else t_end
        y[:] = sc.y_new
        if theta_end < 1.0:
            rec.istate[FSAL_VALID] = 0
        if crossed:
            if _apply_events(t, y, system, modes, work, rec, sc, max_strikes):
                rec.istate[N_EVENTS] += 1
                rec.istate[FSAL_VALID] = 0
            system_event_functions(y, system, sc.g_old)
        else:
            for j in range(sc.g_new.shape[0]):
                sc.g_old[j] = sc.g_new[j]
        if fsal and rec.istate[FSAL_VALID] == 1:
            k[0, :] = k[n_k]
        if use_control:
            h = h_next
        if system_has_fallen(y, system):
            rec.istate[STATUS] = FELL
            rec.fstate[FALL_TIME] = t
    rec.fstate[TIME] = t
    rec.fstate[STEP] = h
