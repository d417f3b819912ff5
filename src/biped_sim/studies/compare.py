"""Per-step error tables of a model's step periods against a reference (measured) period series.

For each reference step k: reference period T_ref, model period T_mod, error T_mod - T_ref [s],
its absolute value, and the relative error |T_mod - T_ref| / T_ref in percent; then the mean,
the maximum and the root mean square of the absolute and relative errors over the compared
steps. Published errors of another model against the same experiment (e.g. Corral et al. 2020
against Liu's walker) are shown beside ours, step by step.

Model steps are counted from the release: the initial state is "just after a heel strike" (the
config's convention), so step 1 lasts from t = 0 to the first heel strike, step k from strike
k - 1 to strike k. ``skip`` drops the first model steps when the experiment's step 1 is later. A
reference numbered from the first heel strike (``step_origin: heel_strike``, as a run's steps.csv)
meets model step k + 1 at its step k (:attr:`~biped_sim.io.references.Reference.origin_offset`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from biped_sim.io.references import Reference
from biped_sim.io.tables import Column, Table


def model_step_periods(step_times: Sequence[float], skip: int = 0) -> list[float]:
    """Periods of the model's steps from the release at t = 0 (see the module docstring)."""
    times = np.concatenate([[0.0], np.asarray(step_times, dtype=float)])
    return np.diff(times)[skip:].tolist()


@dataclass(frozen=True)
class ErrorStats:
    """Mean, max and RMS of |error| [s] and of the relative error [%] over the compared steps."""

    n: int
    mean_abs: float
    max_abs: float
    rms_abs: float
    mean_rel: float
    max_rel: float
    rms_rel: float


def mean_max_rms(values: Sequence[float]) -> tuple[int, float, float, float]:
    """(count, mean, max, RMS) of the absolute values of the finite entries."""
    v = np.abs(np.asarray(values, dtype=float))
    v = v[np.isfinite(v)]
    if not len(v):
        return 0, math.nan, math.nan, math.nan
    return len(v), float(np.mean(v)), float(np.max(v)), float(np.sqrt(np.mean(v**2)))


def error_stats(errors: Sequence[float], relative: Sequence[float]) -> ErrorStats:
    """Statistics over the steps where the model has a period (errors are NaN elsewhere)."""
    n, mean_abs, max_abs, rms_abs = mean_max_rms(errors)
    _, mean_rel, max_rel, rms_rel = mean_max_rms(relative)
    return ErrorStats(n, mean_abs, max_abs, rms_abs, mean_rel, max_rel, rms_rel)


@dataclass
class Comparison:
    """One model period series against a reference, step by step."""

    label: str
    reference: Reference
    steps: list[int]
    reference_periods: list[float]
    model_periods: list[float]  # NaN where the model has no such step
    errors: list[float]  # model - reference [s]
    relative_errors: list[float]  # |model - reference| / reference [%]
    stats: ErrorStats
    published: dict[str, list[float]] = field(default_factory=dict)  # short citation -> errors [%] per step

    @property
    def compared(self) -> int:
        return self.stats.n


def compare_periods(reference: Reference, model_periods: Sequence[float], label: str = "model") -> Comparison:
    """The per-step comparison of ``model_periods`` (step 1 first) with a step-period reference."""
    if not reference.is_periods:
        raise ValueError("compare_periods needs a step_period reference")
    steps, offset = reference.steps, reference.origin_offset
    ref = reference.values
    model = [float(model_periods[s - 1 + offset]) if s + offset <= len(model_periods) else math.nan for s in steps]
    errors = [m - r for m, r in zip(model, ref, strict=True)]
    relative = [abs(e) / r * 100.0 for e, r in zip(errors, ref, strict=True)]
    published: dict[str, list[float]] = {}
    for other in reference.published_errors:
        by_step = dict(zip(other.steps, other.values, strict=True))
        published[other.short_name] = [by_step.get(s, math.nan) for s in steps]
    return Comparison(
        label=label,
        reference=reference,
        steps=steps,
        reference_periods=ref,
        model_periods=model,
        errors=errors,
        relative_errors=relative,
        stats=error_stats(errors, relative),
        published=published,
    )


def _published_key(name: str) -> str:
    return "published::" + name


def step_table(comparisons: Sequence[Comparison], name: str = "compare_steps") -> Table:
    """Per-step table: reference, model, error, |error|, relative error (and published errors).

    Several comparisons (a sweep) share one table with a leading 'series' column.
    """
    reference = comparisons[0].reference
    several = len(comparisons) > 1
    columns = [Column("label", "series")] if several else []
    columns += [Column("step", "step"), Column("reference", "reference period", "s", ".4f")]
    std = reference.std
    if std is not None:
        columns.append(Column("std", "reference std", "s", ".4f"))
    columns += [
        Column("model", "model period", "s", ".4f"),
        Column("error", "error (model - ref.)", "s", "+.4f"),
        Column("abs_error", "|error|", "s", ".4f"),
        Column("relative_error", "relative error", "%", ".2f"),
    ]
    published = list(comparisons[0].published)
    columns += [Column(_published_key(n), f"{n} error", "%", ".2f") for n in published]
    rows: list[dict[str, Any]] = []
    for comparison in comparisons:
        for i, step in enumerate(comparison.steps):
            row: dict[str, Any] = {
                "label": comparison.label,
                "step": step,
                "reference": comparison.reference_periods[i],
                "model": comparison.model_periods[i],
                "error": comparison.errors[i],
                "abs_error": abs(comparison.errors[i]),
                "relative_error": comparison.relative_errors[i],
            }
            if std is not None:
                row["std"] = std[i]
            for n in published:
                row[_published_key(n)] = comparison.published[n][i]
            rows.append(row)
    notes = [
        f"Reference: {reference.citation_text()} {reference.source_text()}.",
        reference.numbering_text(),
    ]
    for other in reference.published_errors:
        notes.append(
            f"{other.short_name} error: {other.spec.compared or other.spec.description} "
            f"({other.source_text()}); their model, not this one."
        )
    for comparison in comparisons:
        missing = sum(1 for m in comparison.model_periods if math.isnan(m))
        if missing:
            notes.append(f"{comparison.label}: no model period for {missing} reference step(s) (it stopped earlier).")
    title = f"Step periods against {reference.short_name}" + ("" if several else f": {comparisons[0].label}")
    return Table(name, title, columns, rows, notes)


def stats_table(comparisons: Sequence[Comparison], name: str = "compare_stats") -> Table:
    """One row per compared series (and per published error series): mean, max, RMS errors."""
    columns = [
        Column("label", "series"),
        Column("n", "steps"),
        Column("mean_abs", "mean |error|", "s", ".4f"),
        Column("max_abs", "max |error|", "s", ".4f"),
        Column("rms_abs", "RMS error", "s", ".4f"),
        Column("mean_rel", "mean rel. error", "%", ".2f"),
        Column("max_rel", "max rel. error", "%", ".2f"),
        Column("rms_rel", "RMS rel. error", "%", ".2f"),
    ]
    rows: list[dict[str, Any]] = [{"label": c.label, **vars(c.stats)} for c in comparisons]
    if comparisons:
        for other_name, values in comparisons[0].published.items():
            n, mean_rel, max_rel, rms_rel = mean_max_rms(values)
            label = f"{other_name} (published)"
            rows.append({"label": label, "n": n, "mean_rel": mean_rel, "max_rel": max_rel, "rms_rel": rms_rel})
    reference = comparisons[0].reference if comparisons else None
    title = f"Step-period errors against {reference.short_name}" if reference else "Step-period errors"
    notes = ["Published rows: relative errors as reported (no periods available, so no errors in seconds)."]
    return Table(name, title, columns, rows, notes if len(rows) > len(comparisons) else [])
