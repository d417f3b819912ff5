"""The rimless wheel on ground whose slope changes randomly from step to step: its analytic apex-to-apex map,
the step-to-step Markov chain made of it, and the same walks by the compiled rigid step map.

Terrain (Byl and Tedrake, "Metastable walking machines", IJRR 28 (2009) 1040-1064; Tedrake, Underactuated
Robotics, chapter "Model systems with stochasticity"): the ground between the contact of step k and the next is
straight with slope gamma_k, drawn independently each step from N(gamma_0, sigma^2). With phi the stance spoke's
angle from the vertical, a strike on ground of slope gamma_k happens at phi = gamma_k + alpha (alpha = pi / N)
and the next step starts at phi = gamma_k - alpha. Energy is conserved in a stance phase and the plastic
strike keeps cos(2 alpha) of the angular rate, so the rate x_k at the top (phi = 0) of step k maps to

    w^2 = x_k^2 + 2 (g / l) (1 - cos(gamma_k + alpha)),    w' = cos(2 alpha) w,
    x_{k+1}^2 = w'^2 - 2 (g / l) (1 - cos(gamma_k - alpha)),

and the wheel falls (stops, rocking back) when x_{k+1}^2 < 0. A transition of the chain is a strike:
m(x) = 1 + E[m(x')] counts the strikes from apex x to the fall (the last one followed by the stall), and the
mean first-passage time, as the walks count it (the strikes and the falling step), is m + 1. On a grid of apex
rates with the fall absorbing, m solves (I - Q) m = 1, Q the transient part of the transition matrix (each grid state's
``CHAIN_NODES`` equiprobable slopes, their next rates split linearly between the two nearest grid states).

The walks step the compiled rigid model (:mod:`biped_sim.rigid.compiled`) one step at a time on the slope of
that step: step k starts, in the frame of gamma_k, at stance angle alpha + gamma_k - gamma_{k-1} (the previous
strike's geometry) and ends at its strike; a stall is the fall. Both start at the nominal gait (slope gamma_0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from biped_sim.config import Config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import STRIKE, CompiledWalker, compile_walker, step_entry, with_slope
from biped_sim.rigid.limit_cycle import rigid_limit_cycle

CHAIN_STATES = 800
CHAIN_NODES = 4000
CHAIN_SPAN = 3.0  # the grid of apex rates reaches this many times the nominal apex rate


def walks_random_slopes(config: Config) -> bool:
    """Whether ``config`` walks random slopes per step: a rigid wheel (a walker of one leg with spokes) or a rigid
    walker in space (its step map, :mod:`.space_slopes`)."""
    if config.dynamics != "rigid":
        return False
    return config.in_space or bool(rigid_walker(config).shift)


@dataclass(frozen=True)
class Wheel:
    """The wheel's numbers: half the inter-spoke angle, g / l and the nominal slope."""

    alpha: float
    g_over_l: float
    slope: float

    @classmethod
    def of(cls, config: Config) -> Wheel:
        walker = rigid_walker(config)
        if not walker.shift:
            raise TypeError("the Markov chain is the rimless wheel's")
        return cls(0.5 * walker.shift, walker.gravity / walker.leg_length, config.ground.slope)

    def apex_map(self, x: np.ndarray, gamma: np.ndarray) -> np.ndarray:
        """The next apex rate of apex rates ``x`` on slopes ``gamma`` (NaN: the wheel falls)."""
        w2 = x * x + 2.0 * self.g_over_l * (1.0 - np.cos(gamma + self.alpha))
        after = math.cos(2.0 * self.alpha) ** 2 * w2 - 2.0 * self.g_over_l * (1.0 - np.cos(gamma - self.alpha))
        return np.where(after >= 0.0, np.sqrt(np.maximum(after, 0.0)), np.nan)

    def nominal_apex_rate(self) -> float:
        """The fixed point of the map on the nominal slope."""
        c2 = math.cos(2.0 * self.alpha) ** 2
        a, b = 1.0 - math.cos(self.slope + self.alpha), 1.0 - math.cos(self.slope - self.alpha)
        return math.sqrt(2.0 * self.g_over_l * (c2 * a - b) / (1.0 - c2))


def chain_mfpt(wheel: Wheel, roughness: float) -> float:
    """The mean first-passage time from the nominal apex rate, by the Markov chain: the steps to the fall, the
    falling step counted (the chain's strikes, plus the stall that ends the walk: see the module)."""
    x_star = wheel.nominal_apex_rate()
    grid = np.linspace(0.0, CHAIN_SPAN * x_star, CHAIN_STATES)
    gamma = wheel.slope + roughness * stats.norm.ppf((np.arange(CHAIN_NODES) + 0.5) / CHAIN_NODES)
    nxt = wheel.apex_map(grid[:, None], gamma[None, :])
    rows = np.repeat(np.arange(CHAIN_STATES), CHAIN_NODES).reshape(CHAIN_STATES, CHAIN_NODES)
    alive = np.isfinite(nxt)
    position = np.clip(nxt[alive] / grid[1], 0.0, CHAIN_STATES - 1.0)
    low = np.minimum(position.astype(int), CHAIN_STATES - 2)
    frac = position - low
    q = np.zeros((CHAIN_STATES, CHAIN_STATES))
    np.add.at(q, (rows[alive], low), (1.0 - frac) / CHAIN_NODES)
    np.add.at(q, (rows[alive], low + 1), frac / CHAIN_NODES)
    m = np.linalg.solve(np.eye(CHAIN_STATES) - q, np.ones(CHAIN_STATES))
    return float(np.interp(x_star, grid, m)) + 1.0


def wheel_walks(config: Config, roughness: float, seeds: range, cap: int) -> tuple[np.ndarray, np.ndarray]:
    """Walks of the compiled rigid wheel on random slopes, one per seed: (strikes, fell), ``fell`` False for a
    walk that reached the cap."""
    walker = rigid_walker(config)
    if not walker.shift:
        raise TypeError("wheel_walks walks the rimless wheel")
    cw = compile_walker(walker)
    start = walker.state_from_legs(rigid_limit_cycle(config).fixed_point)
    strikes, fell = np.zeros(len(seeds), dtype=np.int64), np.zeros(len(seeds), dtype=bool)
    for i, seed in enumerate(seeds):
        strikes[i], fell[i] = _walk(cw, 0.5 * walker.shift, config.ground.slope, start, roughness, seed, cap)
    return strikes, fell


def _walk(cw: CompiledWalker, alpha: float, slope: float, start: np.ndarray, roughness: float, seed: int, cap: int):
    x, previous = start.copy(), slope
    x_minus, x_plus = np.zeros(2), np.zeros(2)
    counters = np.zeros(2, dtype=np.int64)
    rng = np.random.default_rng(seed)
    step = step_entry(cw, x, counters)  # typed once per walk: each step's walker differs only in its slope
    for k in range(cap):
        gamma = float(rng.normal(slope, roughness)) if roughness > 0 else slope
        x[0] = alpha + gamma - previous
        code, _ = step(with_slope(cw, gamma), x, x_minus, x_plus, counters)
        if code != STRIKE or not np.all(np.isfinite(x_plus)):
            return k, True
        x, previous = x_plus.copy(), gamma
    return cap, False
