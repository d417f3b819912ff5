"""The rigid step map compiled: DOP853 with dense output, guards located on it, polish, impact (numba).

One step map for every use of the rigid walkers: a run's steps with pushes, ground profiles and samples
(:func:`rigid_step`, which :mod:`biped_sim.simulate.rigid` takes) and the plain map of limit
cycles, basins, bifurcation and robustness (:func:`rigid_step` without them, :func:`walk_starts`). Its slow
reference is itself run as plain Python (``.py_func`` of each kernel), which gives the same bits (a test); a test
also integrates the kneed walker's phases with scipy's ``solve_ivp`` to the same strike (1e-10). A phase's
integration is :mod:`biped_sim.rigid.integration`'s:

* the flow of :mod:`biped_sim.rigid.kernels` is integrated by DOP853 at rtol = atol = 1e-12 with scipy's
  step-size control (Hairer's norm, safety 0.9, factors 0.2..10, no growth after a rejection), from
  Hairer's starting step; the tableau, the stage arithmetic, the error norm, the step-size controller and the
  dense-output evaluation are the compliant loop's (:mod:`biped_sim.integrate`); the three extra dense-output stages
  are computed here because they call the rigid flow;
* after each accepted step the guard of the phase (downward zero) and the fall functions (any zero) are
  compared with their values at the step's start; the earliest crossing is located on the degree-7 dense
  output by the Illinois variant of regula falsi, to 4 machine epsilon in time (scipy: brentq);
* a located guard is polished by Newton along the flow, dt = -g / (dg/dt), x += dt f(x + dt f / 2), until
  |g| <= 1e-14 (the profile's guard, which has no analytic rate at the profile's vertices, by central
  differences);
* a fall (a leg past the fall angle, the hip below 0.05 l) or a stall (no strike within ``MAX_STEP_TIME``
  natural periods, or a step below ``MIN_STEP``) ends the step with a status.

A step's plan (:class:`StepPlan`, empty for the plain map) and what it did (:class:`StepRecord`,
preallocated buffers and counts) travel in the :class:`CompiledWalker`:

* pushes: the flow stops at each push time before the step ends, :func:`~biped_sim.rigid.tree_kernels.tree_push`
  makes the velocity jump on the hip and the same phase goes on, restarted as scipy restarts ``solve_ivp``
  (a fresh starting step); each is booked as (t, work = the kinetic energy's jump, the ground's normal impulse);
* a ground profile (:mod:`biped_sim.rigid.ground`): the walker's last phase gives way to the swing foot leaving
  its mid-stance scuff (the plane's strike guard turning positive) and then its clearance above the profile; a
  foot below the profile when that strike is first sought, or a strike located at a riser below its top, ends
  the step ``tripped``;
* samples on the grid k / sample_rate of the step's clock, from the dense output of the accepted steps (whatever
  the step's outcome); stop strikes as (t, the kinetic energy lost).

The kernels of the step map count no references (``kernel(reference_counts=False)``: they allocate nothing, and
the walker's tuple of some thirty arrays would otherwise be counted at every call); the guard and event functions
are inlined into the integration loop for the same reason.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from biped_sim.integrate.stepper import make_scratch
from biped_sim.integrate.tableaus import tableau
from biped_sim.kernel import Kernel, kernel
from biped_sim.rigid.ground import RISER_TOLERANCE, ProfileStrike, riser_hit, tree_swing_foot
from biped_sim.rigid.integration import (
    APPLIED,
    N_EVENTS,
    ON_PROFILE,
    OUT,
    OWN,
    REACHED,
    STALLED,
    STATUS_NAMES,
    STOPS,
    STRIKE,
    TRIPPED,
    CompiledWalker,
    StepPlan,
    StepRecord,
    copy_into,
    phase_guard,
    polish,
    stretch,
)
from biped_sim.rigid.integration import FELL as FELL  # re-exported with the other statuses of a step
from biped_sim.rigid.kernels import (
    n_phases,
)
from biped_sim.rigid.step import MAX_STEP_TIME, RigidStep
from biped_sim.rigid.tree import RigidWalker
from biped_sim.rigid.tree_kernels import STOP as STOP_PHASE
from biped_sim.rigid.tree_kernels import after_phase, begin_step, skip_phase, tree_energy, tree_impact, tree_push
from biped_sim.rigid.tree_layout import gravity_vector

DEGENERATE_STEP = 1e-9  # a walk's step shorter than this fraction of the step time limit is no step (a stall)


def with_slope(cw: CompiledWalker, slope: float) -> CompiledWalker:
    """``cw`` on a ground of another slope (the buffers are shared): the step of a walk on ground whose slope
    changes from step to step."""
    gx, gy = gravity_vector(math.hypot(cw.params.gx, cw.params.gy), slope)
    return cw._replace(params=cw.params._replace(gx=gx, gy=gy))


def _empty_plan() -> StepPlan:
    """The plain step's plan: no pushes, the walker's own strike guard, no samples."""
    return StepPlan(np.zeros(0), np.zeros((0, 2)), False, np.zeros((0, 2)), np.zeros(2), np.zeros(2), 0.0)


def _record(ny: int, n_pushes: int, n_samples: int, n_stops: int) -> StepRecord:
    return StepRecord(
        np.zeros(3, dtype=np.int64), np.zeros((n_pushes, 3)), np.zeros(n_samples), np.zeros((n_samples, ny)),
        np.zeros(n_samples), np.zeros((n_stops, 2)), np.zeros(1), np.zeros(1),
    )  # fmt: skip


def compile_walker(walker: RigidWalker) -> CompiledWalker:
    """The kernels' view of ``walker`` and fresh buffers (one per thread of work), with the plain step's plan."""
    params = walker.params.copy()  # a copy: the kernels keep their workspace and the locks' state in it
    ny = 2 * walker.n_q
    t_limit = MAX_STEP_TIME * math.sqrt(walker.leg_length / walker.gravity)
    scratch = make_scratch(ny, 1, N_EVENTS)
    record = _record(ny, 0, 0, len(params.phases))
    return CompiledWalker(params, tableau("dop853"), scratch, t_limit, _empty_plan(), record)


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def _push(cw: CompiledWalker, t: float, y: np.ndarray) -> None:
    """The next push's velocity jump on y (in place, through sc.y_new) and its record (t, work, normal impulse)."""
    p, rec, plan = cw.params, cw.record, cw.plan
    i = rec.counts[APPLIED]
    before, _ = tree_energy(p, y)
    normal = tree_push(p, y, plan.push_impulses[i, 0], plan.push_impulses[i, 1], cw.sc.y_new)
    copy_into(cw.sc.y_new, y)
    after, _ = tree_energy(p, y)
    rec.pushes[i, 0], rec.pushes[i, 1], rec.pushes[i, 2] = t, after - before, normal
    rec.counts[APPLIED] = i + 1


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def _phase(cw: CompiledWalker, phase: int, mode: int, t: float, y: np.ndarray, counters: np.ndarray):
    """Integrate from (t, y) to the phase's guard, a fall or the time limit, stopping at each pending push (one at or
    before t applies at once) for its jump; y ends at the event (in place)."""
    plan, rec = cw.plan, cw.record
    while True:
        pending = rec.counts[APPLIED] < plan.push_times.shape[0]
        t_stop = min(plan.push_times[rec.counts[APPLIED]], cw.t_limit) if pending else cw.t_limit
        if t_stop > t:
            status, t = stretch(cw, phase, mode, t, t_stop, y, counters)
            if status != REACHED:
                return status, t
        elif not pending:
            return STALLED, t
        _push(cw, t, y)


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def _end_phase(cw: CompiledWalker, phase: int, t: float, x: np.ndarray, scratch: np.ndarray) -> None:
    """After a phase's guard: a stop strike (x in place), booked with its loss when there is room."""
    p, rec = cw.params, cw.record
    struck = p.phases[phase].kind == STOP_PHASE
    n = rec.counts[STOPS]
    if not struck or n >= rec.stops.shape[0]:
        after_phase(p, phase, x, scratch)
        return
    before, _ = tree_energy(p, x)
    after_phase(p, phase, x, scratch)
    after, _ = tree_energy(p, x)
    rec.stops[n, 0], rec.stops[n, 1] = t, before - after
    rec.counts[STOPS] = n + 1


@njit(cache=True, inline="always")  # inlined: a kernel of its own would emit the flow's code again
def _tripped(cw: CompiledWalker, x: np.ndarray) -> bool:
    """The swing foot's lowest point at a riser's x, below its top (the profile's strike located there)."""
    plan = cw.plan
    foot_x, foot_y = tree_swing_foot(cw.params, x, plan.footing[0], plan.footing[1])
    return riser_hit(foot_x, foot_y, plan.vertices, RISER_TOLERANCE * cw.params.leg_length)


@kernel(reference_counts=False)
def step_kernel(cw: CompiledWalker, x_start: np.ndarray, x_minus: np.ndarray, x_plus: np.ndarray, counters: np.ndarray):
    """One step from a post-impact state: (status, duration); x_minus = the state at its end, x_plus after
    the strike (meaningful only if the status is STRIKE: a stop strike uses it as scratch). ``cw.plan`` says
    what else the step does, ``cw.record`` gets what it did (reset here).

    On a profile the walker's last phase (the plane's strike) gives way to two: the swing foot out of its
    mid-stance scuff (the plane's strike guard turning positive; skipped if it already is), then the clearance
    above the profile; a swing foot already below the profile by RISER_TOLERANCE l then, or a strike located at a
    riser, ends the step TRIPPED."""
    p, plan = cw.params, cw.plan
    copy_into(x_start, x_minus)
    for i in range(cw.record.counts.shape[0]):  # not a slice assignment: its shape check's message compiles
        cw.record.counts[i] = 0
    cw.record.work[0] = 0.0
    t = 0.0
    begin_step(p)
    last = n_phases(p) - 1
    for phase in range(last + 2 if plan.on_profile else last + 1):
        own = min(phase, last)
        mode = OWN if phase < last or not plan.on_profile else (OUT if phase == last else ON_PROFILE)
        if mode == OWN and skip_phase(p, own, x_minus):
            continue
        if mode == OUT and phase_guard(cw, own, mode, x_minus) <= 0.0:
            continue  # the swing foot is already past its mid-stance scuff
        if mode == ON_PROFILE and phase_guard(cw, own, mode, x_minus) < -RISER_TOLERANCE * p.leg_length:
            return TRIPPED, t  # below the profile: in a riser
        status, t = _phase(cw, own, mode, t, x_minus, counters)
        if status != STRIKE:
            return status, t
        if mode == ON_PROFILE and _tripped(cw, x_minus):
            return TRIPPED, t
        t = polish(cw, own, mode, t, x_minus, counters)
        _end_phase(cw, own, t, x_minus, x_plus)
    landing_x, _ = tree_swing_foot(p, x_minus, 0.0, 0.0)
    cw.record.length[0] = landing_x - (-p.radius * x_start[p.rolling[0]])  # from the stance contact (contact_point)
    tree_impact(p, x_minus, True, x_plus)
    return STRIKE, t


@kernel
def _finite(x: np.ndarray) -> bool:
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            return False
    return True


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
        copy_into(starts[n], last[n])
        status[n], steps[n] = STRIKE, 0
        for k in range(max_steps):
            code, duration = step_kernel(cw, last[n], x_minus, x_plus, counters)
            if code == STRIKE and duration < DEGENERATE_STEP * cw.t_limit:
                code = STALLED  # a strike in no time: the start sits on the guard (legs together), no step
            if code != STRIKE or not _finite(x_plus):
                status[n] = code if code != STRIKE else STALLED
                break
            copy_into(x_plus, last[n])
            steps[n] = k + 1


def with_plan(
    cw: CompiledWalker,
    sample_rate: float | None = None,
    pushes: Sequence[tuple[float, np.ndarray]] = (),
    profile: ProfileStrike | None = None,
) -> CompiledWalker:
    """``cw`` with a step's plan (pushes, profile, samples) and a record sized for it (the other buffers shared).

    The sample buffer holds a whole step's grid, t in [0, t_limit], and one more point per phase (a polish that
    moves a strike back repeats a grid point, as the reference's restart does)."""
    n = len(pushes)
    times = np.array([float(at) for at, _ in pushes])
    impulses = np.array([np.asarray(impulse, dtype=float)[:2] for _, impulse in pushes]).reshape(n, 2)
    vertices, ends, footing = cw.plan.vertices, cw.plan.ends, cw.plan.footing
    if profile is not None:
        vertices = np.ascontiguousarray(profile.ground.vertices, dtype=float).reshape(-1, 2)
        ends = np.ascontiguousarray(profile.ground.ends, dtype=float)
        footing = np.array([profile.footing.origin, profile.footing.level])
    rate = 0.0 if sample_rate is None else float(sample_rate)
    n_phases = cw.record.stops.shape[0]
    n_samples = math.floor(cw.t_limit * rate) + n_phases + 3 if rate > 0.0 else 0
    plan = StepPlan(times, impulses, profile is not None, vertices, ends, footing, rate)
    return cw._replace(plan=plan, record=_record(cw.sc.y_new.shape[0], n, n_samples, n_phases))


_ENTRIES: OrderedDict[int, tuple[CompiledWalker, Callable[..., Any]]] = OrderedDict()  # id(cw): cw, its entry
_KEPT_ENTRIES = 16  # the walkers whose plain step's entry is kept (a study's threads, each with its own buffers)


def step_entry(cw: CompiledWalker, x0: np.ndarray, counters: np.ndarray) -> Callable[..., Any]:
    """:func:`step_kernel`'s compiled entry for ``cw``'s types, found once per ``cw`` (held here, so that its id is
    not reused): a plain step called with the same buffers again and again (limit cycles, basins, the bench, walks
    on random slopes through :func:`with_slope`'s walkers of the same types) skips numba's typing of the walker's and
    the buffers' arrays at every call. The states are 1-d, contiguous, writable."""
    if not isinstance(step_kernel, Kernel):  # run as plain Python (a reference test)
        return step_kernel
    found = _ENTRIES.get(id(cw))
    if found is None:
        found = cw, step_kernel.entry_for(cw, x0, x0, x0, counters)
        _ENTRIES[id(cw)] = found
        while len(_ENTRIES) > _KEPT_ENTRIES:
            _ENTRIES.popitem(last=False)
    return found[1]


def rigid_step(
    walker: RigidWalker,
    x_start: np.ndarray,
    sample_rate: float | None = None,
    pushes: Sequence[tuple[float, np.ndarray]] = (),
    profile: ProfileStrike | None = None,
    cw: CompiledWalker | None = None,
) -> RigidStep:
    """One step from a post-impact state (``cw`` reuses the buffers of :func:`compile_walker`; without pushes,
    profile or samples the step runs on them as they are, the step map of limit cycles and basins).

    The samples fall on the grid k / sample_rate of the step's clock and are kept whatever the step's outcome;
    ``pushes`` (time on the step's clock, impulse on the hip) in time order; ``profile``: the strike on a ground
    profile. A strike in no time (the start on the guard: legs together) is a stall, as in walks.
    """
    cw = cw or compile_walker(walker)
    planned = sample_rate is not None or pushes or profile is not None
    if planned:
        cw = with_plan(cw, sample_rate, pushes, profile)
    x0 = np.array(x_start, dtype=float)  # a copy: C-contiguous and writable, as the step kernel's entry takes it
    x_minus, x_plus = np.zeros_like(x0), np.zeros_like(x0)
    counters = np.zeros(2, dtype=np.int64)
    run = step_kernel if planned or x0.ndim != 1 else step_entry(cw, x0, counters)
    code, period = run(cw, x0, x_minus, x_plus, counters)
    if code == STRIKE and period < DEGENERATE_STEP * cw.t_limit:
        code = STALLED
    strike, rec = code == STRIKE, cw.record
    length = float(rec.length[0]) if strike else math.nan
    evals, accepted = counters.tolist()
    step = RigidStep(STATUS_NAMES[code], x0, x_minus, x_plus if strike else None, period, length, evals,
                     accepted_steps=accepted)  # fmt: skip
    applied, sampled, stops = rec.counts.tolist()
    if applied:  # the record read only where it holds something: a plain step costs no more than before
        step.pushes = [tuple(row) for row in rec.pushes[:applied].tolist()]
    if sampled:
        step.samples_t, step.samples_x = rec.samples_t[:sampled].copy(), rec.samples_x[:sampled].copy()
        step.samples_work = rec.samples_w[:sampled].copy()
    step.element_work = float(rec.work[0])
    if stops:
        step.stop_strikes = [tuple(row) for row in rec.stops[:stops].tolist()]
    return step


def walk_starts(walker: RigidWalker, starts: np.ndarray, max_steps: int) -> WalkOutcome:
    """Walk every start (rows: post-impact states) up to ``max_steps`` strikes, compiled."""
    starts = np.ascontiguousarray(starts, dtype=float)
    n = starts.shape[0]
    out = WalkOutcome(
        np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), np.zeros_like(starts), np.zeros(2, dtype=np.int64)
    )
    walk_kernel(compile_walker(walker), starts, max_steps, out, np.zeros(starts.shape[1]), np.zeros(starts.shape[1]))
    return out
