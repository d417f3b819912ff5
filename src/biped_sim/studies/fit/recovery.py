"""Recovery measured on cases nobody chose: hidden values drawn at random (seeded) across the bounds, fitted back.

Each case is a walker's own first step periods (the default walker's first ``STEPS``, ``T_END`` s runs, as issue
27's reproductions; the compliant kneed walker's first ``KNEED_STEPS``, a described walker fitted by its named
parameter ``walker.parameters.thigh_mass``) at hidden values of a parameter pair, rounded to 1e-5 s, with the
rounding's own std (1e-5 / sqrt(12) s) as the reference's std, so that a fit that stops in another basin is seen
to miss the data. The hidden values are drawn uniformly over ``INTERIOR`` of each parameter's normalised range (a
truth on a bound is a different question: the fit then says "on a bound"); a draw at which the walker falls
before the reference's last step makes no reference and is drawn again (counted). A case is recovered when every
fitted value lies within ``TOLERANCE_SE`` standard errors of the truth, the RMS period error is at the rounding
(below ``ROUNDING_RMS_S``) and the verdict is converged; a case not recovered must at least not be a confident
wrong answer: its verdict must be "not converged" or "not identifiable" (``honest``).

The kneed walker's reference is shorter because each of its runs costs far more than the default walker's
(docs/experiments.md, "Cost, profiled"): three periods, which its thigh mass and foot stiffness move in different
proportions, so the pair is identifiable from them.
"""

from __future__ import annotations

import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import Config, derive, load_config
from biped_sim.io.references import Reference, ReferenceSpec
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.optimize import run_fit
from biped_sim.studies.fit.parameters import parse_parameter
from biped_sim.studies.fit.problem import FitProblem, simulate_outcome
from biped_sim.studies.fit.stats import FitResult, summarize
from biped_sim.studies.fit.synthetic import synthetic_reference_data

STEPS, T_END = 7, 3.5
KNEED_STEPS, KNEED_T_END = 3, 2.5
ROUNDING_S = 1e-5
ROUNDING_STD_S = ROUNDING_S / math.sqrt(12.0)  # 2.9 us: the rounding's own std
ROUNDING_RMS_S = 5e-6  # an RMS period error below this is at the rounding
TOLERANCE_SE = 3.0
INTERIOR = (0.1, 0.9)
MAX_DRAWS = 3  # draws per case at most (the walker must walk at the truth)
DEFAULT_WALKER = "configs/round_foot_walker.yaml"
KNEED_WALKER = "tests/data/kneed_compliant_parametrised.yaml"  # configs/kneed_walker_compliant.yaml, parametrised


@dataclass(frozen=True)
class Pair:
    """A parameter pair: the config its fits start from (a file of the repository, with ``changes``), the fitted
    ``KEY=LO:HI`` and the reference's length (its first ``steps`` periods, runs of ``t_end`` s)."""

    config: str
    changes: dict[str, Any]
    parameters: tuple[str, ...]
    steps: int = STEPS
    t_end: float = T_END


PAIRS: dict[str, Pair] = {
    "inertia+restitution": Pair(DEFAULT_WALKER, {}, ("walker.leg_inertia=0.004:0.007", "contact.restitution=0.1:0.9")),
    "stiffness+friction": Pair(
        DEFAULT_WALKER,
        {"contact.materials": None, "contact.stiffness": 3.24e7},
        ("contact.stiffness=1e7:1e8", "friction.mu_kinetic=0.3:0.9"),
    ),
    "kneed thigh mass+stiffness": Pair(
        KNEED_WALKER,
        {},
        ("walker.parameters.thigh_mass=0.4:0.6", "contact.stiffness=3e5:3e6"),
        KNEED_STEPS,
        KNEED_T_END,
    ),
}


@dataclass(frozen=True)
class Recovery:
    """One case: the hidden values, what the fit found, its verdict and cost."""

    pair: str
    hidden: dict[str, float]
    fitted: dict[str, float]
    standard_errors: dict[str, float | None]
    rms_s: float
    verdict: str
    recovered: bool
    evaluations: int
    wall_s: float

    @property
    def honest(self) -> bool:
        """Recovered, or a miss that says so (never a converged wrong answer)."""
        return self.recovered or self.verdict != "converged"


def start_config(pair: str, root: Path = Path(".")) -> Config:
    """The config a pair's fits start from: its file (under the repository's ``root``) with its changes."""
    spec = PAIRS[pair]
    return derive(load_config(root / spec.config), {**spec.changes, "simulation.t_end": spec.t_end})


def draw_cases(start: Config, pair: str, count: int, seed: int) -> tuple[list[dict[str, float]], int]:
    """``count`` hidden value sets for ``pair``, uniform over INTERIOR of each normalised range (seeded), each one
    whose walker takes the reference's steps (a truth that falls makes no reference); and how many were drawn."""
    steps = PAIRS[pair].steps
    parameters = [parse_parameter(text, start) for text in PAIRS[pair].parameters]
    rng, cases, drawn = np.random.default_rng(seed), [], 0
    while len(cases) < count and drawn < MAX_DRAWS * count:
        drawn += 1
        row = rng.uniform(*INTERIOR, size=len(parameters))
        hidden = {p.key: float(f"{p.from_unit(u):.6g}") for p, u in zip(parameters, row, strict=True)}
        data = derive(start, {**hidden, "simulation.max_steps": steps}).model_dump(mode="json")
        if simulate_outcome(data).strikes >= steps:
            cases.append(hidden)
    return cases, drawn


def recovery_problem(start: Config, pair: str, hidden: dict[str, float]) -> FitProblem:
    """The fit of ``pair`` against ``start``'s periods at ``hidden`` (rounded, with the rounding's std)."""
    steps = PAIRS[pair].steps
    data = synthetic_reference_data(derive(start, hidden), steps, 0.0, 0, decimals=5)
    data["std"] = [ROUNDING_STD_S] * steps
    reference = Reference(Path("synthetic"), ReferenceSpec.model_validate(data))
    return FitProblem(start, reference, tuple(parse_parameter(text, start) for text in PAIRS[pair].parameters))


def judge(pair: str, hidden: dict[str, float], result: FitResult, wall_s: float) -> Recovery:
    """Whether ``result`` recovered ``hidden`` (see the module docstring)."""
    rms = result.after.stats.rms_abs if result.after is not None else math.nan
    close = all(
        e.standard_error is not None and abs(e.value - hidden[e.key]) <= TOLERANCE_SE * e.standard_error
        for e in result.estimates
    )
    recovered = close and rms < ROUNDING_RMS_S and result.converged
    errors = {e.key: e.standard_error for e in result.estimates}
    evaluations = result.simulations + result.replayed
    return Recovery(pair, hidden, result.parameters, errors, rms, result.verdict, recovered, evaluations, wall_s)


def recover(start: Config, pair: str, hidden: dict[str, float], executor: Executor | None = None) -> Recovery:
    """Fit one case from ``start`` (:func:`start_config`; its simulations on ``executor``) and judge it."""
    clock = time.perf_counter()
    evaluator = Evaluator(recovery_problem(start, pair, hidden), executor)
    result = summarize(run_fit(evaluator), evaluator)
    return judge(pair, hidden, result, time.perf_counter() - clock)


def summary(recoveries: list[Recovery]) -> dict[str, Any]:
    """Per pair: cases, recovered, the rate, the honest misses, the mean evaluations and wall time per fit."""
    out: dict[str, Any] = {}
    for pair in dict.fromkeys(r.pair for r in recoveries):
        mine = [r for r in recoveries if r.pair == pair]
        out[pair] = {
            "cases": len(mine),
            "recovered": sum(r.recovered for r in mine),
            "rate": sum(r.recovered for r in mine) / len(mine),
            "dishonest_misses": sum(not r.honest for r in mine),
            "evaluations_per_fit": float(np.mean([r.evaluations for r in mine])),
            "wall_s_per_fit": float(np.mean([r.wall_s for r in mine])),
            "misses": [{"hidden": r.hidden, "fitted": r.fitted, "verdict": r.verdict} for r in mine if not r.recovered],
        }
    return out
