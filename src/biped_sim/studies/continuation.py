"""Continuation of the rigid period-1 gait in the slope, the period-doubling slope, and an independent
route to the simplest walker's multipliers (the variational equations)."""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, derive
from biped_sim.rigid.limit_cycle import LimitCycle, StepFailedError, rigid_limit_cycle
from biped_sim.rigid.models import SimplestWalker
from biped_sim.rigid.stepping import rigid_step


def simplest_variational_jacobian(walker: SimplestWalker, z: np.ndarray) -> np.ndarray:
    """Step-map Jacobian of the simplest walker from the variational equations (not finite differences).

    Phi' = Df(x) Phi along the flow, the saltation through the strike guard g = theta_st + theta_sw
    (the event time moves with the state), then the impact's Jacobian, in section coordinates.
    """
    from scipy.integrate import solve_ivp  # here: scipy.integrate adds 0.3 s to start-up

    step = rigid_step(walker, walker.from_section(z))
    if step.status != "strike":
        raise StepFailedError(f"the simplest walker {step.status}")

    def augmented(_t: float, y: np.ndarray) -> np.ndarray:
        x, phi = y[:4], y[4:].reshape(4, 4)
        return np.concatenate([walker.rhs(x), (walker.jacobian(x) @ phi).ravel()])

    x0 = walker.from_section(z)
    y0 = np.concatenate([x0, np.eye(4).ravel()])
    sol = solve_ivp(augmented, (0.0, step.period), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    x_minus, phi = sol.y[:4, -1], sol.y[4:, -1].reshape(4, 4)
    f = walker.rhs(x_minus)
    grad = np.array([1.0, 1.0, 0.0, 0.0])
    saltation = np.eye(4) - np.outer(f, grad) / (grad @ f)
    full = walker.impact_jacobian(x_minus) @ saltation @ phi
    # d(from_section)/dz and the section rows (theta_st, thetadot_st)
    theta, theta_d = z
    lift = np.array(
        [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [-2.0 * math.sin(2.0 * theta) * theta_d, math.cos(2.0 * theta)]]
    )
    return full[[0, 2]] @ lift


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
