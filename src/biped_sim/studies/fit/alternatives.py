"""Identifiability said plainly: distinct parameter sets that the fit finds fitting the data equally well.

The global stage polishes several basins (:attr:`~biped_sim.studies.fit.optimize.FitRun.basins`). Another
basin is an alternative to the best when it is both

* as good within the noise: its cost rises by ``delta chi2 = 2 (cost - best) / s^2`` no more than the
  ``LEVEL`` quantile of chi2 with p degrees of freedom (it lies inside the best fit's joint confidence
  region by the likelihood ratio; ``s^2`` is 1 with a reference std, else the residual variance), and
* distinct: more than ``APART_SE`` standard errors from the best in some parameter.

Then the data do not pick one, and the fit says so instead of choosing: its verdict is "not identifiable",
listing the sets and what separates them: both simulated ``EXTRA_STEPS`` steps beyond the reference, the
largest difference of each step quantity and the step where it falls (a longer trial or another measured
quantity that would tell them apart).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2 as chi2_distribution

from biped_sim.io.references import MEASURED_UNITS
from biped_sim.studies.fit.optimize import FitRun
from biped_sim.studies.fit.problem import FitProblem, Outcome, simulate_outcome

LEVEL = 0.95  # the confidence region's level: a basin inside it fits as well within the noise
APART_SE = 3.0  # standard errors apart in some parameter: a distinct parameter set
EXTRA_STEPS = 5  # steps simulated beyond the reference to say what separates two sets


@dataclass(frozen=True)
class Alternative:
    """A distinct parameter set that fits as well as the best within the noise, and what tells them apart."""

    parameters: dict[str, float]
    cost: float
    delta_chi_square: float  # 2 (cost - best cost) / s^2
    separation: list[str]  # per quantity: its largest difference from the best set and the step where it falls


def _longer(problem: FitProblem, u: np.ndarray) -> Outcome:
    """The outcome at ``u`` simulated EXTRA_STEPS steps beyond the reference's last."""
    data = problem.evaluation_data(u)
    data["simulation"]["max_steps"] += EXTRA_STEPS
    data["simulation"]["t_end"] *= (problem.model_steps + EXTRA_STEPS) / problem.model_steps
    return simulate_outcome(data)


def separation(problem: FitProblem, best: np.ndarray, other: np.ndarray) -> list[str]:
    """Per step quantity, the largest difference between the two sets over the reference's steps and beyond."""
    a, b = _longer(problem, best), _longer(problem, other)
    steps = range(1, problem.model_steps + EXTRA_STEPS + 1)
    out = []
    for quantity, unit in MEASURED_UNITS.items():
        diffs = np.array([b.value(quantity, j) - a.value(quantity, j) for j in steps])
        if not np.any(np.isfinite(diffs)):
            continue
        j = int(np.nanargmax(np.abs(diffs)))
        beyond = " (beyond the reference)" if steps[j] > problem.model_steps else ""
        out.append(f"{quantity} differs most at model step {steps[j]}{beyond}: {diffs[j]:+.3g} {unit}")
    return out


def alternatives(run: FitRun, s2: float, covariance_u: np.ndarray) -> list[Alternative]:
    """The polished basins other than the best that fit as well within the noise and are distinct from it."""
    if not math.isfinite(s2) or s2 <= 0:
        return []
    problem, best = run.problem, run.polish
    limit = float(chi2_distribution.ppf(LEVEL, len(problem.parameters)))
    se = np.sqrt(np.clip(np.diag(covariance_u), 0.0, None))
    out = []
    for basin in run.basins[1:]:
        delta = 2.0 * (basin.cost - best.cost) / s2
        if delta <= limit and bool(np.any(np.abs(basin.u - best.u) > APART_SE * se)):
            values = problem.values(basin.u)
            out.append(Alternative(values, basin.cost, delta, separation(problem, best.u, basin.u)))
    return out
