"""One stance phase of the rigid walker in space integrated, compiled: DOP853 over the compiled flow to the phase's
guard or a fall (numba).

The algorithm is the planar step map's (:mod:`biped_sim.rigid.integration`, described in
:mod:`biped_sim.rigid.compiled`), which is scipy's ``solve_ivp`` DOP853 with terminal events: rtol = atol = 1e-12,
Hairer's starting step, error norm and step-size control (the compliant loop's tableau, stages and dense output);
after each accepted step the events' values are compared with the step start's, a downward zero of the phase's guard
or of the fall function located on the degree-7 dense output by the Illinois variant of regula falsi to 4 machine
epsilon in time (scipy: brentq to the same width), the earliest one ending the phase. It replaces scipy's loop,
whose Python between the flow's calls took most of a step's time (the flow a tenth of it): it gives scipy's steps
and event times to rounding, not bit for bit (numpy's BLAS sums the stages in another order).

Guards (:func:`space_guard`): phase 0 ends when the hinge angle falls through zero (the swing foot passes the
stance foot), phase 1 when the swing foot's lowest point reaches the slope (:func:`space_clearance`). The fall
function is the smaller of the hip's height above ``fall_height`` and the bank's margin to ``FALL_BANK``.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.integrate.dense import (
    dense_eval,
    dop853_coefficients,
    dop853_extra_stage_input,
    illinois_point,
    illinois_update,
)
from biped_sim.integrate.stepper import (
    Scratch,
    error_norm,
    initial_step_size,
    initial_step_trial,
    make_scratch,
    propagate,
    stage_input,
    step_factor,
)
from biped_sim.integrate.tableaus import Tableau, tableau
from biped_sim.kernel import kernel
from biped_sim.rigid.integration import MIN_STEP, ROOT_TOL, copy_into
from biped_sim.rigid.space_kernels import bottom, rotations, space_flow
from biped_sim.rigid.space_model import N_STATE
from biped_sim.rigid.step import ATOL, RTOL

GUARD, FELL, STALLED = 0, 1, 2  # how a phase ends (:func:`space_phase`)
PHASE_NAMES = ("guard", "fell", "stalled")
FALL_BANK = 1.2  # [rad] a bank past it is a fall
N_SPACE_EVENTS = 2  # the phase's guard, the fall function


def space_scratch() -> tuple[Tableau, Scratch]:
    """The integration's tableau (DOP853) and buffers, made once per step map."""
    return tableau("dop853"), make_scratch(N_STATE, 0, N_SPACE_EVENTS)


@kernel
def space_clearance(p: np.ndarray, x: np.ndarray) -> float:
    """The swing foot's lowest point above the slope (the stance foot's is on it)."""
    stance, swing = rotations(x)
    stance_bottom, _ = bottom(p, 0, stance)
    swing_bottom, _ = bottom(p, 1, swing)
    return swing_bottom[2] - stance_bottom[2]


@kernel
def space_guard(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """The guard of ``phase``: the hinge angle (phase 0), the swing foot's clearance (phase 1)."""
    return x[3] if phase == 0 else space_clearance(p, x)


@kernel
def space_fall(p: np.ndarray, fall_height: float, x: np.ndarray) -> float:
    """Negative once the walker fell: the hinge's height above ``fall_height`` or the bank past ``FALL_BANK``."""
    stance, _ = rotations(x)
    stance_bottom, _ = bottom(p, 0, stance)
    return min(-stance_bottom[2] - fall_height, FALL_BANK - abs(x[1]))


@kernel
def _events(p: np.ndarray, phase: int, fall_height: float, x: np.ndarray, out: np.ndarray) -> None:
    """out = (the phase's guard, the fall function)."""
    out[0] = space_guard(p, phase, x)
    out[1] = space_fall(p, fall_height, x)


@kernel
def _event_value(p: np.ndarray, phase: int, fall_height: float, j: int, x: np.ndarray) -> float:
    return space_guard(p, phase, x) if j == 0 else space_fall(p, fall_height, x)


@kernel
def _root(
    p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, fall_height: float, j: int, t: float, h: float, y: np.ndarray
) -> float:
    """Zero of event j inside the step as theta in [0, 1] (Illinois on the dense output)."""
    lo, hi = 0.0, 1.0
    g_lo, g_hi = sc.g_old[j], sc.g_new[j]
    if g_hi == 0.0:
        return 1.0
    side = 0
    tol = ROOT_TOL * max(1.0, abs(t)) / h
    for _ in range(200):
        if hi - lo <= tol or g_lo == 0.0:
            break
        mid = illinois_point(lo, hi, g_lo, g_hi)
        dense_eval(tab, mid, h, y, sc, sc.y_dense)
        g = _event_value(p, phase, fall_height, j, sc.y_dense)
        same_sign = (g > 0.0) == (g_lo > 0.0) and g != 0.0
        lo, hi, g_lo, g_hi, side = illinois_update(lo, hi, g_lo, g_hi, side, mid, g, same_sign)
    return lo if abs(g_lo) < abs(g_hi) else hi


@kernel
def _first_event(
    p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, fall_height: float, t: float, h: float, y: np.ndarray
) -> tuple[int, float]:
    """The earliest event that fell through zero over the accepted step from (t, y) of length h, and where (theta);
    (-1, 2.0) when none did. Prepares the dense output when one did."""
    first, best = -1, 2.0
    for j in range(N_SPACE_EVENTS):
        if sc.g_old[j] >= 0.0 and sc.g_new[j] <= 0.0:
            if first < 0:
                for e in range(3):
                    row = dop853_extra_stage_input(tab, h, y, sc, e)  # fills sc.y_stage
                    copy_into(space_flow(p, sc.y_stage), sc.k[row])
                dop853_coefficients(tab, h, y, sc)
            theta = _root(p, tab, sc, phase, fall_height, j, t, h, y)
            if theta < best:
                first, best = j, theta
    return first, best


@kernel
def _attempt(p: np.ndarray, tab: Tableau, sc: Scratch, h: float, y: np.ndarray) -> float:
    """One DOP853 step of length h from y: the stages, sc.y_new and the FSAL stage; its error norm."""
    for s in range(1, tab.stages):
        stage_input(tab.a, s, h, y, sc.k, sc.y_stage)
        copy_into(space_flow(p, sc.y_stage), sc.k[s])
    if not propagate(tab.b, tab.stages, h, y, sc.k, sc.y_new):
        return math.inf
    copy_into(space_flow(p, sc.y_new), sc.k[tab.stages])
    return error_norm(tab, h, y, sc, RTOL, ATOL)


@kernel
def space_phase(
    p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, t: float, t_limit: float, fall_height: float, y: np.ndarray
) -> tuple[int, float]:
    """Integrate the stance phase ``phase`` from (t, y) to its guard (GUARD), a fall (FELL) or ``t_limit``
    (STALLED, as a step too short to take); y ends there (in place). Returns (how, t)."""
    copy_into(space_flow(p, y), sc.k[0])
    h0, d1 = initial_step_trial(y, sc, RTOL, ATOL, t_limit - t)
    copy_into(space_flow(p, sc.y_stage), sc.k[1])
    h = initial_step_size(tab, sc, h0, d1, t_limit - t)
    _events(p, phase, fall_height, y, sc.g_old)
    rejected = False
    while t < t_limit:
        h = min(h, t_limit - t)
        if h < MIN_STEP:
            return STALLED, t
        accepted, factor = step_factor(_attempt(p, tab, sc, h, y), tab.error_order, rejected)
        rejected = not accepted
        if not accepted:
            h *= factor
            continue
        _events(p, phase, fall_height, sc.y_new, sc.g_new)
        first, theta = _first_event(p, tab, sc, phase, fall_height, t, h, y)
        if first >= 0:
            dense_eval(tab, theta, h, y, sc, sc.y_dense)
            copy_into(sc.y_dense, y)
            return (GUARD if first == 0 else FELL), t + theta * h
        t += h
        copy_into(sc.y_new, y)
        copy_into(sc.k[tab.stages], sc.k[0])
        copy_into(sc.g_new, sc.g_old)
        h *= factor
    return STALLED, t
