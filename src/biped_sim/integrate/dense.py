"""Dense output of the last explicit step and the location of events inside it (compiled).

An adaptive step that changes the sign of an event function (a foot's penetration, its lead over
its partner) is cut at the event: the earliest sign change is located on the method's dense output
by the Illinois variant of regula falsi to EVENT_TIME_TOL, so that no touchdown is stepped over.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from biped_sim.integrate.stepper import Scratch
from biped_sim.integrate.tableaus import DOPRI5, Tableau
from biped_sim.kernel import kernel
from biped_sim.multibody.events import system_event_functions

EVENT_TIME_TOL = 1e-12  # [s] width of the bracket that locates an event


@njit(cache=True, inline="always")
def dop853_extra_stage_input(tab: Tableau, h: float, y: np.ndarray, sc: Scratch, e: int) -> int:
    """DOP853's extra dense-output stage e (0, 1, 2): its input state into ``sc.y_stage``; returns the row of
    ``sc.k`` where the caller stores f at t + c_extra[e] h of it (the 12 stages and FSAL come first)."""
    stage = 13 + e
    for i in range(y.shape[0]):
        v = 0.0
        for s in range(stage):
            v += sc.k[s, i] * tab.a_extra[e, s]
        sc.y_stage[i] = y[i] + h * v
    return stage


@njit(cache=True, inline="always")
def dop853_coefficients(tab: Tableau, h: float, y: np.ndarray, sc: Scratch) -> None:
    """Hairer's degree-7 interpolant of the last DOP853 step, from its 16 stages (the three extra ones included)."""
    k = sc.k
    for i in range(y.shape[0]):
        dy = sc.y_new[i] - y[i]
        sc.dense[0, i] = dy
        sc.dense[1, i] = h * k[0, i] - dy
        sc.dense[2, i] = 2.0 * dy - h * (k[12, i] + k[0, i])
        for r in range(4):
            v = 0.0
            for s in range(16):
                v += tab.d[r, s] * k[s, i]
            sc.dense[3 + r, i] = h * v


@kernel
def dense_coefficients(tab: Tableau, h: float, y: np.ndarray, sc: Scratch) -> None:
    """Dense-output coefficients of the last step, from its stages in ``sc.k`` (dop853: the three extra ones too).

    dopri5: Shampine's quartic, y(t + theta h) = y + h sum_j (sum_s k[s] p[s, j]) theta^(j+1);
    dop853: Hairer's degree-7 interpolant from the 12 stages, the FSAL stage and three extra ones
    (:func:`dop853_extra_stage_input`; the loop evaluates them, so that only it calls the right-hand side).
    """
    if tab.kind != DOPRI5:
        dop853_coefficients(tab, h, y, sc)
        return
    k = sc.k
    for j in range(4):
        for i in range(y.shape[0]):
            v = 0.0
            for s in range(tab.stages + 1):
                v += k[s, i] * tab.p[s, j]
            sc.dense[j, i] = v


@kernel
def dense_eval(tab: Tableau, theta: float, h: float, y: np.ndarray, sc: Scratch, out: np.ndarray) -> None:
    """out = the interpolated state at t + theta h of the last step (from y at t)."""
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


@njit(cache=True, inline="always")
def illinois_point(lo: float, hi: float, g_lo: float, g_hi: float) -> float:
    """The next point of the Illinois method in the bracket [lo, hi] (regula falsi; bisection when it leaves it)."""
    mid = lo - g_lo * (hi - lo) / (g_hi - g_lo) if g_hi != g_lo else 0.5 * (lo + hi)
    return mid if lo < mid < hi else 0.5 * (lo + hi)


@njit(cache=True, inline="always")
def illinois_update(
    lo: float, hi: float, g_lo: float, g_hi: float, side: int, mid: float, g: float, replaces_lo: bool
) -> tuple[float, float, float, float, int]:
    """The bracket after the value g at mid: it replaces the ``lo`` end or the ``hi`` end (the caller's sign
    test). An end kept twice in a row has its value halved (Illinois), so the bracket shrinks from both sides.
    ``side`` is -1 or 1 after a replaced lo or hi end (0 at the start). Returns (lo, hi, g_lo, g_hi, side)."""
    if replaces_lo:
        if side == -1:
            g_hi *= 0.5
        return mid, hi, g, g_hi, -1
    if side == 1:
        g_lo *= 0.5
    return lo, mid, g_lo, g, 1


@njit(cache=True, inline="always")
def locate_event(tab: Tableau, h: float, y: np.ndarray, system: tuple, sc: Scratch) -> float:
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
            mid = illinois_point(lo, hi, g_lo, g_hi)
            dense_eval(tab, mid, h, y, sc, sc.y_dense)
            system_event_functions(sc.y_dense, system, sc.g_mid)
            g = sc.g_mid[j]
            lo, hi, g_lo, g_hi, side = illinois_update(lo, hi, g_lo, g_hi, side, mid, g, (g > 0.0) == (g_lo > 0.0))
        theta_event = min(theta_event, hi)
    return theta_event


@kernel(reference_counts=False)
def sample_dense(
    tab: Tableau, sc: Scratch, rate: float, k: int, t: float, h: float, t_end: float, y: np.ndarray,
    times: np.ndarray, states: np.ndarray, n: int,
) -> int:  # fmt: skip
    """Record the grid points k / rate in [t, t_end) of the last accepted step (from (t, y), length h) on its dense
    output (prepared by the caller) into rows n, n + 1, ... of ``times`` and ``states`` (those past their end are
    dropped: the caller sizes them for a whole step); returns the next free row."""
    while k / rate < t_end and n < times.shape[0]:
        times[n] = k / rate
        dense_eval(tab, (k / rate - t) / h, h, y, sc, states[n])
        n += 1
        k += 1
    return n
