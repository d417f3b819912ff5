"""Run an integrator on a built model: allocate buffers, call the compiled loop in chunks.

:func:`integrate_model` is the one entry point for every method; the explicit methods run in
the compiled loop of :mod:`biped_sim.integrate.explicit`, ``radau`` and ``bdf`` in
:mod:`biped_sim.integrate.stiff`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from biped_sim.config import IntegratorConfig
from biped_sim.integrate.explicit import (
    ACCEPTED,
    COMPLETED,
    DIVERGED,
    FALL_TIME,
    FELL,
    LAST_STRIKE_FOOT,
    N_EVENTS,
    N_ISTATE,
    N_LOG,
    N_SAMPLES,
    N_STRIKES,
    REJECTED,
    RHS_EVALS,
    STATUS,
    TIME,
    Recorder,
    advance,
    make_scratch,
)
from biped_sim.integrate.tableaus import tableau
from biped_sim.multibody.dispatch import event_count, make_workspace

STATUS_NAMES = {COMPLETED: "walking", FELL: "fell", DIVERGED: "diverged"}
STEP_BUDGET = 20_000  # steps per compiled call between progress updates (does not change results)
LOG_CAPACITY = 200_000


@dataclass
class Integration:
    """Raw output of one integration (samples, heel strikes, contact events, counters)."""

    status: str
    t_final: float
    stop_time: float | None  # time of the fall or divergence
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


def sample_interval(integrator: IntegratorConfig, sample_rate: float) -> float:
    """Sampling interval; for fixed-step methods a whole number of steps."""
    interval = 1.0 / sample_rate
    if integrator.method in ("euler", "rk2", "rk4") or not integrator.adaptive:
        interval = max(1, round(interval / integrator.dt)) * integrator.dt
    return interval


def make_recorder(ny: int, nf: int, n_samples: int, n_strikes: int, initial_stance_foot: int) -> Recorder:
    """Allocate output buffers and the loop state."""
    istate = np.zeros(N_ISTATE, dtype=np.int64)
    istate[LAST_STRIKE_FOOT] = initial_stance_foot
    return Recorder(
        istate=istate,
        fstate=np.zeros(3),
        sample_t=np.zeros(n_samples),
        sample_y=np.zeros((n_samples, ny)),
        sample_modes=np.zeros((n_samples, nf, 3)),
        strike_t=np.zeros(n_strikes),
        strike_foot=np.zeros(n_strikes, dtype=np.int64),
        strike_y=np.zeros((n_strikes, ny)),
        strike_modes=np.zeros((n_strikes, nf, 3)),
        log=np.zeros((LOG_CAPACITY, 4)),
    )


def recorder_for(
    ny: int,
    nf: int,
    integrator: IntegratorConfig,
    t_end: float,
    sample_rate: float,
    max_strikes: int | None,
    initial_stance_foot: int,
) -> tuple[Recorder, float, int]:
    """(recorder, sample interval, strike capacity) sized for an integration to ``t_end``."""
    interval = sample_interval(integrator, sample_rate)
    n_samples = math.floor(t_end / interval + 1e-9) + 2
    n_strikes = max_strikes if max_strikes else int(t_end * 50) + 16
    return make_recorder(ny, nf, n_samples, n_strikes, initial_stance_foot), interval, n_strikes


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
) -> Integration:
    """Integrate ``system`` from (y0, modes0) at t = 0 to ``t_end`` or a stop condition."""
    y = np.array(y0, dtype=np.float64)
    modes = np.array(modes0, dtype=np.float64)
    ny, nf = y.shape[0], modes.shape[0]
    rec, interval, n_strikes = recorder_for(ny, nf, integrator, t_end, sample_rate, max_strikes, initial_stance_foot)
    if integrator.method in ("radau", "bdf"):
        from biped_sim.integrate.stiff import integrate_stiff  # here: scipy.integrate adds 0.3 s to start-up

        integrate_stiff(system, rec, y, modes, integrator, t_end, interval, max_strikes or 0, progress)
    else:
        tab = tableau(integrator.method)
        work = make_workspace(system)
        scratch = make_scratch(ny, nf, event_count(system))
        while rec.istate[STATUS] == 0:
            advance(
                system, work, tab, rec, scratch, y, modes, t_end, integrator.dt, integrator.adaptive,
                integrator.rtol, integrator.atol, integrator.max_step, interval, max_strikes or 0, STEP_BUDGET,
            )  # fmt: skip
            if progress is not None:
                progress(float(rec.fstate[TIME]))
    return finish_integration(rec, n_strikes, interval)


def finish_integration(rec: Recorder, n_strikes: int, interval: float) -> Integration:
    """Copy the filled part of the recorder's buffers into an :class:`Integration`."""
    status = int(rec.istate[STATUS])
    ns, nk, nl = int(rec.istate[N_SAMPLES]), min(int(rec.istate[N_STRIKES]), n_strikes), int(rec.istate[N_LOG])
    return Integration(
        status=STATUS_NAMES[status],
        t_final=float(rec.fstate[TIME]),
        stop_time=float(rec.fstate[FALL_TIME]) if status in (FELL, DIVERGED) else None,
        t=rec.sample_t[:ns].copy(),
        y=rec.sample_y[:ns].copy(),
        modes=rec.sample_modes[:ns].copy(),
        strike_t=rec.strike_t[:nk].copy(),
        strike_foot=rec.strike_foot[:nk].copy(),
        strike_y=rec.strike_y[:nk].copy(),
        strike_modes=rec.strike_modes[:nk].copy(),
        contact_log=rec.log[:nl].copy(),
        rhs_evals=int(rec.istate[RHS_EVALS]),
        accepted_steps=int(rec.istate[ACCEPTED]),
        rejected_steps=int(rec.istate[REJECTED]),
        events=int(rec.istate[N_EVENTS]),
        sample_dt=interval,
    )
