"""Run an integrator on a built model: allocate buffers, call the compiled loop in chunks.

:func:`integrate_model` is the one entry point for every method; the explicit methods run in
the compiled loop of :mod:`biped_sim.integrate.explicit`, ``radau`` and ``bdf`` in
:mod:`biped_sim.integrate.stiff`. Between compiled calls the driver enlarges the contact log and
the strike buffers when one more event might not fit (:func:`~biped_sim.integrate.recorder.with_room`).

Pushes (impulses on the hip at given times) split the integration: the loop runs to the push time
exactly, the formulation's ``hip_impulse`` makes the velocity jump and the same loop resumes from there,
so the recorder holds one continuous trajectory (:func:`apply_push`). Fixed-step methods shorten the step
that reaches a push time and go on at dt from there (their samples then fall off the dt grid of t = 0).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from biped_sim.config import IntegratorConfig
from biped_sim.integrate.blowup import NO_CHECKS, Scales, start_checks
from biped_sim.integrate.explicit import Settings, advance
from biped_sim.integrate.recorder import (
    COMPLETED,
    DIVERGED,
    DIVERGENCE_REASONS,
    FELL,
    RUNNING,
    TIMEOUT,
    Recorder,
    fall_reason,
    make_recorder,
    with_room,
)
from biped_sim.integrate.stepper import Loop, make_scratch
from biped_sim.integrate.tableaus import FIXED, tableau
from biped_sim.multibody.dispatch import contact_buffers, formulation_of, make_workspace, measures
from biped_sim.multibody.events import event_count

FIXED_STEP_METHODS = ("euler", "rk2", "rk4")
STIFF_METHODS = ("radau", "bdf")  # scipy's implicit methods over the compiled right-hand side
TIMEOUT_REASON = "simulation.max_wall_time reached"
STATUS_NAMES = {COMPLETED: "walking", FELL: "fell", DIVERGED: "diverged", TIMEOUT: "timeout"}
STRIKES_PER_SECOND = 50  # the strike buffers' first size per simulated second (they grow; a walker takes ~2)
STEP_BUDGET = 20_000  # steps per compiled call between progress updates (does not change results)
PUSH_COLUMNS = ("time", "first_sample", "work")  # a push record: when, the first sample after it, its work [J]


@dataclass
class Integration:
    """Raw output of one integration (samples, heel strikes, contact events, counters)."""

    status: str
    t_final: float
    stop_time: float | None  # time of the fall, divergence or timeout
    t: np.ndarray
    y: np.ndarray
    modes: np.ndarray
    strike_t: np.ndarray
    strike_foot: np.ndarray
    strike_y: np.ndarray
    strike_modes: np.ndarray
    contact_log: np.ndarray
    rhs_evals: int
    accepted_steps: int
    rejected_steps: int
    events: int
    sample_dt: float
    stop_reason: str | None = None  # why it fell, diverged or timed out
    fall_code: int | None = None  # what fell (the fall kernel's code: recorder.fall_reason), when it fell
    pushes: np.ndarray = field(default_factory=lambda: np.zeros((0, len(PUSH_COLUMNS))))  # applied, PUSH_COLUMNS


def takes_fixed_steps(integrator: IntegratorConfig) -> bool:
    """Whether the integrator steps at ``dt``: euler, rk2, rk4, or any method with step-size control off."""
    return integrator.method in FIXED_STEP_METHODS or not integrator.adaptive


def sample_interval(integrator: IntegratorConfig, sample_rate: float) -> float:
    """Sampling interval; for fixed-step methods a whole number of steps."""
    interval = 1.0 / sample_rate
    if takes_fixed_steps(integrator):
        interval = max(1, round(interval / integrator.dt)) * integrator.dt
    return interval


def recorder_for(
    ny: int,
    nf: int,
    integrator: IntegratorConfig,
    t_end: float,
    sample_rate: float,
    max_strikes: int | None,
    initial_stance_foot: int,
) -> tuple[Recorder, float]:
    """(recorder, sample interval) for an integration to ``t_end`` (samples sized for it; strikes and log grow)."""
    interval = sample_interval(integrator, sample_rate)
    n_samples = math.floor(t_end / interval + 1e-9) + 2
    n_strikes = min(max_strikes or math.inf, int(t_end * STRIKES_PER_SECOND) + 16) + nf  # grown when needed
    return make_recorder(ny, nf, n_samples, n_strikes, initial_stance_foot), interval


def explicit_loop(system: tuple, y: np.ndarray, modes: np.ndarray, method: str, rec: Recorder) -> Loop:
    """What the explicit loop works on for ``system`` from the state (y, modes) by ``method``, recording into ``rec``
    (its tableau, workspace, contact buffers and scratch): a run's, and the argument types of a compile aside."""
    scratch = make_scratch(len(y), len(modes), event_count(system))
    return Loop(tableau(method), system, make_workspace(system), contact_buffers(system), y, modes, scratch, rec)


def integrate_model(
    system: tuple,
    y0: np.ndarray,
    modes0: np.ndarray,
    integrator: IntegratorConfig,
    t_end: float,
    sample_rate: float,
    max_strikes: int | None = None,
    initial_stance_foot: int = 0,
    progress: Callable[[float], None] | None = None,
    deadline: float = math.inf,
    pushes: Sequence[tuple[float, np.ndarray]] = (),
    checks: Scales = NO_CHECKS,
) -> Integration:
    """Integrate ``system`` from (y0, modes0) at t = 0 to ``t_end`` or a stop condition.

    ``deadline``: the ``time.monotonic()`` past which the run stops with status 'timeout'. ``pushes``:
    (time, impulse [px, py]) in time order, each before ``t_end``; the integration stops at each time and
    resumes after :func:`apply_push` (a run that ended earlier, by a fall or max_strikes, skips the rest).
    ``checks``: the walker's units for the blow-up checks (:mod:`~biped_sim.integrate.blowup`; the default
    checks nothing).
    """
    y = np.array(y0, dtype=np.float64)
    modes = np.array(modes0, dtype=np.float64)
    ny, nf = y.shape[0], modes.shape[0]
    rec, interval = recorder_for(ny, nf, integrator, t_end, sample_rate, max_strikes, initial_stance_foot)
    stiff = integrator.method in STIFF_METHODS
    if stiff and checks.energy > 0.0:  # the explicit loop sets the checks' reference itself (compiled, no twin)
        start_checks(rec, system, y, modes)
    if not stiff:
        loop = explicit_loop(system, y, modes, integrator.method, rec)
    applied = []
    for segment_end in [at for at, _ in pushes] + [t_end]:
        if stiff:
            from biped_sim.integrate.stiff import integrate_stiff  # here: scipy.integrate adds 0.3 s to start-up

            rec = integrate_stiff(
                system, rec, y, modes, integrator, segment_end, interval, max_strikes or 0, progress, deadline, checks
            )  # fmt: skip
        else:
            cfg = Settings(
                segment_end, integrator.dt, integrator.adaptive and loop.tab.kind != FIXED, integrator.rtol,
                integrator.atol, integrator.max_step, interval, max_strikes or 0, checks,
            )  # fmt: skip
            loop = loop._replace(rec=rec)
            while loop.rec.state[0].status == RUNNING:
                loop = loop._replace(rec=with_room(loop.rec, nf))
                advance(loop, cfg, STEP_BUDGET)
                if progress is not None:
                    progress(float(loop.rec.state[0].time))
                if loop.rec.state[0].status == RUNNING and time.monotonic() > deadline:
                    stop_for_time(loop.rec)
            rec = loop.rec
        if len(applied) == len(pushes) or not _reached(rec, segment_end, max_strikes):
            break
        applied.append(apply_push(system, y, modes, rec, pushes[len(applied)][1]))
    result = finish_integration(rec, interval, max_strikes)
    result.pushes = np.array(applied, dtype=np.float64).reshape(len(applied), len(PUSH_COLUMNS))
    return result


def _reached(rec: Recorder, segment_end: float, max_strikes: int | None) -> bool:
    """Whether the integration completed by reaching ``segment_end`` (not by max_strikes, a fall or a stop)."""
    st = rec.state[0]
    strikes_done = bool(max_strikes) and st.n_strikes >= max_strikes
    return st.status == COMPLETED and st.time >= segment_end and not strikes_done


def apply_push(system: tuple, y: np.ndarray, modes: np.ndarray, rec: Recorder, impulse: np.ndarray) -> tuple:
    """Apply the impulse on the hip to ``y`` (in place) where the recorder stands and resume its loop.

    The formulation's ``hip_impulse`` makes the jump; the contact modes (armed, touching, the remembered
    impact speed) are kept: a push is not a contact event. Returns the push record (PUSH_COLUMNS): its time,
    the index of the first sample after it (a sample at the push time holds the state before it) and its
    work, the kinetic energy jump (positions do not move, so no other energy changes), which the blow-up
    checks' energy reference takes in.
    """
    formulation = formulation_of(system)
    if formulation.hip_impulse is None:
        raise TypeError(f"the {formulation.name} formulation has no hip impulse (simulation.pushes)")
    energy = measures(system).mechanical_energy
    before = energy(y, system, modes)[0]
    y[:] = formulation.hip_impulse(y, system, np.asarray(impulse, dtype=np.float64))
    work = energy(y, system, modes)[0] - before
    st = rec.state[0]
    st.status = RUNNING
    st.fsal_valid = 0  # the stored first stage f(t, y) is the state's before the jump
    st.energy_reference += work
    return float(st.time), float(st.n_samples), work


def finish_integration(rec: Recorder, interval: float, max_strikes: int | None = None) -> Integration:
    """Copy the filled part of the recorder's buffers into an :class:`Integration`.

    At most ``max_strikes`` heel strikes are reported (an event may strike after the last one counted).
    """
    st = rec.state[0]
    status = int(st.status)
    ns, nk, nl = int(st.n_samples), int(st.n_strikes), int(st.n_log)
    if max_strikes:
        nk = min(nk, max_strikes)
    return Integration(
        status=STATUS_NAMES[status],
        t_final=float(st.time),
        stop_time=float(st.stop_time) if status in (FELL, DIVERGED, TIMEOUT) else None,
        t=rec.sample_t[:ns].copy(),
        y=rec.sample_y[:ns].copy(),
        modes=rec.sample_modes[:ns].copy(),
        strike_t=rec.strike_t[:nk].copy(),
        strike_foot=rec.strike_foot[:nk].copy(),
        strike_y=rec.strike_y[:nk].copy(),
        strike_modes=rec.strike_modes[:nk].copy(),
        contact_log=rec.log[:nl].copy(),
        rhs_evals=int(st.rhs_evals),
        accepted_steps=int(st.accepted),
        rejected_steps=int(st.rejected),
        events=int(st.n_events),
        sample_dt=interval,
        stop_reason=stop_reason(st),
        fall_code=int(st.reason) if status == FELL else None,
    )


def stop_for_time(rec: Recorder) -> None:
    """End a running integration with status TIMEOUT where it stands."""
    st = rec.state[0]
    st.status = TIMEOUT
    st.stop_time = st.time


def stop_reason(st: np.record) -> str | None:
    """Why the integration recorded in ``st`` fell, diverged or timed out (None when it did none of these)."""
    if st.status == TIMEOUT:
        return TIMEOUT_REASON
    if st.status == DIVERGED:
        return DIVERGENCE_REASONS.get(int(st.reason), "the integration failed").format(float(st.excess))
    if st.status == FELL:
        return fall_reason(int(st.reason))
    return None
