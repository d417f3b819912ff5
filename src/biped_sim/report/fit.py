"""A fit's files: fit.json, fitted.yaml, its tables and figures, and in the Bayesian mode posterior.h5.

:func:`write_calibration` writes one fit into a directory, :func:`write_contest` a contest (one
sub-directory per value, the ranking and the per-step error figure). Every file is written atomically;
the CLI stages the whole directory (:func:`~biped_sim.io.output.staged_directory`), a Python caller may
do the same. ``FIT_OUTPUT`` names what a fit directory may hold (checked before any work).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from biped_sim.io.atomic import write_json_atomic, write_text_atomic
from biped_sim.io.output import OutputKind
from biped_sim.io.posterior import POSTERIOR_FILE, Posterior, write_posterior
from biped_sim.io.provenance import provenance
from biped_sim.io.tables import Column, Table
from biped_sim.plots import comparisons_figure, save_figure
from biped_sim.report.fit_figures import contest_errors_figure, corner_figure, predictive_figure, profile_figure
from biped_sim.studies.compare import stats_table, step_table
from biped_sim.studies.fit import Calibration
from biped_sim.studies.fit.bayes import PosteriorRun
from biped_sim.studies.fit.document import fit_document, parameter_table, target_table
from biped_sim.studies.fit.ranking import evidence, ranked, ranking_table

FIT_FILES = (
    "fit.json", "fitted.yaml", "fit_parameters.*", "fit_targets.*", "fit_steps.*", "fit_stats.*", "fit_periods.*",
    "fit_profiles.*", "compare_steps.*", "compare_stats.*", "compare.png", "compare.svg", POSTERIOR_FILE,
    "posterior.*", "posterior_corner.*", "posterior_predictive.*", "*.checkpoint.json",
)  # fmt: skip
FIT_OUTPUT = OutputKind("fit", (*FIT_FILES, *(f"*/{name}" for name in FIT_FILES), "ranking.*", "contest_errors.*"))


def label_dir(label: str) -> str:
    """A contest value as a directory name."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", label)


def posterior_document(posterior: PosteriorRun) -> dict[str, Any]:
    """fit.json's ``posterior`` section: intervals, diagnostics, warnings, priors."""
    return {
        "file": POSTERIOR_FILE,
        "draws_kept": len(posterior.samples),
        "walkers": posterior.chain.shape[1],
        "steps": posterior.chain.shape[0],
        "evaluations": posterior.evaluations,
        "discard": posterior.discard,
        "thin": posterior.thin,
        "seed": posterior.seed,
        "acceptance_fraction": posterior.acceptance,
        "autocorrelation_time": dict(zip(posterior.keys, posterior.autocorrelation, strict=True)),
        "intervals_90": {k: {"low": lo, "median": mid, "high": hi} for k, (lo, mid, hi) in posterior.intervals.items()},
        "correlation": posterior.correlation.tolist() if posterior.correlation is not None else None,
        "warnings": posterior.warnings,
        "priors": [vars(p) for p in posterior.priors],
        "sampler": "emcee.EnsembleSampler (stretch move)",
    }


def interval_table(posterior: PosteriorRun) -> Table:
    """One row per parameter: the posterior median and 90 % credible interval."""
    columns = [Column("key", "parameter"), Column("median", "median", fmt=".6g"), Column("low", "5 %", fmt=".6g"),
               Column("high", "95 %", fmt=".6g"), Column("tau", "autocorr. time", fmt=".3g")]  # fmt: skip
    rows = [
        {"key": k, "low": lo, "median": mid, "high": hi, "tau": tau}
        for (k, (lo, mid, hi)), tau in zip(posterior.intervals.items(), posterior.autocorrelation, strict=True)
    ]
    notes = [f"{len(posterior.samples)} draws kept (burn-in {posterior.discard} steps, thin {posterior.thin})."]
    notes += [f"Warning: {w}." for w in posterior.warnings]
    return Table("posterior", "Posterior: median and 90 % credible interval", columns, rows, notes)


def _write_posterior(calibration: Calibration, directory: Path) -> None:
    posterior, result = calibration.posterior, calibration.result
    assert posterior is not None
    attributes = {
        "config_hash": result.run.problem.config.hash(),
        "acceptance_fraction": posterior.acceptance,
        "autocorrelation_time": posterior.autocorrelation,
        "discard": posterior.discard,
        "thin": posterior.thin,
        "seed": posterior.seed,
        **provenance(),
    }
    datasets = {"chain": posterior.chain, "chain_log_probability": posterior.chain_log_probability}
    record = Posterior(
        posterior.keys, posterior.samples, posterior.log_probability, result.run.problem.config.to_yaml()
    )
    write_posterior(directory / POSTERIOR_FILE, record, attributes, datasets)
    interval_table(posterior).write(directory)
    save_figure(corner_figure(posterior), directory, "posterior_corner")
    save_figure(predictive_figure(calibration), directory, "posterior_predictive")


def write_calibration(
    calibration: Calibration, directory: Path, config_path: str | None = None, extra: dict[str, Any] | None = None
) -> dict[str, Any]:
    """One fit's files in ``directory`` (``extra``: more top-level entries of fit.json); returns fit.json's content."""
    result = calibration.result
    directory.mkdir(parents=True, exist_ok=True)
    reference = result.run.problem.reference
    header = f"# Fitted by biped-sim fit against {reference.path} (see fit.json); runnable with biped-sim run.\n"
    write_text_atomic(directory / "fitted.yaml", header + result.fitted_config.to_yaml())
    tables = [parameter_table(result), target_table(result)]
    if result.before is not None and result.after is not None:
        pair = [result.before, result.after]
        tables += [step_table(pair, "fit_steps"), stats_table(pair, "fit_stats")]
        tables += [step_table([result.after]), stats_table([result.after])]
        save_figure(comparisons_figure([result.after]), directory, "compare")
        save_figure(comparisons_figure([result.before, result.after]), directory, "fit_periods")
    for table in tables:
        table.write(directory)
    save_figure(profile_figure(result), directory, "fit_profiles")
    doc = fit_document(result, config_path)
    if calibration.posterior is not None:
        _write_posterior(calibration, directory)
        doc["posterior"] = posterior_document(calibration.posterior)
    doc.update(extra or {})
    write_json_atomic(directory / "fit.json", doc)
    return doc


def write_contest(
    key: str, fits: list[tuple[str, Calibration]], directory: Path, config_path: str | None = None
) -> tuple[Table, list[dict[str, Any]]]:
    """A contest's files: one sub-directory per value, ``ranking.*`` and ``contest_errors.*``."""
    docs = [
        write_calibration(c, directory / label_dir(label), config_path, {"evidence": vars(evidence(c.result))})
        for label, c in fits
    ]
    results = [(label, c.result) for label, c in fits]
    ranking = ranking_table(key, results)
    ranking.write(directory)
    save_figure(contest_errors_figure([(e.label, e.result) for e in ranked(key, results)]), directory, "contest_errors")
    return ranking, docs
