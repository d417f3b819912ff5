"""What the integration loops take for a blown-up integration rather than physics, checked while they step.

The energy residual r = E(t) + W(t) - E(0) - W(0) - W_push(t) (E kinetic + potential + elastic, W the work
dissipated by normal damping and friction, integrated with the motion, W_push the pushes' work) is pure
integration error, about 1e-9 m g l for an accurate run, so it tells a blow-up from a physical fall. A run
is ``diverged`` when

* |r| passes ``DIVERGED_ENERGY`` m g l, or a joint drifts apart by ``DIVERGED_DRIFT`` leg lengths, or
* it falls after r changed by ``DIVERGED_ENERGY_JUMP`` m g l between two checks (``CHECK_INTERVAL``): a step
  too large for the contact throws a foot off the ground faster than it landed (fixed-step runs that walk
  change r far less: tests/test_inputs.py).

The loops check the first accepted step past every ``CHECK_INTERVAL`` of simulated time, the step at which the
walker falls and the state a run ends on; which steps are checked depends on the steps alone, so the status does
not depend on ``output.sample_rate`` (the samples used to be the checks). A check evaluates the formulation's
``audit`` kernel (its energy and drift) once.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.integrate.recorder import DIVERGED, ENERGY_JUMP, ENERGY_RESIDUAL, FELL, JOINT_DRIFT, Recorder
from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import system_audit, system_energy

DIVERGED_ENERGY = 1.0  # [m g l] an energy residual this large is a blown-up integration, not physics
DIVERGED_ENERGY_JUMP = 0.01  # [m g l] this much energy error between two checks before a fall: a blown-up step
DIVERGED_DRIFT = 0.1  # [leg lengths] joints this far apart: the constraints no longer hold
CHECK_INTERVAL = 1e-3  # [s] of simulated time between checks


class Scales(NamedTuple):
    """The units of the checks: energy m g l [J] and length l [m] of the walker (energy 0: no checks)."""

    energy: float
    length: float


NO_CHECKS = Scales(0.0, 1.0)


def start_checks(rec: Recorder, system: tuple, y: np.ndarray, modes: np.ndarray) -> None:
    """Set the energy the residual is measured from: E + W of the state the integration starts from (the stiff
    driver's start; the compiled loop sets it itself, at its first call)."""
    rec.state[0].energy_reference = energy_reference(y, system, modes)


@njit(cache=True, inline="always")
def energy_reference(y: np.ndarray, system: tuple, modes: np.ndarray) -> float:
    """E + W of the state (y, modes): the formulation's mechanical energy (its measure kernel, which the energy
    audit's loop compiles too) plus the work dissipated so far (:func:`plus_dissipated`)."""
    kinetic, potential, elastic = system_energy(y, system, modes)
    return plus_dissipated(kinetic + potential + elastic, y, system)


@njit(cache=True, inline="always")
def plus_dissipated(energy: float, y: np.ndarray, system: tuple) -> float:
    """E + W: ``energy`` plus the work the feet's normal damping and friction (and, with joint elements and stops,
    theirs: W_element, W_stop) dissipated, the last entries of the state (``StateLayout`` of
    :mod:`biped_sim.multibody`), added in the state's order."""
    n = y.shape[0]
    first = n - 2
    if system.elements.law.shape[0] > 0:
        first -= 1
    if system.stops.law.shape[0] > 0:
        first -= 1
    for k in range(first, n):
        energy += y[k]
    return energy


@njit(cache=True, inline="always")
def _blow_up(st: np.record, t: float, reason: int, excess: float) -> None:
    st.status = DIVERGED
    st.stop_time = t
    st.reason = reason
    st.excess = excess


@njit(cache=True, inline="always")
def check(
    t: float, y: np.ndarray, system: tuple, modes: np.ndarray, work: tuple, state: np.ndarray, scales: Scales,
    force: bool,
) -> None:  # fmt: skip
    """The checks at the state (t, y), if it is due (``t`` past the record's check time) or ``force``d.

    Inlined, it is the due test only: the checks themselves (:func:`_check_now`, about once per ``CHECK_INTERVAL``)
    are one compiled call, so that the loop, which checks at three places, compiles them once.
    """
    if scales.energy > 0.0 and (force or t >= state[0].check_time):
        _check_now(t, y, system, modes, work, state, scales)


@kernel(reference_counts=False, by_symbol=True)  # about once per CHECK_INTERVAL
def _check_now(
    t: float, y: np.ndarray, system: tuple, modes: np.ndarray, work: tuple, state: np.ndarray, scales: Scales
) -> None:
    """The checks at the state (t, y), due: stops the run (``state[0]``, the loop-state record) as diverged when
    the residual or the drift is too large; notes the first jump of the residual since the last check, which makes
    a later fall a divergence.
    """
    st = state[0]
    energy, drift = system_audit(y, system, modes, work)
    residual = (plus_dissipated(energy, y, system) - st.energy_reference) / scales.energy
    jump = abs(residual - st.check_residual)
    st.check_residual = residual
    st.check_time = t + CHECK_INTERVAL
    if not abs(residual) <= DIVERGED_ENERGY:  # a NaN too
        _blow_up(st, t, ENERGY_RESIDUAL, abs(residual))
    elif not drift / scales.length <= DIVERGED_DRIFT:
        _blow_up(st, t, JOINT_DRIFT, drift / scales.length)
    elif not jump <= DIVERGED_ENERGY_JUMP and st.jump_time < 0.0:
        st.jump_time = t
        st.jump_size = jump


@kernel(reference_counts=False)
def fall(
    t: float, y: np.ndarray, system: tuple, modes: np.ndarray, work: tuple, state: np.ndarray, scales: Scales,
    criterion: int,
) -> None:  # fmt: skip
    """End the run at a fall (``criterion``: the fall kernel's code): FELL, or DIVERGED when the checks, made
    here too, fail or saw the residual jump before it."""
    check(t, y, system, modes, work, state, scales, True)
    st = state[0]
    if st.status == DIVERGED:
        return
    if st.jump_time >= 0.0:
        _blow_up(st, st.jump_time, ENERGY_JUMP, st.jump_size)
        return
    st.status = FELL
    st.stop_time = t
    st.reason = criterion
