"""The stiff methods' segment without solve_ivp (integrate.segment): the same steps, states, status, evaluation count
and dense output as solve_ivp, bit for bit, on seeded random problems with terminal events."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from biped_sim.integrate.newton_lu import DirectBDF, DirectRadau
from biped_sim.integrate.segment import SegmentEvents, ivp_segment, sample_steps, stepped_segment

CASES = 12  # random problems per method


def _problem(rng: np.random.Generator) -> tuple:
    """A stiff damped oscillator pair (a fast mode and a slow one) and three level-crossing events."""
    stiffness, damping = rng.uniform(1.0, 10.0), rng.uniform(10.0, 1e3)
    matrix = np.array([[0.0, 1.0, 0.0], [-stiffness, -0.1, 0.5], [0.0, 0.0, -damping]])

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        return matrix @ y + np.array([0.0, np.sin(3.0 * t), 0.0])

    def jac(t: float, y: np.ndarray) -> np.ndarray:
        return matrix

    levels = rng.uniform(-0.8, 0.8, 3)

    def values(t: float, y: np.ndarray) -> np.ndarray:
        return y[0] - levels

    def event_of(j: int):
        def event(t: float, y: np.ndarray) -> float:
            return values(t, y)[j]

        event.terminal = True  # type: ignore[attr-defined]
        return event

    y0 = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-2.0, 2.0), 1.0])
    return fun, jac, values, [event_of(j) for j in range(3)], y0


@pytest.mark.parametrize("method", [DirectBDF, DirectRadau])
def test_a_stepped_segment_is_solve_ivps_to_the_bit(method: type) -> None:
    rng = np.random.default_rng(20261205)
    events_hit = 0
    for _ in range(CASES):
        fun, jac, values, each, y0 = _problem(rng)
        interval = float(rng.uniform(0.005, 0.05))
        options = {"rtol": 1e-6, "atol": 1e-9, "max_step": np.inf, "jac": jac}
        events = SegmentEvents(each, values, sample_steps(0, interval))
        ours = stepped_segment(fun, 0.0, 3.0, y0, method, options, events)
        theirs = ivp_segment(fun, 0.0, 3.0, y0, method, options, events)
        assert ours.status == theirs.status
        assert ours.nfev == theirs.nfev
        assert_array_equal(ours.t, theirs.t)
        assert_array_equal(ours.y, theirs.y)
        end = float(ours.t[-1]) + 1e-12  # the driver reads the sample times, and just past an event
        samples = [n * interval for n in range(1, int(end / interval) + 1) if n * interval <= ours.t[-1]]
        for t in [*samples, *([end] if ours.status == 1 else [])]:
            assert_array_equal(ours.sol(t), theirs.sol(t))
        events_hit += ours.status == 1
    assert events_hit >= CASES // 2  # the cases test the events, not only the steps


def test_sample_steps_says_which_steps_hold_a_sample_time() -> None:
    rng = np.random.default_rng(7)
    for _ in range(2000):
        interval, n_start = float(rng.uniform(1e-3, 0.1)), int(rng.integers(0, 50))
        t_old = float(rng.uniform(0.0, 5.0))
        t = t_old + float(rng.choice([rng.uniform(0.0, 3.0 * interval), interval]))
        times = np.arange(n_start, int(t / interval) + 3) * interval
        expected = bool(np.any((times > t_old) & (times <= t)))
        assert sample_steps(n_start, interval)(t_old, t) == expected or (expected is False and t - t_old >= interval)
