"""fit.json's content and the fit's tables: what was fitted to what, what it found, and how far to trust it."""

from __future__ import annotations

import math
from typing import Any

from biped_sim.io.provenance import provenance
from biped_sim.io.tables import Column, Table
from biped_sim.studies.compare import Comparison
from biped_sim.studies.fit.diagnose import JUMP_RATIO, PROFILE_POINTS, PROFILE_WIDTH_SE
from biped_sim.studies.fit.optimize import (
    BASIN_RADIUS,
    CMA_SETTINGS,
    DE_SETTINGS,
    FD_STEP,
    GRID_POINTS,
    IPOP_SETTINGS,
    POLISH_EVALUATIONS,
    POLISH_STARTS,
    SOBOL_PER_PARAMETER,
    TOLERANCES,
    FitRun,
)
from biped_sim.studies.fit.parameters import LOG_SPAN
from biped_sim.studies.fit.problem import PENALTY_SCALES
from biped_sim.studies.fit.stats import FitResult


def _per_step(comparison: Comparison | None) -> dict[str, list[float]] | None:
    if comparison is None:
        return None
    return {
        "model": comparison.model_periods,
        "error_s": comparison.errors,
        "error_percent": comparison.relative_errors,
    }


def targets_used(result: FitResult) -> dict[str, Any]:
    """Which quantities at which steps the fit used, with the step numbering said."""
    problem = result.run.problem
    by_quantity: dict[str, list[int]] = {}
    for t in problem.targets:
        by_quantity.setdefault(t.quantity, []).append(t.step)
    return {
        "quantities": by_quantity,
        "step_origin": problem.reference.spec.step_origin,
        "numbering": problem.reference.numbering_text(),
        "skip_steps": problem.skip,
        "model_steps": [t.model_step for t in problem.targets],
        "weights": "1 / (std / sqrt(n_trials))" if problem.weighted else "unit weights (no std in the reference)",
    }


def _global_settings(run: FitRun) -> dict[str, Any]:
    """The settings of the global stage that ran."""
    if run.global_method == "multistart" or run.global_stage.name == "grid":
        grid = run.global_stage.name == "grid"
        design = {"grid_points": GRID_POINTS} if grid else {"sobol_per_parameter": SOBOL_PER_PARAMETER}
        return design | {"basin_radius": BASIN_RADIUS, "polish_starts": POLISH_STARTS, "ipop_cma": IPOP_SETTINGS}
    return DE_SETTINGS if run.global_method == "de" else CMA_SETTINGS


def _method(result: FitResult) -> dict[str, Any]:
    run = result.run
    return {
        "global_method": run.global_method,
        "global_stage": run.global_stage.name,
        "global_settings": _global_settings(run),
        "seed": run.seed,
        "polish": "scipy.optimize.least_squares (trf), variables normalised to [0, 1] over the bounds",
        "log_scale_when_bounds_span": LOG_SPAN,
        "jacobian": f"forward differences, step {FD_STEP:g} of the normalised range",
        "polish_tolerances": TOLERANCES,
        "polish_max_evaluations": POLISH_EVALUATIONS,
        "missed_step_penalty_scales": PENALTY_SCALES,
        "evaluation_formulation": run.problem.evaluation_formulation,
        "profile": f"{PROFILE_POINTS} points each side, spaced {PROFILE_WIDTH_SE:g} standard error(s); "
        f"a jump: second difference > {JUMP_RATIO:g} of the largest first difference",
    }


def fit_document(result: FitResult, config_path: str | None = None) -> dict[str, Any]:
    """The fit as JSON-ready data: parameters, errors, statistics, scans, verdict, targets, configs, provenance."""
    run, ident, problem = result.run, result.identifiability, result.run.problem
    after = result.after
    keys = [e.key for e in result.estimates]
    return {
        "parameters": result.parameters,
        "converged": result.converged,
        "verdict": result.verdict,
        "alternatives": [vars(a) for a in result.alternatives],
        "misfit": result.misfit,
        "rms_error_s": after.stats.rms_abs if after is not None else None,
        "max_error_s": after.stats.max_abs if after is not None else None,
        "rms_error_percent": after.stats.rms_rel if after is not None else None,
        "rms_weighted_residual": result.rms_residual,
        "chi_square": result.chi_square,
        "evaluations": result.simulations + result.replayed,
        "simulations": result.simulations,
        "evaluations_replayed": result.replayed,
        "wall_time_s": run.wall_time_s,
        "stages": [vars(s) | {"u": list(s.u), "point": problem.values(s.u)} for s in (run.global_stage, *run.basins)],
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
        "profiles": [vars(p) for p in result.profiles],
        "targets": targets_used(result),
        "per_target": [vars(t) | {"model": float(m)} for t, m in zip(problem.targets, result.model_after, strict=True)],
        "per_step": {
            "step": after.steps if after is not None else None,
            "reference": after.reference_periods if after is not None else None,
            "std": problem.reference.std,
            "before": _per_step(result.before),
            "after": _per_step(after),
        },
        "method": _method(result),
        "reference": {"path": str(problem.reference.path), "experiment": problem.reference.spec.experiment},
        "config_path": config_path,
        "start_config": problem.config.model_dump(mode="json"),
        "start_config_hash": problem.config.hash(),
        "config": result.fitted_config.model_dump(mode="json"),
        "config_hash": result.fitted_config.hash(),
        "provenance": provenance(),
    }


def parameter_table(result: FitResult, name: str = "fit_parameters") -> Table:
    """One row per parameter: bounds, start, fitted value and standard error; the verdict in the notes."""
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
    notes.append(result.verdict[0].upper() + result.verdict[1:] + ".")
    notes += [f"Warning: {result.misfit}."] if result.misfit else []
    notes += [f"Warning: {w}." for w in result.identifiability.warnings]
    return Table(name, "Fitted parameters", columns, rows, notes)


def target_table(result: FitResult, name: str = "fit_targets") -> Table:
    """Every target: quantity, step, measured mean and its standard error, the fitted model, the residual."""
    columns = [
        Column("quantity", "quantity"),
        Column("step", "step"),
        Column("mean", "measured mean", fmt=".6g"),
        Column("sigma", "std error", fmt=".3g"),
        Column("n_trials", "trials"),
        Column("model", "fitted model", fmt=".6g"),
        Column("residual", "residual [std errors]", fmt="+.3f"),
    ]
    problem = result.run.problem
    residuals = problem.residuals(result.after_outcome)
    rows = [
        vars(t) | {"model": float(m), "residual": float(r) if math.isfinite(m) else math.nan}
        for t, m, r in zip(problem.targets, result.model_after, residuals, strict=True)
    ]
    notes = [problem.reference.numbering_text(), f"Weights: {targets_used(result)['weights']}."]
    return Table(name, f"Fitted targets against {problem.reference.short_name}", columns, rows, notes)
