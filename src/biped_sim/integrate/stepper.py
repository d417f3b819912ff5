"""One explicit Runge-Kutta step, its error estimate and the starting step size (compiled).

The loop's buffers are one :class:`Scratch`; the stage derivatives k[s] = f(t + c_s h, y + h sum_j
a_sj k[j]) of every method live in its rows, with the FSAL stage f(t + h, y_new) of the adaptive
methods in row ``tab.stages`` (it is the next step's k[0]). Error control follows Hairer, Norsett &
Wanner (Solving ODEs I, II.4) as scipy does, so dopri5 takes scipy RK45's steps. What one call of
the loop works on is one :class:`Loop`; the pieces called at every step take the arrays they use
one by one instead, and the loop itself calls the right-hand side for each stage (:func:`stage_input`,
:func:`propagate` are the arithmetic of a step), inlined in it. The loop counts no references
(:func:`biped_sim.kernel.kernel`): the arrays it hands on carry no memory-info pointer, so the
kernels it calls skip their own count updates too (an atomic one per array argument, at entry and exit).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.contact.response import ContactBuffers
from biped_sim.integrate.recorder import Recorder
from biped_sim.integrate.tableaus import DOPRI5, MAX_STAGES, Tableau
from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import system_rhs


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
        np.zeros((MAX_STAGES, ny)),
        np.zeros(ny),
        np.zeros(ny),
        np.zeros(ny),
        np.zeros((7, ny)),
        np.zeros(n_events),
        np.zeros(n_events),
        np.zeros(n_events),
        np.zeros(nf),
    )


class Loop(NamedTuple):
    """What one call of the compiled loop works on."""

    tab: Tableau
    system: tuple  # a formulation's system NamedTuple
    work: tuple  # its right-hand side's workspace
    contact: ContactBuffers  # its contact-mode update's buffers
    y: np.ndarray  # (ny,) the state at the current time, updated in place
    modes: np.ndarray  # (nf, N_MODE_COLUMNS) the contact modes, updated in place
    sc: Scratch
    rec: Recorder


@njit(cache=True, inline="always")  # inlined (numba IR): a call per stage would cost reference counts
def stage_input(a: np.ndarray, s: int, h: float, y: np.ndarray, k: np.ndarray, out: np.ndarray) -> None:
    """out = y + h sum_{j<s} a_sj k[j]: the state at which stage s evaluates f."""
    for i in range(y.shape[0]):
        v = 0.0
        for j in range(s):
            v += a[s, j] * k[j, i]
        out[i] = y[i] + h * v


@njit(cache=True, inline="always")
def propagate(b: np.ndarray, stages: int, h: float, y: np.ndarray, k: np.ndarray, out: np.ndarray) -> bool:
    """out = y + h sum_s b_s k[s]: the step's end state; returns whether it is finite."""
    finite = True
    for i in range(y.shape[0]):
        v = 0.0
        for s in range(stages):
            v += b[s] * k[s, i]
        out[i] = y[i] + h * v
        if not math.isfinite(out[i]):
            finite = False
    return finite


SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0  # the step-size rule's constants (Hairer's, as scipy's)


@njit(cache=True, inline="always")
def step_factor(err: float, error_order: int, after_rejection: bool) -> tuple[bool, float]:
    """The step-size controller of every adaptive loop: (accepted, factor of h for the next try or step).

    Hairer, Norsett & Wanner's rule (Solving ODEs I, II.4), as scipy's RK45 and DOP853: a step whose error
    norm ``err`` is below 1 is accepted and the next one is h min(MAX_FACTOR, SAFETY err^(-1/(q+1))) (q the
    order of the error estimator; MAX_FACTOR after an error of exactly 0), capped at 1 ``after_rejection`` (the
    step before it was rejected, as scipy); else it is retried with h max(MIN_FACTOR, SAFETY err^(-1/(q+1))),
    MIN_FACTOR for a non-finite norm. The compliant loop (:mod:`~biped_sim.integrate.explicit`) lets the step
    after a rejection grow (``after_rejection`` always False: its runs are pinned so); the rigid step map
    (:mod:`biped_sim.rigid.integration`) caps it.
    """
    exponent = -1.0 / (error_order + 1)
    if not err < 1.0:
        return False, MIN_FACTOR if not math.isfinite(err) else max(MIN_FACTOR, SAFETY * err**exponent)
    factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**exponent)
    return True, min(1.0, factor) if after_rejection else factor


@kernel
def rms_norm(v: np.ndarray, scale: np.ndarray) -> float:
    """sqrt(mean((v / scale)^2))."""
    s = 0.0
    for i in range(v.shape[0]):
        s += (v[i] / scale[i]) ** 2
    return math.sqrt(s / v.shape[0])


@njit(cache=True, inline="always")
def error_norm(tab: Tableau, h: float, y: np.ndarray, sc: Scratch, rtol: float, atol: float) -> float:
    """Hairer's scaled RMS error norm of the embedded estimate (dop853: combined 5th/3rd order).

    The scale of entry i is atol + rtol max(|y_i|, |y_new,i|); the estimate sums the error weights
    over the stages and the FSAL stage.
    """
    ny = y.shape[0]
    n_k = tab.stages + 1
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


@njit(cache=True, inline="always")
def initial_step_trial(y: np.ndarray, sc: Scratch, rtol: float, atol: float, max_step: float) -> tuple[float, float]:
    """First half of Hairer, Norsett & Wanner's starting step (Solving ODEs I, II.4): with k[0] = f(t, y),
    the trial step h0 and ||f||; leaves the scale in ``sc.y_dense`` and the Euler trial point y + h0 f in
    ``sc.y_stage``, where the caller evaluates f into k[1] (:func:`initial_step_size` then finishes)."""
    ny = y.shape[0]
    for i in range(ny):
        sc.y_dense[i] = atol + rtol * abs(y[i])
    d0 = rms_norm(y, sc.y_dense)
    d1 = rms_norm(sc.k[0], sc.y_dense)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, max_step)
    for i in range(ny):
        sc.y_stage[i] = y[i] + h0 * sc.k[0, i]
    return h0, d1


@njit(cache=True, inline="always")
def initial_step_size(tab: Tableau, sc: Scratch, h0: float, d1: float, max_step: float) -> float:
    """Second half of the starting step: from k[1] = f at the trial point, the estimate of f' and the step."""
    for i in range(sc.y_stage.shape[0]):
        sc.y_stage[i] = sc.k[1, i] - sc.k[0, i]
    d2 = rms_norm(sc.y_stage, sc.y_dense) / h0
    q = tab.error_order + 1
    if max(d1, d2) <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / q)
    return min(100.0 * h0, h1, max_step)


@njit(cache=True, inline="always")
def initial_step(
    tab: Tableau,
    t: float,
    y: np.ndarray,
    system: tuple,
    modes: np.ndarray,
    work: tuple,
    sc: Scratch,
    st,
    rtol: float,
    atol: float,
    max_step: float,
) -> float:
    """Hairer, Norsett & Wanner's starting step (Solving ODEs I, II.4); uses k[0] = f(t, y)."""
    h0, d1 = initial_step_trial(y, sc, rtol, atol, max_step)
    system_rhs(t + h0, sc.y_stage, system, modes, work, sc.k[1])
    st.rhs_evals += 1
    return initial_step_size(tab, sc, h0, d1, max_step)
