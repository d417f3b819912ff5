"""What an integration records, and the bookkeeping every integrator driver shares.

A :class:`Recorder` holds the resumable loop state (``state[0]``: a record of named counters and
flags, ``LOOP_STATE``) and the output buffers: samples, heel strikes and the contact log. The
compiled explicit loop, the scipy event-restart driver and the benchmark's plain-Python baseline
(``.py_func``) all record through :func:`record_sample` and :func:`apply_events`.

The loop state is one numpy record rather than a NamedTuple of 1-element arrays: compiled code reads
and writes its fields in place (``st = rec.state[0]; st.n_samples += 1``), and a record, unlike an
array, costs no reference counting each time the loop hands it to a function.

The sample buffers are sized for the whole run. The contact log and the strike buffers grow: a
driver checks :func:`has_room` before every event (the compiled loop stops when it is false, with
its state saved in the recorder), enlarges them with :func:`with_room` and resumes, which does not
change a bit of the result.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.contact.response import (
    BODY_TOO_FAR,
    HIP_TOO_LOW,
    LEG_TOO_FAR,
    N_MODE_COLUMNS,
    TOUCHDOWN,
    TOUCHING,
    ContactBuffers,
)
from biped_sim.kernel import kernel
from biped_sim.multibody.events import system_approach_velocity, system_is_leading, system_update_modes

# status codes
RUNNING, COMPLETED, FELL, DIVERGED, TIMEOUT = 0, 1, 2, 3, 4
# why a run diverged (LOOP_STATE.reason; the blow-up checks' value is LOOP_STATE.excess)
NONFINITE, MIN_STEP_REACHED, TOO_MANY_FORCED, STEPS_COLLAPSED, EVALUATION_BUDGET, SOLVER_FAILED = 1, 2, 3, 4, 5, 6
ENERGY_RESIDUAL, ENERGY_JUMP, JOINT_DRIFT = 7, 8, 9  # integrate.blowup's checks
EVENT_SEARCH_FAILED = 10  # the stiff driver's: scipy found no root where its step saw an event change sign
BLEW_UP = ": the integration blew up"
DIVERGENCE_REASONS = {
    NONFINITE: "non-finite state",
    MIN_STEP_REACHED: "step size below 1e-13 s",
    TOO_MANY_FORCED: "more than 100000 steps forced across force jumps",
    STEPS_COLLAPSED: "steps averaging below 1e-8 s over 200000 steps: the step-size control is stuck",
    EVALUATION_BUDGET: "right-hand-side evaluation budget exhausted",
    SOLVER_FAILED: "the stiff solver failed (its step size fell below round-off)",
    EVENT_SEARCH_FAILED: "the stiff solver's event search failed (an event function within round-off of zero)",
    ENERGY_RESIDUAL: "energy residual {:.2g} m g l" + BLEW_UP,
    ENERGY_JUMP: "energy error of {:.2g} m g l between two checks (1 ms or one step apart), then a fall" + BLEW_UP,
    JOINT_DRIFT: "joint drift {:.2g} leg lengths" + BLEW_UP,
}
# why a run fell (LOOP_STATE.reason): the codes of the formulations' fall kernels (contact.response)
FALL_REASONS = {
    HIP_TOO_LOW: "the hip below simulation.fall_hip_height leg lengths above the ground",
    LEG_TOO_FAR: "a leg past simulation.fall_leg_angle from the slope normal",
}


def fall_reason(code: int, body_names: list[str] | None = None) -> str | None:
    """Why a run fell, from its fall code: FALL_REASONS, or a body off the legs (BODY_TOO_FAR + its index, named
    from ``body_names`` when given) past its fall angle."""
    if code < BODY_TOO_FAR:
        return FALL_REASONS.get(code)
    body = code - BODY_TOO_FAR
    return body_fall_reason(body_names[body] if body_names is not None and body < len(body_names) else body)


def body_fall_reason(body: str | int) -> str:
    """Why a run fell when a body off the legs (a torso; its name, or its index unnamed) passed its fall angle: the
    one wording of compliant and rigid runs."""
    return f"the body {body!r} (off the legs) past its fall_angle from the slope normal"


LOG_CAPACITY = 4096  # initial rows of the contact log (it grows)
LOG_COLUMNS = 4  # time, foot, +1 touchdown / -1 lift-off, approach velocity deltadot
LOOP_STATE = np.dtype(
    [
        ("time", np.float64),  # [s] where the integration stands
        ("step", np.float64),  # [s] next step size of an adaptive method (0: not chosen yet)
        ("stop_time", np.float64),  # [s] time of the fall or divergence
        ("status", np.int64),  # RUNNING, COMPLETED, FELL, DIVERGED or TIMEOUT
        ("reason", np.int64),  # why it diverged (DIVERGENCE_REASONS) or fell (FALL_REASONS), 0 otherwise
        ("n_samples", np.int64),  # samples recorded
        ("n_strikes", np.int64),  # heel strikes recorded
        ("n_log", np.int64),  # contact-log rows recorded
        ("rhs_evals", np.int64),  # right-hand-side evaluations
        ("accepted", np.int64),  # accepted steps
        ("rejected", np.int64),  # steps rejected by error control
        ("forced", np.int64),  # tiny steps accepted whatever their error (explicit loop)
        ("n_events", np.int64),  # event updates that changed a contact mode
        ("last_strike_foot", np.int64),  # foot of the last heel strike (bounces of it are not strikes)
        ("fsal_valid", np.int64),  # 1 when the stored first stage f(t, y) is current (explicit loop)
        # the blow-up checks (integrate.blowup)
        ("energy_reference", np.float64),  # [J] E(0) + W(0) + the pushes' work so far: residual = E + W - this
        ("check_time", np.float64),  # [s] the first accepted step from here on is checked
        ("check_residual", np.float64),  # [m g l] the energy residual at the last check
        ("jump_time", np.float64),  # [s] the first check that saw a jump of the residual (-1: none)
        ("jump_size", np.float64),  # [m g l] that jump
        ("excess", np.float64),  # the value that failed a check (m g l or leg lengths)
    ]
)


class Recorder(NamedTuple):
    """Loop state and output buffers (allocated by :func:`make_recorder`)."""

    state: np.ndarray  # (1,) LOOP_STATE record array: the loop's resumable state, state[0].time etc.
    sample_t: np.ndarray  # (ns,)
    sample_y: np.ndarray  # (ns, ny)
    sample_modes: np.ndarray  # (ns, nf, N_MODE_COLUMNS)
    strike_t: np.ndarray  # (nk,)
    strike_foot: np.ndarray  # (nk,) int64
    strike_y: np.ndarray  # (nk, ny)
    strike_modes: np.ndarray  # (nk, nf, N_MODE_COLUMNS)
    log: np.ndarray  # (nl, LOG_COLUMNS): time, foot, +1 touchdown / -1 lift-off, approach velocity deltadot


def make_recorder(ny: int, nf: int, n_samples: int, n_strikes: int, initial_stance_foot: int) -> Recorder:
    """Allocate output buffers and the loop state (the strike and log buffers grow when needed)."""
    state = np.zeros(1, dtype=LOOP_STATE).view(np.recarray)
    state[0].status = RUNNING
    state[0].last_strike_foot = initial_stance_foot
    state[0].jump_time = -1.0
    return Recorder(
        state=state,
        sample_t=np.zeros(n_samples),
        sample_y=np.zeros((n_samples, ny)),
        sample_modes=np.zeros((n_samples, nf, N_MODE_COLUMNS)),
        strike_t=np.zeros(n_strikes),
        strike_foot=np.zeros(n_strikes, dtype=np.int64),
        strike_y=np.zeros((n_strikes, ny)),
        strike_modes=np.zeros((n_strikes, nf, N_MODE_COLUMNS)),
        log=np.zeros((LOG_CAPACITY, LOG_COLUMNS)),
    )


@kernel
def has_room(rec: Recorder, nf: int) -> bool:
    """Whether one more event fits: it logs at most one row and makes at most one heel strike per foot."""
    st = rec.state[0]
    return st.n_log + nf <= rec.log.shape[0] and st.n_strikes + nf <= rec.strike_t.shape[0]


_has_room_in_python = getattr(has_room, "py_func", has_room)  # its code run by Python: no compiled twin for a test


def _enlarged(buffer: np.ndarray, rows: int) -> np.ndarray:
    """``buffer`` with at least ``rows`` rows: twice as many, its contents first."""
    out = np.zeros((max(rows, 2 * buffer.shape[0]), *buffer.shape[1:]), dtype=buffer.dtype)
    out[: buffer.shape[0]] = buffer
    return out


def with_room(rec: Recorder, nf: int) -> Recorder:
    """``rec``, or a copy with larger contact-log and strike buffers (same loop state) if an event might not fit."""
    if _has_room_in_python(rec, nf):
        return rec
    st = rec.state[0]
    log_rows, strike_rows = int(st.n_log) + nf, int(st.n_strikes) + nf
    return rec._replace(
        log=_enlarged(rec.log, log_rows),
        strike_t=_enlarged(rec.strike_t, strike_rows),
        strike_foot=_enlarged(rec.strike_foot, strike_rows),
        strike_y=_enlarged(rec.strike_y, strike_rows),
        strike_modes=_enlarged(rec.strike_modes, strike_rows),
    )


@njit(cache=True, inline="always")
def copy_vector(dst: np.ndarray, src: np.ndarray) -> None:
    """dst[:] = src for 1-D arrays, element by element.

    Written out because numba compiles a slice assignment with a shape check whose error message
    (string formatting of the shapes) is a large part of a cold compilation.
    """
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True, inline="always")
def copy_matrix(dst: np.ndarray, src: np.ndarray) -> None:
    """dst[:, :] = src for 2-D arrays, element by element (as :func:`copy_vector`)."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@kernel
def record_sample(rec: Recorder, t: float, y: np.ndarray, modes: np.ndarray) -> None:
    """Store the sample (t, y, modes) if the sample buffer has room (it is sized for the whole run)."""
    st = rec.state[0]
    k = st.n_samples
    if k < rec.sample_t.shape[0]:
        rec.sample_t[k] = t
        copy_vector(rec.sample_y[k], y)
        copy_matrix(rec.sample_modes[k], modes)
        st.n_samples = k + 1


@njit(cache=True, inline="always")
def _log_contact_changes(
    t: float, y: np.ndarray, system: tuple, modes: np.ndarray, rec: Recorder, touching_before: np.ndarray
) -> None:
    """One contact-log row per contact (foot, then joint stop) whose TOUCHING mode changed: (t, contact, +1 / -1,
    approach velocity)."""
    for i in range(modes.shape[0]):
        now = modes[i, TOUCHING]
        if now != touching_before[i]:
            st = rec.state[0]
            n = st.n_log
            rec.log[n, 0] = t
            rec.log[n, 1] = i
            rec.log[n, 2] = 1.0 if now > 0.5 else -1.0
            rec.log[n, 3] = system_approach_velocity(y, system, i)
            st.n_log = n + 1


@njit(cache=True, inline="always")
def apply_events(
    t: float,
    y: np.ndarray,
    system: tuple,
    modes: np.ndarray,
    contact: ContactBuffers,
    rec: Recorder,
    touching_before: np.ndarray,
    max_strikes: int,
) -> bool:
    """Update contact modes at an event; log touchdowns/lift-offs and heel strikes (the caller keeps has_room).

    A heel strike is the touchdown (``contact.onset`` = TOUCHDOWN) of a foot that is ahead of its
    partner and is not the foot of the previous strike: bounces of the same foot after touchdown
    belong to that strike. Reaching ``max_strikes`` (> 0) strikes completes the run.
    ``touching_before`` is a scratch buffer of one entry per row of ``modes`` (feet, then joint stops). Returns
    True when a mode changed.
    """
    for i in range(modes.shape[0]):
        touching_before[i] = modes[i, TOUCHING]
    if not system_update_modes(t, y, system, modes, contact):
        return False
    _log_contact_changes(t, y, system, modes, rec, touching_before)
    st = rec.state[0]
    for i in range(system.foot_body.shape[0]):
        if contact.onset[i] == TOUCHDOWN and i != st.last_strike_foot and system_is_leading(y, system, i):
            k = st.n_strikes
            rec.strike_t[k] = t
            rec.strike_foot[k] = i
            copy_vector(rec.strike_y[k], y)
            copy_matrix(rec.strike_modes[k], modes)
            st.n_strikes = k + 1
            st.last_strike_foot = i
            if max_strikes > 0 and k + 1 >= max_strikes:
                st.status = COMPLETED
    return True
