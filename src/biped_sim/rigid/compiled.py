"""The rigid step map compiled: DOP853 with dense output, guards located on it, polish, impact (numba).

The same algorithm as :func:`biped_sim.rigid.stepping.rigid_step`, which stays the slow reference (scipy's
``solve_ivp``; the tests check that fixed points and multipliers agree to 1e-10), for maps of thousands
of starts (limit cycles, basins of attraction):

* the flow of :mod:`biped_sim.rigid.kernels` is integrated by DOP853 at rtol = atol = 1e-12 with scipy's
  step-size control (Hairer's norm, safety 0.9, factors 0.2..10, no growth after a rejection), from
  Hairer's starting step; the tableau, the stage arithmetic, the error norm and the dense-output
  evaluation are the compliant loop's (:mod:`biped_sim.integrate`); the three extra dense-output stages
  are computed here because they call the rigid flow;
* after each accepted step the guard of the phase (downward zero) and the fall functions (any zero) are
  compared with their values at the step's start; the earliest crossing is located on the degree-7 dense
  output by the Illinois variant of regula falsi, to 4 machine epsilon in time (scipy: brentq);
* a located guard is polished by Newton along the flow, dt = -g / (dg/dt), x += dt f(x + dt f / 2), until
  |g| <= 1e-14 (the reference differentiates g by central differences: the same step to round-off);
* a fall (a leg past the fall angle, the hip below 0.05 l) or a stall (no strike within ``MAX_STEP_TIME``
  natural periods, or a step below ``MIN_STEP``) ends the step with a status.
"""

from __future__ import annotations

import math
from typing import NamedTuple

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
)
from biped_sim.integrate.tableaus import Tableau, tableau
from biped_sim.kernel import kernel
from biped_sim.rigid.kernels import (
    TREE,
    end_phase,
    fall_check,
    first_phase,
    guard,
    guard_rate,
    n_fall_checks,
    n_phases,
    phase_skipped,
    rigid_impact,
    rigid_rhs,
    start_step,
)
from biped_sim.rigid.stepping import ATOL, GUARD_TOLERANCE, MAX_STEP_TIME, RTOL, RigidStep
from biped_sim.rigid.tree import RigidWalker
from biped_sim.rigid.tree_layout import P_GX, P_GY, gravity_vector

STRIKE, FELL, STALLED = 0, 1, 2
STATUS_NAMES = ("strike", "fell", "stalled")
MIN_STEP = 1e-14  # a smaller step means the flow cannot be integrated: the step counts as a stall
ROOT_TOL = 4.0 * np.finfo(float).eps  # relative width of the final bracket of an event time
N_EVENTS = 4  # the guard, and at most three fall functions (two legs, the hip)
DEGENERATE_STEP = 1e-9  # a walk's step shorter than this fraction of the step time limit is no step (a stall)


class CompiledWalker(NamedTuple):
    """A rigid walker as the kernels read it, with the integration's buffers."""

    kind: int
    params: np.ndarray
    tab: Tableau
    sc: Scratch
    q_work: np.ndarray  # (4,) scratch of the impact map
    t_limit: float  # a step longer than this stalls


def walker_params(walker: RigidWalker) -> tuple[int, np.ndarray]:
    """(kind, parameter vector) of a rigid walker: a copy (the kernels keep their workspace in it)."""
    return TREE, walker.params.copy()


def with_slope(cw: CompiledWalker, slope: float) -> CompiledWalker:
    """``cw`` on a ground of another slope (a copy of the parameters; the buffers are shared): the step of a
    walk on ground whose slope changes from step to step."""
    params = cw.params.copy()
    params[P_GX], params[P_GY] = gravity_vector(math.hypot(params[P_GX], params[P_GY]), slope)
    return cw._replace(params=params)


def compile_walker(walker: RigidWalker) -> CompiledWalker:
    """The kernels' view of ``walker`` and fresh buffers (one per thread of work)."""
    kind, params = walker_params(walker)
    ny = 2 * walker.n_q
    t_limit = MAX_STEP_TIME * math.sqrt(walker.leg_length / walker.gravity)
    return CompiledWalker(kind, params, tableau("dop853"), make_scratch(ny, 1, N_EVENTS), np.zeros(4), t_limit)


@kernel
def _events(kind: int, p: np.ndarray, phase: int, y: np.ndarray, out: np.ndarray) -> int:
    """out[0] = the phase's guard, out[1:] = the fall functions; returns how many were written."""
    out[0] = guard(kind, p, phase, y)
    n = n_fall_checks(kind, p)
    for i in range(n):
        out[1 + i] = fall_check(kind, p, i, y)
    return n + 1


@kernel
def _crossed(j: int, g_old: float, g_new: float) -> bool:
    """Event j crossed over the step: the guard (j = 0) downward only, a fall function either way (as scipy)."""
    down = g_old >= 0.0 and g_new <= 0.0
    return down if j == 0 else down or (g_old <= 0.0 and g_new >= 0.0)


@kernel
def _initial_step(kind: int, p: np.ndarray, tab: Tableau, sc: Scratch, y: np.ndarray, span: float) -> float:
    """Hairer, Norsett & Wanner's starting step (as scipy's select_initial_step); uses k[0] = f(y)."""
    h0, d1 = initial_step_trial(y, sc, RTOL, ATOL, span)
    rigid_rhs(kind, p, sc.y_stage, sc.k[1])
    return initial_step_size(tab, sc, h0, d1, span)


@kernel
def _prepare_dense(kind: int, p: np.ndarray, tab: Tableau, h: float, y: np.ndarray, sc: Scratch) -> None:
    """DOP853's dense-output coefficients of the last step (three extra stages of the rigid flow)."""
    for e in range(3):
        rigid_rhs(kind, p, sc.y_stage, sc.k[dop853_extra_stage_input(tab, h, y, sc, e)])
    dop853_coefficients(tab, h, y, sc)


@kernel
def _event_value(kind: int, p: np.ndarray, phase: int, j: int, y: np.ndarray) -> float:
    return guard(kind, p, phase, y) if j == 0 else fall_check(kind, p, j - 1, y)


@kernel
def _root(kind: int, p: np.ndarray, tab: Tableau, sc: Scratch, phase: int, j: int, t: float, h: float, y: np.ndarray):
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
        g = _event_value(kind, p, phase, j, sc.y_dense)
        same_sign = (g > 0.0) == (g_lo > 0.0) and g != 0.0
        lo, hi, g_lo, g_hi, side = illinois_update(lo, hi, g_lo, g_hi, side, mid, g, same_sign)
    return lo if abs(g_lo) < abs(g_hi) else hi


@kernel
def _phase(cw: CompiledWalker, phase: int, t: float, y: np.ndarray, counters: np.ndarray) -> tuple[int, float]:
    """Integrate from (t, y) to the phase's guard, a fall or the time limit; y ends at the event (in place)."""
    kind, p, tab, sc = cw.kind, cw.params, cw.tab, cw.sc
    expo = -1.0 / (tab.error_order + 1)
    rigid_rhs(kind, p, y, sc.k[0])
    h = _initial_step(kind, p, tab, sc, y, cw.t_limit - t)
    counters[0] += 2
    n_ev = _events(kind, p, phase, y, sc.g_old)
    rejected = False
    while t < cw.t_limit:
        h = min(h, cw.t_limit - t)
        if h < MIN_STEP:
            return STALLED, t
        for s in range(1, tab.stages):
            stage_input(tab.a, s, h, y, sc.k, sc.y_stage)
            rigid_rhs(kind, p, sc.y_stage, sc.k[s])
        finite = propagate(tab.b, tab.stages, h, y, sc.k, sc.y_new)
        rigid_rhs(kind, p, sc.y_new, sc.k[tab.stages])
        counters[0] += tab.stages
        err = error_norm(tab, h, y, sc, RTOL, ATOL) if finite else math.inf
        if not err < 1.0:
            h *= max(0.2, 0.9 * err**expo) if math.isfinite(err) else 0.2
            rejected = True
            continue
        factor = 10.0 if err == 0.0 else min(10.0, 0.9 * err**expo)
        if rejected:
            factor = min(1.0, factor)
        rejected = False
        counters[1] += 1
        _events(kind, p, phase, sc.y_new, sc.g_new)
        best, first = 2.0, -1
        for j in range(n_ev):
            if _crossed(j, sc.g_old[j], sc.g_new[j]):
                if first < 0:  # the first crossing of this step: the dense output is needed
                    _prepare_dense(kind, p, tab, h, y, sc)
                    counters[0] += 3
                theta = _root(kind, p, tab, sc, phase, j, t, h, y)
                if theta < best:
                    best, first = theta, j
        if first >= 0:
            dense_eval(tab, best, h, y, sc, sc.y_dense)
            y[:] = sc.y_dense
            return (STRIKE if first == 0 else FELL), t + best * h
        t += h
        y[:] = sc.y_new
        sc.k[0, :] = sc.k[tab.stages]
        sc.g_old[:] = sc.g_new
        h *= factor
    return STALLED, t


@kernel
def _polish(cw: CompiledWalker, phase: int, t: float, x: np.ndarray, counters: np.ndarray) -> float:
    """Newton on the guard along the flow: dt = -g / (dg/dt), x += dt f(x + dt f / 2); returns the new t."""
    kind, p, sc = cw.kind, cw.params, cw.sc
    f, f_mid = sc.k[1], sc.k[2]
    for _ in range(4):
        g = guard(kind, p, phase, x)
        if abs(g) <= GUARD_TOLERANCE:
            break
        rigid_rhs(kind, p, x, f)
        rate = guard_rate(kind, p, phase, x, f)
        if rate == 0.0:
            break
        dt = -g / rate
        for i in range(x.shape[0]):
            sc.y_stage[i] = x[i] + 0.5 * dt * f[i]
        rigid_rhs(kind, p, sc.y_stage, f_mid)
        counters[0] += 2
        for i in range(x.shape[0]):
            x[i] += dt * f_mid[i]
        t += dt
    return t


@kernel
def _copy(source: np.ndarray, target: np.ndarray) -> None:
    """target[:] = source, element by element (a slice assignment may allocate: no reference counts here)."""
    for i in range(source.shape[0]):
        target[i] = source[i]


@kernel
def _finite(x: np.ndarray) -> bool:
    for v in x:
        if not math.isfinite(v):
            return False
    return True


@kernel(reference_counts=False)
def step_kernel(cw: CompiledWalker, x_start: np.ndarray, x_minus: np.ndarray, x_plus: np.ndarray, counters: np.ndarray):
    """One step from a post-impact state: (status, duration); x_minus = the state at its end, x_plus after
    the strike (meaningful only if the status is STRIKE: a stop strike uses it as scratch)."""
    _copy(x_start, x_minus)
    t = 0.0
    start_step(cw.kind, cw.params)
    for phase in range(first_phase(cw.kind), n_phases(cw.kind, cw.params)):
        if phase_skipped(cw.kind, cw.params, phase, x_minus):
            continue
        status, t = _phase(cw, phase, t, x_minus, counters)
        if status != STRIKE:
            return status, t
        t = _polish(cw, phase, t, x_minus, counters)
        end_phase(cw.kind, cw.params, phase, x_minus, x_plus)
    rigid_impact(cw.kind, cw.params, x_minus, cw.q_work, x_plus)
    return STRIKE, t


class WalkOutcome(NamedTuple):
    """Per start of :func:`walk_starts`: status code (STRIKE: walked every step), strikes, last post-impact state;
    the evaluation and accepted-step counters of them all."""

    status: np.ndarray
    steps: np.ndarray
    last: np.ndarray
    counters: np.ndarray


@kernel(reference_counts=False)
def walk_kernel(
    cw: CompiledWalker, starts: np.ndarray, max_steps: int, out: WalkOutcome, x_minus: np.ndarray, x_plus: np.ndarray
) -> None:
    """Walk each start (a row of ``starts``) up to ``max_steps`` strikes; per start: the final status (STRIKE:
    walked them all), the strikes taken and the last post-impact state (the start if none). A strike that takes
    no time (the legs together at the start: the guard is already zero) ends the walk as a stall."""
    status, steps, last, counters = out.status, out.steps, out.last, out.counters
    for n in range(starts.shape[0]):
        _copy(starts[n], last[n])
        status[n], steps[n] = STRIKE, 0
        for k in range(max_steps):
            code, duration = step_kernel(cw, last[n], x_minus, x_plus, counters)
            if code == STRIKE and duration < DEGENERATE_STEP * cw.t_limit:
                code = STALLED  # a strike in no time: the start sits on the guard (legs together), no step
            if code != STRIKE or not _finite(x_plus):
                status[n] = code if code != STRIKE else STALLED
                break
            _copy(x_plus, last[n])
            steps[n] = k + 1


def compiled_step(walker: RigidWalker, x_start: np.ndarray, cw: CompiledWalker | None = None) -> RigidStep:
    """:func:`~biped_sim.rigid.stepping.rigid_step` without samples, compiled (``cw`` reuses buffers)."""
    cw = cw or compile_walker(walker)
    x0 = np.asarray(x_start, dtype=float)
    x_minus, x_plus = np.zeros_like(x0), np.zeros_like(x0)
    counters = np.zeros(2, dtype=np.int64)
    code, period = step_kernel(cw, x0, x_minus, x_plus, counters)
    if code == STRIKE and period < DEGENERATE_STEP * cw.t_limit:
        code = STALLED  # as in walk_kernel: a strike in no time is no step (the start sits on the guard)
    if code != STRIKE:
        return RigidStep(
            STATUS_NAMES[code], x0, x_minus, None, period, math.nan, int(counters[0]), accepted_steps=int(counters[1])
        )
    length = walker.step_length(x0, x_minus)
    return RigidStep("strike", x0, x_minus, x_plus, period, length, int(counters[0]), accepted_steps=int(counters[1]))


def walk_starts(walker: RigidWalker, starts: np.ndarray, max_steps: int) -> WalkOutcome:
    """Walk every start (rows: post-impact states) up to ``max_steps`` strikes, compiled."""
    starts = np.ascontiguousarray(starts, dtype=float)
    n = starts.shape[0]
    out = WalkOutcome(
        np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), np.zeros_like(starts), np.zeros(2, dtype=np.int64)
    )
    walk_kernel(compile_walker(walker), starts, max_steps, out, np.zeros(starts.shape[1]), np.zeros(starts.shape[1]))
    return out
