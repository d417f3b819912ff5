"""What a fit (:mod:`biped_sim.studies.fit`) found: estimates, standard errors, identifiability, tables.

The covariance of the normalised variables is ``s^2 (J^T J)^+`` at the solution, with ``s^2 = 1`` when
the reference gives a std per step (the residuals are then in units of it) and the residual variance
``|r|^2 / (n - p)`` otherwise; it is carried to the parameters' units by the slope of each variable's
map (linear or log). The fit is flagged as not identifiable when the Jacobian is rank-deficient
(a singular value below ``RANK_TOLERANCE`` of the largest: a direction the periods do not see), when two
parameters correlate beyond ``CORRELATION_LIMIT``, or when a standard error exceeds its parameter's
bound range (the periods hardly depend on it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from biped_sim.config import Config
from biped_sim.io.tables import Column, Table
from biped_sim.studies.compare import Comparison, compare_periods, model_step_periods
from biped_sim.studies.fit import (
    FD_STEP,
    LOG_SPAN,
    MAX_RESIDUAL_EVALUATIONS,
    PENALTY_PERIODS,
    QMC_SEED,
    TOLERANCES,
    FitRun,
    Outcome,
)

RANK_TOLERANCE = 1e-6
CORRELATION_LIMIT = 0.99


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
    warnings: list[str]


def _covariance(jacobian: np.ndarray, s2: float) -> tuple[np.ndarray, Identifiability, set[int]]:
    """(covariance in normalised variables, rank and correlations, indices of the unresolved parameters)."""
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=True)
    p = jacobian.shape[1]
    singular = np.concatenate([singular, np.zeros(p - len(singular))])
    largest = singular[0] if len(singular) else 0.0
    resolved = singular > RANK_TOLERANCE * largest if largest > 0 else np.zeros(p, dtype=bool)
    unresolved = {int(j) for k in np.flatnonzero(~resolved) for j in np.flatnonzero(np.abs(vt[k]) > 0.5)}
    inverse = np.linalg.pinv(jacobian.T @ jacobian, rcond=RANK_TOLERANCE**2)
    covariance = s2 * inverse
    sd = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = covariance / np.outer(sd, sd)
    identifiability = Identifiability(int(resolved.sum()), singular.tolist(), correlation, [])
    return covariance, identifiability, unresolved


def _warnings(estimates: list[Estimate], ident: Identifiability, unresolved: set[int]) -> list[str]:
    """Why the data may not fix the parameters (empty when they do)."""
    warnings = []
    p = len(estimates)
    if ident.rank < p:
        names = ", ".join(estimates[j].key for j in sorted(unresolved)) or "a combination of parameters"
        warnings.append(f"Jacobian rank {ident.rank} < {p} parameters: the periods do not determine {names}")
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
    """A finished fit: estimates, statistics, the comparisons before and after, and the fitted config."""

    run: FitRun
    estimates: list[Estimate]
    identifiability: Identifiability
    residual_variance: float
    variance_source: str
    before: Comparison
    after: Comparison
    fitted_config: Config

    @property
    def converged(self) -> bool:
        """The optimizer met a tolerance and the fitted walker reaches every reference step."""
        return self.run.best.status > 0 and self.after.compared == len(self.after.steps)

    @property
    def parameters(self) -> dict[str, float]:
        return {e.key: e.value for e in self.estimates}

    def to_json(self) -> dict[str, Any]:
        """fit.json's content (provenance and configs are added by the writer)."""
        return fit_document(self)


def _comparison(run: FitRun, outcome: Outcome, label: str) -> Comparison:
    periods = model_step_periods(outcome.step_times, run.problem.skip)
    return compare_periods(run.problem.reference, periods, label)


def summarize(run: FitRun) -> FitResult:
    """Estimates, standard errors and identifiability at the best start's solution."""
    problem, best = run.problem, run.best
    n, p = len(best.residuals), len(problem.parameters)
    if problem.reference.spec.std is not None:
        s2, source = 1.0, "reference std"
    else:
        s2 = float(best.residuals @ best.residuals) / (n - p) if n > p else math.nan
        source = "residual variance"
    covariance, ident, unresolved = _covariance(best.jacobian, s2)
    estimates = []
    for j, (parameter, u) in enumerate(zip(problem.parameters, best.u, strict=True)):
        se = abs(parameter.slope(float(u))) * math.sqrt(max(covariance[j, j], 0.0))
        known = j not in unresolved and math.isfinite(se)
        estimates.append(
            Estimate(
                parameter.key,
                parameter.low,
                parameter.high,
                parameter.log,
                parameter.start,
                parameter.from_unit(float(u)),
                se if known else None,
                bool(u <= 1e-9 or u >= 1 - 1e-9),
            )
        )
    ident.warnings = _warnings(estimates, ident, unresolved)
    if not math.isfinite(s2):
        ident.warnings.append(f"{n} reference steps for {p} parameters: no residual variance, no standard errors")
    return FitResult(
        run=run,
        estimates=estimates,
        identifiability=ident,
        residual_variance=s2,
        variance_source=source,
        before=_comparison(run, run.start_outcome, "start"),
        after=_comparison(run, run.best_outcome, "fitted"),
        fitted_config=problem.config_at({e.key: e.value for e in estimates}),
    )


def _per_step(comparison: Comparison) -> dict[str, list[float]]:
    return {
        "model": comparison.model_periods,
        "error_s": comparison.errors,
        "error_percent": comparison.relative_errors,
    }


def fit_document(result: FitResult) -> dict[str, Any]:
    """The fit as JSON-ready data: parameters, errors, statistics, per-step errors, starts and method."""
    run, after, ident = result.run, result.after, result.identifiability
    keys = [e.key for e in result.estimates]
    return {
        "parameters": result.parameters,
        "rms_error_s": after.stats.rms_abs,
        "max_error_s": after.stats.max_abs,
        "rms_error_percent": after.stats.rms_rel,
        "max_error_percent": after.stats.max_rel,
        "converged": result.converged,
        "status": run.best.status,
        "convergence_reason": run.best.message,
        "steps_compared": after.compared,
        "reference_steps": len(after.steps),
        "evaluations": run.evaluations,
        "wall_time_s": run.wall_time_s,
        "estimates": [vars(e) | {"scale": "log" if e.log else "linear"} for e in result.estimates],
        "correlation": {"keys": keys, "matrix": ident.correlation.tolist()},
        "residual_variance": result.residual_variance,
        "variance_source": result.variance_source,
        "identifiability": {
            "rank": ident.rank,
            "singular_values": ident.singular_values,
            "identifiable": not ident.warnings,
            "warnings": ident.warnings,
        },
        "per_step": {
            "step": after.steps,
            "reference": after.reference_periods,
            "std": run.problem.reference.spec.std,
            "before": _per_step(result.before),
            "after": _per_step(after),
        },
        "starts": [
            {
                "start": run.problem.values(s.start),
                "fitted": run.problem.values(s.u),
                "cost": s.cost,
                "status": s.status,
                "message": s.message,
                "residual_evaluations": s.residual_evaluations,
            }
            for s in run.starts
        ],
        "method": {
            "optimizer": "scipy.optimize.least_squares (trf), variables normalised to [0, 1] over the bounds",
            "log_scale_when_bounds_span": LOG_SPAN,
            "jacobian": f"forward differences, step {FD_STEP:g} of the normalised range",
            "missed_step_penalty_periods": PENALTY_PERIODS,
            "tolerances": TOLERANCES,
            "max_residual_evaluations_per_start": MAX_RESIDUAL_EVALUATIONS,
            "multistart": f"config values, then scipy.stats.qmc.LatinHypercube(seed={QMC_SEED})",
            "qmc_seed": QMC_SEED,
        },
        "skip_steps": run.problem.skip,
        "reference": {"path": str(run.problem.reference.path), "experiment": run.problem.reference.spec.experiment},
    }


def parameter_table(result: FitResult, name: str = "fit_parameters") -> Table:
    """One row per parameter: bounds, start, fitted value and standard error."""
    columns = [
        Column("key", "parameter"),
        Column("scale", "scale"),
        Column("low", "low", fmt=".6g"),
        Column("high", "high", fmt=".6g"),
        Column("start", "start", fmt=".6g"),
        Column("value", "fitted", fmt=".6g"),
        Column("standard_error", "standard error", fmt=".3g"),
    ]
    rows = [vars(e) | {"scale": "log" if e.log else "linear"} for e in result.estimates]
    notes = [f"Standard errors from the Jacobian and the {result.variance_source}."]
    notes += [f"Warning: {w}." for w in result.identifiability.warnings]
    notes += [f"{e.key} is at a bound." for e in result.estimates if e.at_bound]
    return Table(name, "Fitted parameters", columns, rows, notes)


def ranking_table(key: str, fits: list[tuple[str, FitResult]], name: str = "ranking") -> Table:
    """The contest: one fit per value of ``key``, best (complete, lowest RMS error) first."""

    def order(item: tuple[str, FitResult]) -> tuple[bool, float]:
        rms = item[1].after.stats.rms_abs
        return (not item[1].converged, rms if math.isfinite(rms) else math.inf)

    columns = [
        Column("rank", "rank"),
        Column("value", key),
        Column("parameters", "fitted parameters"),
        Column("rms_abs", "RMS error", "s", ".4f"),
        Column("max_abs", "max |error|", "s", ".4f"),
        Column("rms_rel", "RMS rel. error", "%", ".2f"),
        Column("max_rel", "max rel. error", "%", ".2f"),
        Column("evaluations", "evaluations"),
        Column("converged", "converged"),
    ]
    rows = []
    for rank, (value, result) in enumerate(sorted(fits, key=order), start=1):
        stats = result.after.stats
        text = "; ".join(
            f"{e.key}={e.value:.4g}" + (f" ± {e.standard_error:.2g}" if e.standard_error is not None else "")
            for e in result.estimates
        )
        rows.append(
            {
                "rank": rank, "value": value, "parameters": text, "rms_abs": stats.rms_abs, "max_abs": stats.max_abs,
                "rms_rel": stats.rms_rel, "max_rel": stats.max_rel, "evaluations": result.run.evaluations,
                "converged": "yes" if result.converged else "no",
            }
        )  # fmt: skip
    notes = ["Each row is a separate fit of the same parameters and bounds at that value (its best parameters)."]
    return Table(name, f"Contest of {key} at each one's fitted parameters", columns, rows, notes)
