"""One phase of a rigid step integrated, compiled: DOP853 with dense output, its events located, samples (numba).

The integration that :mod:`biped_sim.rigid.compiled`'s step map runs phase after phase, and the step's data it
reads and writes (:class:`CompiledWalker`: the walker, the integration's buffers, the step's :class:`StepPlan`
and :class:`StepRecord`). :func:`stretch` integrates from a state to the phase's guard, a fall or a stop time (a
push's, or the step's time limit), sampling on the way; :func:`polish` moves a located guard onto its zero. The
algorithm (scipy's DOP853, the events, Newton's polish) is described in :mod:`biped_sim.rigid.compiled`.

The joint elements' dissipated work (their dampers') is integrated with the flow, as if it were one more state
that nothing feeds back on: over an accepted step by the step's own quadrature (DOP853's weights on the power at
its stages), up to a sample or an event inside the step by Gauss-Legendre on the dense output (8 points: exact
for a polynomial of degree 15, the linear damper's power on the degree-7 dense output), through a polish by its
midpoint rule. So the rigid energy audit closes to the integrator's tolerance at any sampling. It stays out of
the error norm: the states, and every walker's results, are those of the flow alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.integrate.dense import (
    dense_eval,
    dop853_coefficients,
    illinois_point,
    illinois_update,
)
from biped_sim.integrate.stepper import (
    Scratch,
    error_norm,
    initial_step_size,
    initial_step_trial,
    step_factor,
)
from biped_sim.integrate.tableaus import Tableau
from biped_sim.kernel import kernel
from biped_sim.rigid.ground import clearance, tree_swing_foot
from biped_sim.rigid.kernels import (
    DENSE,
    FLOW,
    STAGES,
    element_power,
    fall_check,
    flow_kernel,
    guard,
    guard_rate,
    has_elements,
    n_fall_checks,
)
from biped_sim.rigid.step import ATOL, GUARD_TOLERANCE, RTOL
from biped_sim.rigid.tree_layout import RigidTree

STRIKE, FELL, STALLED, TRIPPED = 0, 1, 2, 3
STATUS_NAMES = ("strike", "fell", "stalled", "tripped")
REACHED = -1  # a stretch of a phase reached its stop time (a push's) before any event
OWN, OUT, ON_PROFILE = 0, 1, 2  # guard modes: the walker's own; the plane's strike guard negated; the profile's
APPLIED, SAMPLED, STOPS = 0, 1, 2  # StepRecord.counts: pushes applied, samples taken, stop strikes
MIN_STEP = 1e-14  # a smaller step means the flow cannot be integrated: the step counts as a stall
ROOT_TOL = 4.0 * np.finfo(float).eps  # relative width of the final bracket of an event time
N_EVENTS = 5  # the guard, and at most four fall functions (two legs, the hip, a torso)
FD_STEP = 1e-7  # the central difference of the profile guard's rate along the flow (as the scipy reference)
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(8)
GAUSS_NODES, GAUSS_WEIGHTS = 0.5 * (_NODES + 1.0), 0.5 * _WEIGHTS  # Gauss-Legendre on [0, 1]


class StepPlan(NamedTuple):
    """What a step takes besides its start state (the kernels only read it); an empty plan is the plain step."""

    push_times: np.ndarray  # (k,) on the step's clock, in time order
    push_impulses: np.ndarray  # (k, 2) on the hip, slope frame
    on_profile: bool  # the strike is sought on the profile below the swing foot (else the walker's own guard)
    vertices: np.ndarray  # (n, 2) the profile's polyline (:func:`biped_sim.contact.profile.profile_arrays`)
    ends: np.ndarray  # (2,) its slopes beyond the polyline
    footing: np.ndarray  # (2,) the stance contact's origin and level (:class:`~biped_sim.rigid.ground.Footing`)
    sample_rate: float  # samples on the grid k / sample_rate of the step's clock; 0: none


class StepRecord(NamedTuple):
    """What a step writes besides its end states: ``counts`` says how many rows of each buffer it filled."""

    counts: np.ndarray  # (3,) int64: pushes applied, samples, stop strikes
    pushes: np.ndarray  # (k, 3): t, work (the kinetic energy's jump), the ground's normal impulse
    samples_t: np.ndarray  # (m,)
    samples_x: np.ndarray  # (m, ny)
    samples_w: np.ndarray  # (m,) the joint elements' dissipated work since the step's start
    stops: np.ndarray  # (s, 2): t, the kinetic energy lost
    work: np.ndarray  # (1,) the joint elements' dissipated work since the step's start, at its end
    length: np.ndarray  # (1,) the step's length: the landing foot's lowest point at the strike from the stance contact


class CompiledWalker(NamedTuple):
    """A rigid walker as the kernels read it, with the integration's buffers and a step's plan and record."""

    params: RigidTree
    tab: Tableau
    sc: Scratch
    t_limit: float  # a step longer than this stalls
    plan: StepPlan
    record: StepRecord


@njit(cache=True, inline="always")
def copy_into(source: np.ndarray, target: np.ndarray) -> None:
    """target = source, element by element (a slice assignment may allocate: not in an uncounted kernel)."""
    for i in range(source.shape[0]):
        target[i] = source[i]


@njit(cache=True, inline="always")  # inlined: a call would count references to every array of cw
def phase_guard(cw: CompiledWalker, phase: int, mode: int, y: np.ndarray) -> float:
    """The guard of the phase in ``mode``: the walker's own, the plane's strike negated (the swing foot leaving
    its mid-stance scuff), or the swing foot's clearance above the profile (a tree walker's)."""
    if mode == OWN:
        return guard(cw.params, phase, y)
    if mode == OUT:
        return -guard(cw.params, phase, y)
    plan = cw.plan
    foot_x, foot_y = tree_swing_foot(cw.params, y, plan.footing[0], plan.footing[1])
    return clearance(foot_x, foot_y, plan.vertices, plan.ends)


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def _guard_rate(cw: CompiledWalker, phase: int, mode: int, x: np.ndarray, f: np.ndarray) -> float:
    """d(guard)/dt along the flow f: analytic for the walker's guards, a central difference (step FD_STEP along f,
    as the scipy reference) for the profile's (sc.k[3] holds the probe)."""
    if mode == OWN:
        return guard_rate(cw.params, phase, x, f)
    if mode == OUT:
        return -guard_rate(cw.params, phase, x, f)
    probe = cw.sc.k[3]
    for i in range(x.shape[0]):
        probe[i] = x[i] + FD_STEP * f[i]
    ahead = phase_guard(cw, phase, mode, probe)
    for i in range(x.shape[0]):
        probe[i] = x[i] - FD_STEP * f[i]
    return (ahead - phase_guard(cw, phase, mode, probe)) / (2.0 * FD_STEP)


@njit(cache=True, inline="always")  # inlined: a call would count references to every array of cw
def _events(cw: CompiledWalker, phase: int, mode: int, y: np.ndarray, out: np.ndarray) -> int:
    """out[0] = the phase's guard, out[1:] = the fall functions; returns how many were written."""
    out[0] = phase_guard(cw, phase, mode, y)
    n = n_fall_checks(cw.params)
    for i in range(n):
        out[1 + i] = fall_check(cw.params, i, y)
    return n + 1


@kernel
def _crossed(j: int, g_old: float, g_new: float) -> bool:
    """Event j crossed over the step: the guard (j = 0) downward only, a fall function either way (as scipy)."""
    down = g_old >= 0.0 and g_new <= 0.0
    return down if j == 0 else down or (g_old <= 0.0 and g_new >= 0.0)


@njit(cache=True, inline="always")  # inlined: a kernel of its own would pass the tree's arrays once more
def _initial_step(p: RigidTree, tab: Tableau, sc: Scratch, y: np.ndarray, span: float) -> float:
    """Hairer, Norsett & Wanner's starting step (as scipy's select_initial_step); uses k[0] = f(y)."""
    h0, d1 = initial_step_trial(y, sc, RTOL, ATOL, span)
    flow_kernel(p, tab, sc, 0.0, sc.y_stage, FLOW, 1, False)
    return initial_step_size(tab, sc, h0, d1, span)


@njit(cache=True, inline="always")  # inlined: a kernel of its own would pass the tree's arrays once more
def _prepare_dense(p: RigidTree, tab: Tableau, h: float, y: np.ndarray, sc: Scratch) -> None:
    """DOP853's dense-output coefficients of the last step (three extra stages of the rigid flow)."""
    flow_kernel(p, tab, sc, h, y, DENSE, 0, False)
    dop853_coefficients(tab, h, y, sc)


@njit(cache=True, inline="always")  # inlined: a call would count references to every array of cw
def _event_value(on: tuple[CompiledWalker, int, int], j: int, y: np.ndarray) -> float:
    """Event j at y for the phase and guard mode of ``on`` = (cw, phase, mode): the guard (j = 0), a fall function."""
    cw, phase, mode = on
    return phase_guard(cw, phase, mode, y) if j == 0 else fall_check(cw.params, j - 1, y)


@njit(cache=True, inline="always")  # inlined: each caller's event function resolved, and inlined if it is, at typing
def event_root(
    value: Callable[..., float], on: tuple, tab: Tableau, sc: Scratch, j: int, t: float, h: float, y: np.ndarray
) -> float:
    """Zero of event j inside the accepted step from (t, y) of length h as theta in [0, 1], on the dense output
    (prepared by the caller) by the Illinois method from the bracket of the event's values sc.g_old[j] at the start
    and sc.g_new[j] at the end, to ROOT_TOL relative in time; returns the end of the final bracket where the event is
    closer to zero. ``value(on, j, x)`` is event j at the state x, ``on`` what else it reads: the one search of the
    planar and the 3D rigid integrations (a jitted function passed as an argument, resolved where this is inlined)."""
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
        g = value(on, j, sc.y_dense)
        same_sign = (g > 0.0) == (g_lo > 0.0) and g != 0.0
        lo, hi, g_lo, g_hi, side = illinois_update(lo, hi, g_lo, g_hi, side, mid, g, same_sign)
    return lo if abs(g_lo) < abs(g_hi) else hi


@kernel
def first_sample(rate: float, t: float) -> int:
    """The first grid index k with k / rate >= t (0 when not sampling)."""
    if rate == 0.0:
        return 0
    k = math.ceil(t * rate)
    while k / rate < t:
        k += 1
    return k


@njit(cache=True, inline="always")  # inlined: a call would count references to every array of cw
def _dense_work(cw: CompiledWalker, theta: float, h: float, y: np.ndarray) -> float:
    """The joint elements' dissipated work over [t, t + theta h] of the last accepted step (from (t, y), length h):
    Gauss-Legendre on its dense output, prepared by the caller (sc.y_dense holds the nodes' states)."""
    sc = cw.sc
    total = 0.0
    for i in range(GAUSS_NODES.shape[0]):
        dense_eval(cw.tab, theta * GAUSS_NODES[i], h, y, sc, sc.y_dense)
        total += GAUSS_WEIGHTS[i] * element_power(cw.params, sc.y_dense)
    return theta * h * total


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def _sample(cw: CompiledWalker, k: int, t: float, h: float, t_end: float, y: np.ndarray, elements: bool) -> int:
    """Record the grid points k / rate in [t, t_end) of the last accepted step (from (t, y), length h) on its dense
    output, prepared by the caller, with the elements' work (``elements``: the walker has some); returns the next
    grid index. The buffer is sized for a step's whole grid."""
    rate, rec = cw.plan.sample_rate, cw.record
    n = rec.counts[SAMPLED]
    while k / rate < t_end and n < rec.samples_t.shape[0]:
        rec.samples_t[n] = k / rate
        dense_eval(cw.tab, (k / rate - t) / h, h, y, cw.sc, rec.samples_x[n])
        rec.samples_w[n] = rec.work[0] + (_dense_work(cw, (k / rate - t) / h, h, y) if elements else 0.0)
        n += 1
        k += 1
    rec.counts[SAMPLED] = n
    return k


@kernel(reference_counts=False)
def stretch(
    cw: CompiledWalker, phase: int, mode: int, t: float, t_stop: float, y: np.ndarray, counters: np.ndarray
) -> tuple[int, float]:
    """Integrate from (t, y) to the phase's guard, a fall or t_stop (REACHED; STALLED if it is the step's time
    limit), sampling on the way; y ends at the event or at t_stop (in place). A fresh start, as scipy's solve_ivp
    after a push: the starting step, the events' values at the start."""
    p, tab, sc = cw.params, cw.tab, cw.sc
    rate, work = cw.plan.sample_rate, cw.record.work
    elements = has_elements(p)
    k_next = first_sample(rate, t)
    flow_kernel(p, tab, sc, 0.0, y, FLOW, 0, False)
    h = _initial_step(p, tab, sc, y, t_stop - t)
    counters[0] += 2
    n_ev = _events(cw, phase, mode, y, sc.g_old)
    rejected = False
    while t < t_stop:
        clipped = h >= t_stop - t
        h = min(h, t_stop - t)
        if h < MIN_STEP:  # a push's time within MIN_STEP is reached; anything else cannot be integrated
            return (REACHED if clipped and t_stop < cw.t_limit else STALLED), t
        finite, stage_power = flow_kernel(p, tab, sc, h, y, STAGES, 0, elements)  # the work: the step's quadrature
        counters[0] += tab.stages
        err = error_norm(tab, h, y, sc, RTOL, ATOL) if finite else math.inf
        accepted, factor = step_factor(err, tab.error_order, rejected)
        if not accepted:
            h *= factor
            rejected = True
            continue
        rejected = False
        counters[1] += 1
        _events(cw, phase, mode, sc.y_new, sc.g_new)
        best, first = 2.0, -1
        for j in range(n_ev):
            if _crossed(j, sc.g_old[j], sc.g_new[j]):
                if first < 0:  # the first crossing of this step: the dense output is needed
                    _prepare_dense(p, tab, h, y, sc)
                    counters[0] += 3
                theta = event_root(_event_value, (cw, phase, mode), tab, sc, j, t, h, y)
                if theta < best:
                    best, first = theta, j
        t_end = t + best * h if first >= 0 else (t_stop if clipped else t + h)
        if rate > 0.0 and k_next / rate < t_end:
            if first < 0:
                _prepare_dense(p, tab, h, y, sc)
                counters[0] += 3
            k_next = _sample(cw, k_next, t, h, t_end, y, elements)
        if first >= 0:
            if elements:
                work[0] += _dense_work(cw, best, h, y)
            dense_eval(tab, best, h, y, sc, sc.y_dense)
            copy_into(sc.y_dense, y)
            return (STRIKE if first == 0 else FELL), t_end
        work[0] += h * stage_power
        t = t_end
        copy_into(sc.y_new, y)
        copy_into(sc.k[tab.stages], sc.k[0])
        copy_into(sc.g_new, sc.g_old)
        h *= factor
    return (STALLED if t_stop >= cw.t_limit else REACHED), t


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def polish(cw: CompiledWalker, phase: int, mode: int, t: float, x: np.ndarray, counters: np.ndarray) -> float:
    """Newton on the guard along the flow: dt = -g / (dg/dt), x += dt f(x + dt f / 2), the elements' work by the
    same midpoint rule; returns the new t."""
    p, tab, sc = cw.params, cw.tab, cw.sc
    f, f_mid = sc.k[1], sc.k[2]
    for _ in range(4):
        g = phase_guard(cw, phase, mode, x)
        if abs(g) <= GUARD_TOLERANCE:
            break
        flow_kernel(p, tab, sc, 0.0, x, FLOW, 1, False)
        rate = _guard_rate(cw, phase, mode, x, f)
        if rate == 0.0:
            break
        dt = -g / rate
        for i in range(x.shape[0]):
            sc.y_stage[i] = x[i] + 0.5 * dt * f[i]
        flow_kernel(p, tab, sc, 0.0, sc.y_stage, FLOW, 2, False)
        counters[0] += 2
        for i in range(x.shape[0]):
            x[i] += dt * f_mid[i]
        cw.record.work[0] += dt * element_power(p, sc.y_stage)
        t += dt
    return t
