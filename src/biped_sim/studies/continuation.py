"""Continuation of the rigid period-1 gait in the slope and the period-doubling slope."""

from __future__ import annotations

from biped_sim.config import Config, derive
from biped_sim.rigid.limit_cycle import LimitCycle, rigid_limit_cycle


def continue_cycle(config: Config, slope: float, guess: dict[str, float]) -> LimitCycle:
    """The rigid period-1 cycle at another slope, Newton started from ``guess`` (no settling)."""
    return rigid_limit_cycle(derive(config, {"ground.slope": slope}), guess, settle_steps=0)


def flip_margin(cycle: LimitCycle) -> float:
    """1 + the most negative real multiplier (<= 0 once the period-1 gait has flipped); 1 if none is real."""
    real = [m.real for m in cycle.multipliers if abs(m.imag) < 1e-12]
    return min(real) + 1.0 if real else 1.0


def period_doubling_slope(
    config: Config, low: float, high: float, step: float = 5e-4, tolerance: float = 1e-7
) -> tuple[float, LimitCycle]:
    """Slope in [low, high] where a multiplier of the period-1 gait leaves the unit circle through -1.

    Natural continuation from ``low`` (the config's cycle there must not have flipped) in increments of
    ``step``, each solution the next guess, until the flip margin changes sign; then bisection to
    ``tolerance``. Returns the slope and the cycle just past it.
    """
    lower = continue_cycle(config, low, rigid_limit_cycle(config).fixed_point)
    if flip_margin(lower) <= 0:
        raise ValueError(f"period_doubling_slope: the gait has already flipped at slope {low}")
    slope = low
    while True:
        slope = min(slope + step, high)
        upper = continue_cycle(config, slope, lower.fixed_point)
        if not upper.converged:
            raise ValueError(f"period_doubling_slope: continuation lost the cycle at slope {slope}")
        if flip_margin(upper) <= 0:
            break
        if slope >= high:
            raise ValueError(f"period_doubling_slope: no flip between slopes {low} and {high}")
        lower = upper
    return bisect_flip(config, lower, upper, tolerance)


def bisect_flip(
    config: Config, lower: LimitCycle, upper: LimitCycle, tolerance: float = 1e-7
) -> tuple[float, LimitCycle]:
    """Bisection on the flip margin between a cycle that has not flipped and one that has."""
    a, b = lower.slope, upper.slope
    while b - a > tolerance:
        mid = 0.5 * (a + b)
        cycle = continue_cycle(config, mid, lower.fixed_point)
        if flip_margin(cycle) > 0:
            a, lower = mid, cycle
        else:
            b, upper = mid, cycle
    return 0.5 * (a + b), upper
