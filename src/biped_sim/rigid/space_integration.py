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
stance foot), phase 1 when the swing foot's lowest point reaches the slope (:func:`space_clearance`), phase 2
(``KNEE_PHASE``, a kneed walker's first) when the swing knee's flexion falls through zero (the knee strike). The
fall function is the smaller of the hip's height above ``fall_height`` and the bank's margin to ``FALL_BANK``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.integrate.dense import (
    dense_eval,
    dop853_coefficients,
    dop853_extra_stage_input,
    sample_dense,
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
from biped_sim.rigid.integration import MIN_STEP, copy_into, event_root, first_sample
from biped_sim.rigid.space_kernels import KNEE_FLEXION, bottom, knee_frame, rotations, space_flow
from biped_sim.rigid.space_model import KNEE_ANGLE, N_STATE
from biped_sim.rigid.step import ATOL, RTOL

GUARD, FELL, STALLED, REACHED, STIFF = 0, 1, 2, 3, 4  # how a phase ends (:func:`space_phase`); REACHED: its stop
PHASE_NAMES = ("guard", "fell", "stalled", "until", "stiff")  # time; STIFF: MAX_ATTEMPTS steps tried
MAX_ATTEMPTS = 20_000  # steps tried in one phase (a walking step's phase takes some tens to hundreds): more is a
# flow the integrator cannot follow (a nearly singular mass matrix: a motion almost no mass resists)
FALL_BANK = 1.2  # [rad] a bank past it is a fall
N_SPACE_EVENTS = 2  # the phase's guard, the fall function
KNEE_PHASE = 2  # the phase that ends at the swing knee's strike
SAMPLED, FLOWS, ACCEPTED = 0, 1, 2  # PhaseRecord.counts: samples taken, flow calls, accepted steps


class PhaseRecord(NamedTuple):
    """What the phases of a step write besides their end state: the samples on the grid k / rate of the step's
    clock and the integrator's counters (``counts``, reset by the caller)."""

    counts: np.ndarray  # (3,) int64: samples, flow calls, accepted steps
    samples_t: np.ndarray  # (m,)
    samples_x: np.ndarray  # (m, the state's length)


class SpaceScratch(NamedTuple):
    """The integration's tableau (DOP853), buffers and record, made once per step map or run."""

    tab: Tableau
    sc: Scratch
    record: PhaseRecord


def space_scratch(samples: int = 0, n_state: int = N_STATE) -> SpaceScratch:
    """The integration's tableau, buffers and a record with room for ``samples`` samples a step, for states of
    ``n_state`` (the model's ``n_state``)."""
    record = PhaseRecord(np.zeros(3, dtype=np.int64), np.empty(samples), np.empty((samples, n_state)))
    return SpaceScratch(tableau("dop853"), make_scratch(n_state, 0, N_SPACE_EVENTS), record)


@kernel
def space_clearance(p: np.ndarray, x: np.ndarray) -> float:
    """The swing foot's lowest point above the slope (the stance foot's is on it)."""
    stance, swing = rotations(x)
    stance_bottom, _ = bottom(p, 0, stance)
    shank, shift = knee_frame(p, x, swing)
    swing_bottom, _ = bottom(p, 1, shank)
    return swing_bottom[2] + shift[2] - stance_bottom[2]


@kernel
def space_guard(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """The guard of ``phase``: the hinge angle (phase 0), the swing foot's clearance (phase 1), the swing knee's
    flexion (``KNEE_PHASE``)."""
    if phase == KNEE_PHASE:
        return p[KNEE_FLEXION] * x[KNEE_ANGLE]
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


@njit(cache=True, inline="always")  # inlined into _root: a kernel of its own costs more to compile than its copy
def _event_value(on: tuple[np.ndarray, int, float], j: int, x: np.ndarray) -> float:
    """Event j at x for ``on`` = (the parameters, the phase, the fall height): the phase's guard (j = 0), the fall."""
    p, phase, fall_height = on
    return space_guard(p, phase, x) if j == 0 else space_fall(p, fall_height, x)


@kernel
def _root(
    p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, fall_height: float, j: int, t: float, h: float, y: np.ndarray
) -> float:
    """Zero of event j inside the step as theta in [0, 1] (:func:`~biped_sim.rigid.integration.event_root`): a kernel
    of its own, which the run's process compiles while the second compiles the flow (``space_aside.events_share``)."""
    return event_root(_event_value, (p, phase, fall_height), tab, sc, j, t, h, y)


@kernel
def _prepare_dense(p: np.ndarray, tab: Tableau, sc: Scratch, h: float, y: np.ndarray) -> None:
    """DOP853's dense-output coefficients of the last step (three extra stages of the flow)."""
    for e in range(3):
        row = dop853_extra_stage_input(tab, h, y, sc, e)  # fills sc.y_stage
        copy_into(space_flow(p, sc.y_stage), sc.k[row])
    dop853_coefficients(tab, h, y, sc)


@njit(cache=True, inline="always")  # inlined, as _accepted: a kernel of its own would emit both trees' code again
def _first_event(
    p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, fall_height: float, t: float, h: float, y: np.ndarray
) -> tuple[int, float]:
    """The earliest event that fell through zero over the accepted step from (t, y) of length h, and where (theta);
    (-1, 2.0) when none did. Prepares the dense output when one did."""
    first, best = -1, 2.0
    for j in range(N_SPACE_EVENTS):
        if sc.g_old[j] >= 0.0 and sc.g_new[j] <= 0.0:
            if first < 0:
                _prepare_dense(p, tab, sc, h, y)
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


@njit(cache=True, inline="always")  # inlined in the phase (one call site), for the same reason
def _accepted(
    p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, fall_height: float, rate: float, k: int, t: float, h: float,
    y: np.ndarray, rec: PhaseRecord,
) -> tuple[int, float, int]:  # fmt: skip
    """After an accepted step from (t, y) of length h: its first event (-1: none) and where (theta; 2.0: none),
    the samples up to there (or to t + h) taken; returns them and the next grid index."""
    rec.counts[ACCEPTED] += 1
    _events(p, phase, fall_height, sc.y_new, sc.g_new)
    first, theta = _first_event(p, tab, sc, phase, fall_height, t, h, y)
    rec.counts[FLOWS] += 0 if first < 0 else 3
    t_end = t + theta * h if first >= 0 else t + h
    if rate > 0.0 and k / rate < t_end:
        if first < 0:
            _prepare_dense(p, tab, sc, h, y)
            rec.counts[FLOWS] += 3
        n = sample_dense(tab, sc, rate, k, t, h, t_end, y, rec.samples_t, rec.samples_x, rec.counts[SAMPLED])
        k += n - rec.counts[SAMPLED]
        rec.counts[SAMPLED] = n
    return first, theta, k


@kernel
def space_phase(
    p: np.ndarray, scratch: SpaceScratch, phase: int, t: float, t_stop: float, t_limit: float, fall_height: float,
    rate: float, y: np.ndarray,
) -> tuple[int, float]:  # fmt: skip
    """Integrate the stance phase ``phase`` from (t, y) to its guard (GUARD), a fall (FELL), ``t_stop`` (REACHED, or
    STALLED when it is the step's time limit ``t_limit``; also a step too short to take) or ``MAX_ATTEMPTS`` steps
    tried (STIFF); y ends there (in place).
    Samples on the grid k / ``rate`` (0: none) of [t, its end) go to ``scratch.record``. A fresh start each call, as
    scipy's solve_ivp after a push: the starting step, the events' values at the start. Returns (how, t)."""
    tab, sc, rec = scratch
    k = first_sample(rate, t)
    copy_into(space_flow(p, y), sc.k[0])
    h0, d1 = initial_step_trial(y, sc, RTOL, ATOL, t_stop - t)
    copy_into(space_flow(p, sc.y_stage), sc.k[1])
    h = initial_step_size(tab, sc, h0, d1, t_stop - t)
    rec.counts[FLOWS] += 2
    _events(p, phase, fall_height, y, sc.g_old)
    rejected, stalled, attempts = False, STALLED if t_stop >= t_limit else REACHED, 0
    while t < t_stop:
        clipped = h >= t_stop - t
        h = min(h, t_stop - t)
        if h < MIN_STEP:
            return (stalled if clipped else STALLED), t
        attempts += 1
        if attempts > MAX_ATTEMPTS:
            return STIFF, t
        accepted, factor = step_factor(_attempt(p, tab, sc, h, y), tab.error_order, rejected)
        rec.counts[FLOWS] += tab.stages
        rejected = not accepted
        if not accepted:
            h *= factor
            continue
        first, theta, k = _accepted(p, tab, sc, phase, fall_height, rate, k, t, h, y, rec)
        if first >= 0:
            dense_eval(tab, theta, h, y, sc, sc.y_dense)
            copy_into(sc.y_dense, y)
            return (GUARD if first == 0 else FELL), t + theta * h
        t = t_stop if clipped else t + h
        copy_into(sc.y_new, y)
        copy_into(sc.k[tab.stages], sc.k[0])
        copy_into(sc.g_new, sc.g_old)
        h *= factor
    return stalled, t
