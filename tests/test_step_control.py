"""The one step-size controller of the compliant loop and the rigid step map (integrate.stepper.step_factor)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim.integrate.explicit import FORCED_STEP, _control
from biped_sim.integrate.recorder import LOOP_STATE, RUNNING
from biped_sim.integrate.stepper import MAX_FACTOR, MIN_FACTOR, SAFETY, step_factor

DOPRI5_ERROR_ORDER = 4  # the step-size exponent -1/5


@pytest.mark.parametrize(
    ("err", "after_rejection", "expected"),
    [
        (0.5, False, (True, SAFETY * 0.5**-0.2)),  # accepted: grows by the rule
        (0.5, True, (True, 1.0)),  # ... but not right after a rejection (scipy)
        (0.01, True, (True, 1.0)),
        (0.001**5, False, (True, MAX_FACTOR)),  # at most tenfold
        (0.0, False, (True, MAX_FACTOR)),
        (0.99, True, (True, SAFETY * 0.99**-0.2)),  # a shrinking factor stays below 1 after a rejection
        (1.0, False, (False, SAFETY)),  # scipy's test: a norm of exactly 1 is rejected
        (2.0, False, (False, SAFETY * 2.0**-0.2)),
        (1e9, False, (False, MIN_FACTOR)),  # at most fivefold smaller
        (math.inf, False, (False, MIN_FACTOR)),
        (math.nan, False, (False, MIN_FACTOR)),
    ],
)
def test_the_controller_accepts_below_one_and_bounds_its_factor(
    err: float, after_rejection: bool, expected: tuple[bool, float]
) -> None:
    assert step_factor.py_func(err, DOPRI5_ERROR_ORDER, after_rejection) == expected


def test_the_compliant_loop_accepts_a_forced_step_whatever_its_error_and_counts_it() -> None:
    """A step of at most FORCED_STEP (a force jump at its start that no smaller step resolves) is taken as if its
    error were 1: the next step is SAFETY h."""
    state = np.zeros(1, dtype=LOOP_STATE).view(np.recarray)
    h = 0.5 * FORCED_STEP
    assert _control.py_func(50.0, True, 0.25, h, DOPRI5_ERROR_ORDER, state[0]) == (True, h * SAFETY)
    assert state[0].forced == 1 and state[0].rejected == 0 and state[0].status == RUNNING
    accepted, retry = _control.py_func(50.0, True, 0.25, 1e-3, DOPRI5_ERROR_ORDER, state[0])
    assert not accepted and retry == 1e-3 * step_factor.py_func(50.0, DOPRI5_ERROR_ORDER, False)[1]
    assert state[0].forced == 1 and state[0].rejected == 1
