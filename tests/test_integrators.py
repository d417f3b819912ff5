"""Integrator orders on a smooth problem, adaptive/fixed agreement, and bit-for-bit reproducibility."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import simulate
from biped_sim.config import IntegratorConfig
from biped_sim.integrate.driver import integrate_model
from biped_sim.simulate import RunResult
from biped_sim.testing import default_walker, pendulum


def final_state(method: str, n_steps: int, t_end: float, amplitude: float = 0.1) -> np.ndarray:
    """Position and velocity of the rod after n_steps fixed steps (step-size control off)."""
    system, y0 = pendulum(amplitude)
    integrator = IntegratorConfig(method=method, dt=t_end / n_steps, adaptive=False)
    run = integrate_model(system, y0, np.zeros((0, 3)), integrator, t_end, sample_rate=1.0 / t_end)
    return run.y[-1, :6]


@pytest.mark.parametrize(
    ("method", "order", "t_end", "steps"),
    [
        ("euler", 1, 10.0, (20_000, 40_000)),
        ("rk2", 2, 10.0, (2_000, 4_000)),
        ("rk4", 4, 100.0, (6_400, 12_800)),
        ("dopri5", 5, 100.0, (6_400, 12_800)),
        ("dop853", 8, 100.0, (1_600, 3_200)),
    ],
)
def test_convergence_order_on_smooth_problem(method: str, order: int, t_end: float, steps: tuple[int, int]) -> None:
    """Global error ratio at halved steps on a nearly linear pendulum (10-50 periods).

    The high-order methods have small principal error coefficients: on strongly nonlinear
    problems their measured order exceeds the nominal one until round-off takes over, so the
    problem is a small (0.1 rad) swing over many periods, where the asymptotic regime is
    reached with errors well above round-off.
    """
    reference = final_state("dop853", 40_000, t_end)
    coarse, fine = (np.linalg.norm(final_state(method, n, t_end) - reference) for n in steps)
    measured = math.log2(coarse / fine)
    assert abs(measured - order) < 0.3, (coarse, fine, measured)


def test_adaptive_methods_agree_on_the_walker() -> None:
    periods = {}
    for method in ("dopri5", "dop853", "radau"):
        result = simulate(default_walker(f"integrator.method={method}"))
        periods[method] = result.step_periods
    np.testing.assert_allclose(periods["dop853"], periods["dopri5"], rtol=1e-6)
    np.testing.assert_allclose(periods["radau"], periods["dopri5"], rtol=1e-4)


def test_same_config_same_bits(short_run: RunResult) -> None:
    again = simulate(short_run.config)
    assert np.array_equal(again.run.y, short_run.run.y)
    assert np.array_equal(again.run.strike_t, short_run.run.strike_t)
    assert again.summary["config_hash"] == short_run.summary["config_hash"]


def test_progress_chunking_does_not_change_results() -> None:
    """3 s of dopri5: 24,000 steps, so two compiled calls (at most 20,000 steps each) with a progress update
    between them, and the step-size control carried across. (2 s, 16,000 steps, would be one call: no test.)"""
    config = default_walker(t_end=3.0)
    times: list[float] = []
    with_progress = simulate(config, progress=times.append)
    assert len(times) >= 2 and times == sorted(times) and times[-1] == pytest.approx(3.0)
    assert np.array_equal(with_progress.run.y, simulate(config).run.y)


def test_a_stiff_run_whose_event_search_fails_ends_diverged_with_its_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    """scipy's root search raising "f(a) and f(b) must have different signs" (its interpolant disagreeing in sign
    with its step's end states) is a status, not a crash: with no event at zero to hold, the run ends diverged, saying
    why."""
    from biped_sim.integrate import segment

    def failing_search(*args: object, **kwargs: object) -> None:
        raise ValueError("f(a) and f(b) must have different signs")

    monkeypatch.setattr(segment, "brentq", failing_search)
    result = simulate(default_walker("integrator.method=radau", t_end=0.05))
    assert result.status == "diverged"
    assert result.status_reason == "the stiff solver's event search failed (an event function within round-off of zero)"
