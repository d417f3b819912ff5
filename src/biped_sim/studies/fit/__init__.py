"""Calibration of config keys against measured steps: the fit, its statistics, its posterior and the contest.

From Python (the CLI's ``biped-sim fit`` is this, plus flags)::

    from biped_sim import load_config
    from biped_sim.io.references import load_reference
    from biped_sim.studies.fit import calibrate, fit_problems
    from biped_sim.report.fit import write_calibration
    from biped_sim.sweep import study_executor

    config = load_config("configs/round_foot_walker.yaml")
    reference = load_reference("configs/references/synthetic_round_foot_periods.yaml")
    [(_, problem)] = fit_problems(config, reference, ["walker.leg_inertia=0.0043:0.006"])
    with study_executor("local", 2) as executor:      # None: serial, in this process
        calibration = calibrate(problem, executor, checkpoint=Path("fit.checkpoint.json"), draws=4000)
    write_calibration(calibration, Path("results/fit/mine"))

Modules: :mod:`.parameters` (keys, bounds, the normalised variable), :mod:`.problem` (targets and residuals),
:mod:`.evaluate` (the cached, parallel, checkpointed evaluations), :mod:`.optimize` (global stage and polish),
:mod:`.diagnose` (profile scans, verdict), :mod:`.stats` (estimates, identifiability), :mod:`.bayes`
(emcee), :mod:`.ranking` (the AICc ranking of a contest), :mod:`.document` (fit.json, tables), :mod:`.synthetic`.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import Config, derive, parse_yaml
from biped_sim.errors import ConfigError
from biped_sim.io.references import Reference
from biped_sim.studies.fit.bayes import (
    PosteriorRun,
    Prior,
    parse_prior,
    predictive_band,
    priors_for,
    sample_posterior,
    sampler_size,
)
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.optimize import GLOBAL_METHODS, SEED, run_fit
from biped_sim.studies.fit.parameters import FitParameter, fit_parameter, parse_parameter, same_key
from biped_sim.studies.fit.problem import FitProblem, Outcome
from biped_sim.studies.fit.stats import FitResult, summarize
from biped_sim.studies.fit.synthetic import synthetic_reference, synthetic_reference_data

__all__ = [
    "GLOBAL_METHODS", "Calibration", "FitParameter", "FitProblem", "FitResult", "Outcome", "PosteriorRun", "Prior",
    "calibrate", "contest", "fit_parameter", "fit_problems", "parse_each", "parse_parameter", "parse_prior",
    "priors_for", "sampler_size", "synthetic_reference", "synthetic_reference_data",
]  # fmt: skip


@dataclass
class Calibration:
    """A fit and, in the Bayesian mode, its posterior and the posterior predictive band per target."""

    result: FitResult
    posterior: PosteriorRun | None = None
    band: dict[str, np.ndarray] | None = None


def parse_each(text: str) -> tuple[str, list[Any]]:
    """``KEY=V1,V2,...``: the key and its distinct values (each read as YAML, as ``--set`` reads them)."""
    key, sep, values = text.partition("=")
    items = [v.strip() for v in values.split(",") if v.strip()]
    if not sep or not key.strip() or not items:
        raise ConfigError("each", f"expected KEY=V1,V2,..., got {text[:60]!r}")
    if len(set(items)) != len(items):
        raise ConfigError("each", "a value is listed twice")
    return key.strip(), [parse_yaml(item, source=f"each {key.strip()}") for item in items]


def fit_problems(
    config: Config,
    reference: Reference,
    parameters: list[str],
    skip: int = 0,
    each: tuple[str, list[Any]] | None = None,
    quantities: tuple[str, ...] | None = None,
) -> list[tuple[str | None, FitProblem]]:
    """One fit problem, or one per value of ``each`` (label, problem); every one checked now."""
    variants: list[tuple[str | None, Config]] = [(None, config)]
    if each is not None:
        key, values = each
        variants = [(str(value), derive(config, {key: value})) for value in values]
    problems = []
    for label, variant in variants:
        fitted = tuple(parse_parameter(text, variant) for text in parameters)
        if each is not None and same_key(each[0]) in [same_key(p.key) for p in fitted]:
            raise ConfigError(each[0], "is both the contest's key and a fitted parameter")
        problems.append((label, FitProblem(variant, reference, fitted, skip, quantities)))
    return problems


def calibrate(
    problem: FitProblem,
    executor: Executor | None = None,
    *,
    checkpoint: Path | None = None,
    progress: Callable[[Evaluator], None] | None = None,
    global_method: str = "multistart",
    seed: int = SEED,
    draws: int = 0,
    walkers: int | None = None,
    priors: tuple[Prior, ...] = (),
) -> Calibration:
    """Fit ``problem`` (global stage, polish, scans); with ``draws`` > 0 also sample its posterior.

    ``checkpoint``: a file of the evaluations so far, written atomically as the fit goes and read back
    when it exists, so that an interrupted call made again resumes without re-simulating.
    """
    priors = priors_for(problem.parameters, priors)
    if draws > 0:
        sampler_size(problem, draws, walkers)
    evaluator = Evaluator(problem, executor, checkpoint, progress)
    try:
        result = summarize(run_fit(evaluator, global_method, seed), evaluator)
        if draws <= 0:
            return Calibration(result)
        slopes = np.array([abs(p.slope(u)) for p, u in zip(problem.parameters, result.run.u, strict=True)])
        se_u = np.array([(e.standard_error or np.nan) for e in result.estimates]) / slopes
        posterior = sample_posterior(evaluator, result.run.u, se_u, draws, walkers, priors, seed)
        return Calibration(result, posterior, predictive_band(evaluator, posterior, seed))
    finally:
        evaluator.save()


def contest(
    problems: list[tuple[str, FitProblem]],
    executor: Executor | None = None,
    *,
    checkpoints: Path | None = None,
    **options: Any,
) -> list[tuple[str, Calibration]]:
    """:func:`calibrate` each labelled problem (one checkpoint file per label in the directory ``checkpoints``)."""
    out = []
    for label, problem in problems:
        checkpoint = None if checkpoints is None else checkpoints / f"{_file_label(label)}.checkpoint.json"
        out.append((label, calibrate(problem, executor, checkpoint=checkpoint, **options)))
    return out


def _file_label(label: str) -> str:
    return "".join(c if c.isalnum() or c in "_.-" else "_" for c in label)
