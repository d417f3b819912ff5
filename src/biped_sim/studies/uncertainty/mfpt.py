"""Survival on stochastic ground: the mean first-passage time (MFPT, Byl and Tedrake 2009), the expected number
of steps before a fall, from walks over seeds, as a function of the roughness.

Two grounds:

* ``height`` (any walker): a ``random`` ground profile (heights drawn every ``SPACING`` leg lengths, standard
  deviation ``roughness`` leg lengths, seeded) from the start on; a run stops at a fall or after ``cap`` heel
  strikes;
* ``slope`` (the rigid rimless wheel, a rigid walker in space): the slope of every step drawn from
  N(slope, roughness^2), walked by the compiled rigid step map; the wheel's with the Markov chain of its analytic
  apex-to-apex map beside it as a check (:mod:`.rimless_chain`), the walker in space's with each step's state turned
  into its slope's frame (:mod:`.space_slopes`).

The estimate (:func:`mfpt_estimate`): a metastable walker has a constant chance p of falling at each step, so its
first-passage time T, the step on which it falls (the falling step counted: the Markov chain's strikes plus one), is
geometric with mean 1 / p >= 1. A walk that fell after s strikes has T = s + 1, one that reached the cap after s
strikes T > s (censored); the likelihood p^k (1 - p)^S (k falls, S strikes in all) gives the MFPT (S + k) / k and
its likelihood-ratio interval (the p within chi2_1(confidence) / 2 of the maximum), which stays at or above one
step; with no fall at all, the MFPT is unbounded above and the interval's lower end is the bound the walks give.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from scipy import optimize, stats

from biped_sim.config import Config, derive
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.simulate import study_formulation
from biped_sim.simulate.budget import check_run_count
from biped_sim.studies.tasks import results_as_done
from biped_sim.studies.uncertainty.rimless_chain import Wheel, chain_mfpt, walks_random_slopes, wheel_walks
from biped_sim.studies.uncertainty.space_slopes import space_slope_walks

CONFIDENCE = 0.95
SPACING = 0.1  # [leg lengths] between the random heights
GROUNDS = ("height", "slope")
MAX_CAP = 10_000  # steps of a walk: its random ground (2 leg lengths a step) and its samples stay within bounds
MAX_WHEEL_CAP = 100_000  # steps of a wheel's walk on random slopes: no ground profile, a step map per strike
TIME_PER_STEP = 10.0  # a height walk's t_end: this many sqrt(l / g) per step (it stops at the cap)


@dataclass(frozen=True)
class Estimate:
    """MFPT [steps] with its interval, and what it rests on."""

    mfpt: float
    ci: tuple[float, float]
    falls: int
    censored: int
    method: str


def mfpt_estimate(strikes: np.ndarray, fell: np.ndarray, confidence: float = CONFIDENCE) -> Estimate:
    """The MFPT [steps] of walks that took ``strikes`` steps and fell (``fell``) or reached the cap (see module)."""
    strikes, fell = np.asarray(strikes, dtype=float), np.asarray(fell, dtype=bool)
    k, total = int(np.count_nonzero(fell)), float(np.sum(strikes))
    p_low, p_high = _likelihood_interval(k, total, float(stats.chi2.ppf(confidence, 1)))
    mfpt = (total + k) / k if k else math.inf
    ci = (1.0 / p_high, 1.0 / p_low if p_low > 0 else math.inf)
    return Estimate(
        mfpt, ci, k, strikes.size - k, "geometric first passage, censored at the cap; likelihood-ratio interval"
    )


def _likelihood_interval(k: int, total: float, threshold: float) -> tuple[float, float]:
    """The fall probabilities p whose log-likelihood k ln p + total ln(1 - p) is within ``threshold`` / 2 of its
    maximum, at p = k / (k + total)."""

    def log_likelihood(p: float) -> float:
        return (k * math.log(p) if k else 0.0) + (total * math.log1p(-p) if total else 0.0)

    best = k / (k + total)
    peak = log_likelihood(best) if 0.0 < best < 1.0 else 0.0

    def excess(p: float) -> float:
        return 2.0 * (peak - log_likelihood(p)) - threshold

    tiny = 1e-300
    low = optimize.brentq(excess, tiny, best) if k else 0.0
    high = optimize.brentq(excess, best, 1.0 - 1e-16) if total else 1.0
    return low, high


def height_walk_config(config: Config, roughness: float, seed: int, cap: int) -> Config:
    """``config`` on random heights of ``roughness`` leg lengths, stopped after ``cap`` heel strikes (a compliant
    planar walker in minimal coordinates, as every study runs it)."""
    leg = config.walker.leg_length
    t_end = TIME_PER_STEP * cap * math.sqrt(leg / config.gravity)
    profile = {"kind": "random", "spacing": SPACING * leg, "roughness": roughness * leg, "seed": seed,
               "start": 0.0, "length": 2.0 * cap * leg}  # fmt: skip
    values: dict[str, Any] = {"ground.profile": profile, "simulation.max_steps": cap, "simulation.t_end": t_end}
    if config.dynamics == "compliant":
        values |= {"formulation.kind": study_formulation(config), "output.sample_rate": 100.0}
    return derive(config, values)


def height_walk(config: Config, roughness: float, seed: int, cap: int) -> tuple[int, bool]:
    """One walk on random heights of ``roughness`` leg lengths: (strikes, fell)."""
    from biped_sim.simulate import simulate  # the engine: imported by the workers that walk

    result = simulate(height_walk_config(config, roughness, seed, cap))
    strikes = len(result.steps.strike_time)
    return min(strikes, cap), not (result.status == "walking" and strikes >= cap)


def _height_task(task: tuple[Config, float, int, int]) -> tuple[float, int, int, bool]:
    config, roughness, seed, cap = task
    strikes, fell = height_walk(config, roughness, seed, cap)
    return roughness, seed, strikes, fell


@dataclass
class MfptCurve:
    """MFPT against roughness: the walks' estimates and, for the rimless wheel on random slopes, the chain's."""

    ground: str
    roughness: list[float]
    estimates: list[Estimate]
    chain: list[float] | None
    seeds: int
    cap: int
    notes: list[str] = field(default_factory=list)

    @property
    def roughness_label(self) -> str:
        return "slope sd per step [rad]" if self.ground == "slope" else "height sd [leg lengths]"

    def to_pandas(self) -> pd.DataFrame:
        """One row per roughness level: the MFPT [steps], its interval, the falls, the censored walks (and the
        rimless wheel's chain MFPT)."""
        return pd.DataFrame(self.to_json()["levels"])

    def __repr__(self) -> str:
        mfpts = ", ".join(f"{e.mfpt:.3g}" for e in self.estimates)
        return (f"<MfptCurve on {self.ground} ground, {self.seeds} walks per level capped at {self.cap} steps: "
                f"MFPT [{mfpts}] at roughness {self.roughness}>")  # fmt: skip

    def to_json(self) -> dict[str, Any]:
        rows = []
        for i, (h, e) in enumerate(zip(self.roughness, self.estimates, strict=True)):
            row = {"roughness": h, "mfpt": e.mfpt, "ci": list(e.ci), "falls": e.falls, "censored": e.censored,
                   "method": e.method}  # fmt: skip
            if self.chain is not None:
                row["chain_mfpt"] = self.chain[i]
            rows.append(row)
        return {"ground": self.ground, "roughness_unit": self.roughness_label, "seeds": self.seeds, "cap": self.cap,
                "confidence": CONFIDENCE, "levels": rows, "notes": self.notes}  # fmt: skip


def check_mfpt_input(config: Config, ground: str, roughness: Sequence[float], seeds: int, cap: int) -> None:
    """ArgumentError naming the argument at fault."""
    if ground not in GROUNDS:
        raise ArgumentError("ground", f"unknown ground {ground!r}; expected one of {', '.join(GROUNDS)}")
    if ground == "slope" and not walks_random_slopes(config):
        raise ArgumentError(
            "ground", "random slopes per step are walked by the rigid rimless wheel and rigid walkers in space only"
        )
    if ground == "height" and (reason := config.profile_refusal()):
        # refused here, before any worker: a worker would meet it only after resolving the walker's start
        raise ConfigError("ground.profile", reason)
    if not roughness or not all(math.isfinite(h) and h >= 0 for h in roughness):
        raise ArgumentError("roughness", "give non-negative roughness levels")
    if seeds < 2:
        raise ArgumentError("seeds", "need at least 2 seeds")
    check_run_count(len(roughness) * seeds, "seeds", "walks (roughness levels x seeds)")
    most = MAX_WHEEL_CAP if ground == "slope" else MAX_CAP
    if not 1 <= cap <= most:
        raise ArgumentError("cap", f"must be from 1 to {most:,} steps on the {ground} ground")


def mfpt_curve(
    config: Config, ground: str, roughness: Sequence[float], seeds: int, cap: int, executor: Executor | None = None
) -> MfptCurve:
    """The MFPT at each roughness level over ``seeds`` walks capped at ``cap`` strikes."""
    check_mfpt_input(config, ground, roughness, seeds, cap)
    levels = [float(h) for h in roughness]
    if ground == "slope" and config.in_space:
        estimates = [mfpt_estimate(*space_slope_walks(config, h, range(seeds), cap)) for h in levels]
        notes = ["slope of each step ~ N(slope, roughness^2), a kink at each new contact point; the step map in space"]
        return MfptCurve(ground, levels, estimates, None, seeds, cap, notes)
    if ground == "slope":
        walks = [wheel_walks(config, h, range(seeds), cap) for h in levels]
        estimates = [mfpt_estimate(*w) for w in walks]
        chain = [chain_mfpt(Wheel.of(config), h) if h > 0 else math.inf for h in levels]
        notes = ["slope of each step ~ N(slope, roughness^2); chain: the analytic apex-to-apex map (Byl & Tedrake)"]
        return MfptCurve(ground, levels, estimates, chain, seeds, cap, notes)
    tasks = [(config, h, seed, cap) for h in levels for seed in range(seeds)]
    done: dict[float, list[tuple[int, bool]]] = {h: [] for h in levels}
    for h, _seed, strikes, fell in results_as_done(_height_task, tasks, executor):
        done[h].append((strikes, fell))
    estimates = [mfpt_estimate(*np.array(done[h], dtype=float).T) for h in levels]
    notes = [f"random heights every {SPACING:g} leg lengths from the start; a walk stops at a fall or {cap} strikes"]
    return MfptCurve(ground, levels, estimates, None, seeds, cap, notes)
