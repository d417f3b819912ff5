"""What a fit found: estimates, standard errors, identifiability, the profile scans and the verdict.

The covariance of the normalised variables is ``s^2 (J^T J)^+`` at the optimum, with ``s^2 = 1`` when the
reference gives a std per target (the residuals are then in units of the mean's standard error) and the
residual variance ``|r|^2 / (n - p)`` otherwise; it is carried to the parameters' units by the slope of
each variable's map (linear or log). The fit is flagged as not identifiable when the Jacobian is
rank-deficient (a singular value below ``RANK_TOLERANCE`` of the largest: a direction the data do not
see), when two parameters correlate beyond ``CORRELATION_LIMIT``, or when a standard error exceeds its
parameter's bound range. A standard error means something only where the objective is smooth: the
profile scans (:mod:`.diagnose`) say whether it is, and the verdict is not "converged" otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from biped_sim.config import Config
from biped_sim.io.references import Reference
from biped_sim.studies.compare import Comparison, compare_periods
from biped_sim.studies.fit.alternatives import Alternative, alternatives
from biped_sim.studies.fit.diagnose import (
    AT_BOUND,
    Profile,
    misfit,
    numbering_check,
    profile_scans,
    unreached_text,
    verdict,
)
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.optimize import FitRun
from biped_sim.studies.fit.problem import Outcome, simulate_outcome

RANK_TOLERANCE = 1e-6
CORRELATION_LIMIT = 0.99
UNIDENTIFIED_MARK = "the data do not determine"


@dataclass(frozen=True)
class Estimate:
    """One fitted parameter: bounds, start, value and standard error (None where the data do not fix it)."""

    key: str
    low: float
    high: float
    log: bool
    start: float
    value: float
    standard_error: float | None
    at_bound: bool


@dataclass
class Identifiability:
    """Rank and singular values of the Jacobian (normalised variables), correlations, and the warnings."""

    rank: int
    singular_values: list[float]
    correlation: np.ndarray
    warnings: list[str] = field(default_factory=list)


def covariance(jacobian: np.ndarray, s2: float) -> tuple[np.ndarray, Identifiability, set[int]]:
    """(covariance in normalised variables, rank and correlations, indices of the unresolved parameters)."""
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=True)
    p = jacobian.shape[1]
    singular = np.concatenate([singular, np.zeros(p - len(singular))])
    largest = singular[0] if len(singular) else 0.0
    resolved = singular > RANK_TOLERANCE * largest if largest > 0 else np.zeros(p, dtype=bool)
    unresolved = {int(j) for k in np.flatnonzero(~resolved) for j in np.flatnonzero(np.abs(vt[k]) > 0.5)}
    cov = s2 * np.linalg.pinv(jacobian.T @ jacobian, rcond=RANK_TOLERANCE**2)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = cov / np.outer(sd, sd)
    return cov, Identifiability(int(resolved.sum()), singular.tolist(), correlation), unresolved


def identifiability_warnings(estimates: list[Estimate], ident: Identifiability, unresolved: set[int]) -> list[str]:
    """Why the data may not fix the parameters (empty when they do)."""
    warnings, p = [], len(estimates)
    if ident.rank < p:
        names = ", ".join(estimates[j].key for j in sorted(unresolved)) or "a combination of parameters"
        warnings.append(f"Jacobian rank {ident.rank} < {p} parameters: {UNIDENTIFIED_MARK} {names}")
    for i in range(p):
        for j in range(i + 1, p):
            c = ident.correlation[i, j]
            if math.isfinite(c) and abs(c) > CORRELATION_LIMIT:
                warnings.append(f"{estimates[i].key} and {estimates[j].key} correlate at {c:+.4f}")
    for e in estimates:
        if e.standard_error is not None and e.standard_error > e.high - e.low:
            warnings.append(f"{e.key}: standard error {e.standard_error:.3g} exceeds its bound range")
    return warnings


@dataclass
class FitResult:
    """A finished fit: estimates, statistics, scans, verdict, comparisons before and after, the fitted config."""

    run: FitRun
    estimates: list[Estimate]
    identifiability: Identifiability
    residual_variance: float
    variance_source: str
    profiles: list[Profile]
    reasons: list[str]  # why not converged (empty: converged)
    before: Comparison | None  # step periods at the start (None: the reference gives no periods)
    after: Comparison | None
    after_outcome: Outcome  # the fitted config run as given (its own formulation)
    fitted_config: Config
    misfit: str | None = None  # the data are not matched at the optimum (diagnose.misfit)
    simulations: int = 0  # run by the fit, the scans included
    replayed: int = 0  # read back from a checkpoint
    alternatives: list[Alternative] = field(default_factory=list)  # other sets that fit as well (.alternatives)

    @property
    def converged(self) -> bool:
        return not self.reasons and not self.alternatives

    @property
    def verdict(self) -> str:
        """ "converged", "not identifiable: ..." (other parameter sets fit as well) or "not converged: ..."."""
        if self.alternatives:
            sets = "; ".join(", ".join(f"{k} = {v:.6g}" for k, v in a.parameters.items()) for a in self.alternatives)
            text = f"not identifiable: {len(self.alternatives) + 1} distinct parameter sets fit within the noise "
            return text + f"(the best and {sets})" + "".join(f"; {r}" for r in self.reasons)
        return "converged" if not self.reasons else "not converged: " + "; ".join(self.reasons)

    @property
    def parameters(self) -> dict[str, float]:
        return {e.key: e.value for e in self.estimates}

    @property
    def model_after(self) -> np.ndarray:
        return self.run.problem.model_values(self.after_outcome)

    @property
    def rms_residual(self) -> float:
        """RMS of the weighted residuals at the optimum (in standard errors, or in the unit when unweighted)."""
        r = self.run.problem.residuals(self.after_outcome)
        return float(np.sqrt(np.mean(r**2)))

    @property
    def chi_square(self) -> float:
        r = self.run.problem.residuals(self.after_outcome)
        return float(r @ r)


def _periods(reference: Reference, outcome: Outcome, skip: int, label: str) -> Comparison | None:
    """The per-step comparison of the step periods (as ``compare`` would tabulate it), if the reference has periods."""
    if not reference.is_periods:
        return None
    return compare_periods(
        reference, [outcome.value("step_period", j) for j in range(1 + skip, outcome.strikes + 1)], label
    )


def _estimates(run: FitRun, cov: np.ndarray, unresolved: set[int]) -> list[Estimate]:
    out = []
    for j, (parameter, u) in enumerate(zip(run.problem.parameters, run.u, strict=True)):
        se = abs(parameter.slope(float(u))) * math.sqrt(max(cov[j, j], 0.0))
        known = j not in unresolved and math.isfinite(se)
        out.append(
            Estimate(
                parameter.key, parameter.low, parameter.high, parameter.log, parameter.start,
                parameter.from_unit(float(u)), se if known else None, bool(u <= AT_BOUND or u >= 1 - AT_BOUND),
            )
        )  # fmt: skip
    return out


def summarize(run: FitRun, evaluator: Evaluator) -> FitResult:
    """Estimates, standard errors, identifiability, profile scans and the verdict at the fit's optimum."""
    problem = run.problem
    n, p = len(run.residuals), len(problem.parameters)
    if problem.weighted:
        s2, source = 1.0, "reference std"
    else:
        s2 = float(run.residuals @ run.residuals) / (n - p) if n > p else math.nan
        source = "residual variance"
    cov, ident, unresolved = covariance(run.jacobian, s2 if math.isfinite(s2) else 1.0)
    estimates = _estimates(run, cov, unresolved)
    ident.warnings = identifiability_warnings(estimates, ident, unresolved)
    shifted = numbering_check(problem, np.array([q.to_unit(q.start) for q in problem.parameters]))
    if shifted is not None:
        ident.warnings.append(shifted)
    if not math.isfinite(s2):
        ident.warnings.append(f"{n} reference values for {p} parameters: no residual variance, no standard errors")
        estimates = [Estimate(**{**vars(e), "standard_error": None}) for e in estimates]
    curvature = np.diag(run.jacobian.T @ run.jacobian)
    with np.errstate(divide="ignore", invalid="ignore"):
        conditional = np.sqrt((s2 if math.isfinite(s2) else 1.0) / curvature)
    profiles = profile_scans(evaluator, run, conditional)
    fitted = problem.config_at({e.key: e.value for e in estimates})
    after_data = problem.evaluation_data(run.u)
    after_data["formulation"]["kind"] = problem.config.formulation.kind  # the fitted config as the user runs it
    after = simulate_outcome(after_data)
    unreached = [
        t.step for t, value in zip(problem.targets, problem.model_values(after), strict=True) if math.isnan(value)
    ]
    evaluator.save()
    others = alternatives(run, s2 if math.isfinite(s2) else 1.0, cov)
    totals = {"simulations": evaluator.evaluations, "replayed": evaluator.replayed, "alternatives": others}
    missed = misfit(run)  # another minimum or a model error: never a converged fit
    reasons = verdict(run, profiles, unreached_text(unreached, after)) + ([missed] if missed else [])
    return FitResult(
        run, estimates, ident, s2, source, profiles, reasons,
        _periods(problem.reference, run.start_outcome, problem.skip, "start"),
        _periods(problem.reference, after, problem.skip, "fitted"), after, fitted, missed, **totals,
    )  # fmt: skip
