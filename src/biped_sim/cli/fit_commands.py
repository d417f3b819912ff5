"""``biped-sim fit``: config keys fitted to a reference's measured steps, its posterior, and the contest (``--each``).

A thin layer over :mod:`biped_sim.studies.fit` (the fit) and :mod:`biped_sim.report.fit` (its files): it parses
the flags, maps the API's argument names in errors to the flags, prints a progress line and the result.
Every input is checked before the first simulation; bad input is one line and exit code 2, nothing written.
The evaluations are checkpointed beside the output directory (``.<name>.checkpoint/``) as the fit goes: the
same command run again after an interruption resumes from them; a finished fit keeps them in its directory.
"""

from __future__ import annotations

import functools
import json
import math
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from biped_sim.cli.common import ConfigArgument, SetOption, app, end_interrupted, load, user_errors
from biped_sim.errors import ConfigError

if TYPE_CHECKING:
    from biped_sim.studies.fit.evaluate import Evaluator

FLAGS = {
    "parameters": "--param", "skip": "--skip-steps", "each": "--each", "quantities": "--quantity", "priors": "--prior",
    "walkers": "--walkers", "draws": "--posterior", "global_method": "--global",
}  # fmt: skip
PROGRESS_INTERVAL_S = 2.0


def _flag_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """:func:`~biped_sim.cli.common.user_errors` (one line, exit 2 for bad input, 1 for a full disk, 130 on Ctrl-C,
    143 on SIGTERM) with the API's argument names (``parameters: ...``) shown as the flags the user typed
    (``--param: ...``) and, when interrupted, how to resume (the checkpoint is flushed on the way out)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except ConfigError as exc:
            if exc.field in FLAGS:
                raise ConfigError(FLAGS[exc.field], exc.reason) from None
            raise
        except KeyboardInterrupt as exc:
            end_interrupted(exc, "run the same command again to resume from the checkpoint")

    return user_errors(wrapper)


def _progress(label: str | None) -> Callable[[Evaluator], None]:
    """A progress line on stderr, at most every PROGRESS_INTERVAL_S and at each new stage."""
    last = {"time": 0.0, "stage": ""}

    def report(evaluator: Evaluator) -> None:
        now = time.monotonic()
        if evaluator.stage == last["stage"] and now - last["time"] < PROGRESS_INTERVAL_S:
            return
        last.update(time=now, stage=evaluator.stage)
        prefix = f"{label}: " if label else ""
        done = f"{evaluator.evaluations} simulations ({evaluator.replayed} from the checkpoint)"
        typer.echo(f"{prefix}{evaluator.stage}: {done}, best cost {evaluator.best_cost:.6g}", err=True)

    return report


def _print(label: str | None, doc: dict[str, Any]) -> None:
    """One line per fit (values, errors, evaluations, verdict), its warnings, and the posterior's intervals."""
    values = ", ".join(f"{k} = {v:.6g}" for k, v in doc["parameters"].items())
    known = doc["rms_error_s"] is not None and math.isfinite(doc["rms_error_s"])
    rms = f"RMS error {doc['rms_error_s']:.4g} s, " if known else ""
    typer.echo(
        (f"{label}: " if label else "") + f"{values}; {rms}RMS residual {doc['rms_weighted_residual']:.3g}, "
        f"{doc['evaluations']} evaluations ({doc['simulations']} simulated, {doc['evaluations_replayed']} from the "
        f"checkpoint) in {doc['wall_time_s']:.1f} s; {doc['verdict']}"
    )
    for warning in doc["identifiability"]["warnings"] + ([doc["misfit"]] if doc["misfit"] else []):
        typer.echo(f"  warning: {warning}")
    posterior = doc.get("posterior")
    if posterior:
        for key, ci in posterior["intervals_90"].items():
            typer.echo(f"  posterior {key}: {ci['median']:.6g} [{ci['low']:.6g}, {ci['high']:.6g}] (90 %)")
        for warning in posterior["warnings"]:
            typer.echo(f"  warning: {warning}")


def _checkpoints(out_dir: Path) -> Path:
    """The checkpoint directory beside ``out_dir``, seeded from a finished fit's own checkpoints when it is new."""
    side = out_dir.parent / f".{out_dir.name}.checkpoint"
    if not side.exists() and out_dir.is_dir():
        for old in [*out_dir.glob("*.checkpoint.json"), *out_dir.glob("*/*.checkpoint.json")]:
            (side / old.relative_to(out_dir)).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(old, side / old.relative_to(out_dir))
    side.mkdir(parents=True, exist_ok=True)
    return side


@app.command("fit")
@_flag_errors
def fit_command(
    config_path: ConfigArgument,
    reference: Annotated[Path | None, typer.Option("--reference", help="Reference file of measured steps.")] = None,
    param: Annotated[list[str] | None, typer.Option("--param", help="Config key to fit: KEY=LO:HI.")] = None,
    set_: SetOption = None,
    skip: Annotated[int, typer.Option("--skip-steps", help="Model steps before reference step 1.")] = 0,
    quantity: Annotated[list[str] | None, typer.Option("--quantity", help="Fit only these quantities.")] = None,
    global_method: Annotated[
        str, typer.Option("--global", help="Global stage: multistart (Sobol, polishes, IPOP), cma or de.")
    ] = "multistart",
    posterior: Annotated[int, typer.Option("--posterior", help="Posterior draws (emcee), 0: none.")] = 0,
    walkers: Annotated[int | None, typer.Option("--walkers", help="emcee walkers (default max(16, 4 p)).")] = None,
    prior: Annotated[list[str] | None, typer.Option("--prior", help="KEY=normal:MEAN:SD (default: bounds).")] = None,
    jobs: Annotated[int, typer.Option("--jobs", "-j", help="Parallel simulations (1: in-process).")] = 1,
    executor: Annotated[str, typer.Option("--executor", help="local (processes) or dask.")] = "local",
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="Dask scheduler tcp://host:port.")] = None,
    each: Annotated[str | None, typer.Option("--each", help="One fit per value, ranked: KEY=V1,V2,...")] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Output directory (default results/fit/<stem>).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print fit.json (or the contest) to stdout.")] = False,
) -> None:
    """Fit config keys so that the model's steps match a reference: global stage, polish, scans; a posterior."""
    from biped_sim.io.atomic import json_safe  # here and below: the command's modules load only when it runs
    from biped_sim.io.output import check_output_dir, staged_directory
    from biped_sim.io.references import load_reference
    from biped_sim.report.fit import FIT_OUTPUT, label_dir, write_calibration, write_contest
    from biped_sim.studies.fit import (
        GLOBAL_METHODS,
        calibrate,
        fit_problems,
        parse_each,
        parse_prior,
        priors_for,
        sampler_size,
    )  # fmt: skip
    from biped_sim.sweep import check_executor, study_executor

    check_executor(executor, scheduler)
    for option, value, least in (("--skip-steps", skip, 0), ("--posterior", posterior, 0), ("--jobs", jobs, 1)):
        if value < least:
            raise ConfigError(option, f"must be at least {least}")
    if global_method not in GLOBAL_METHODS:
        raise ConfigError("--global", f"unknown method {global_method!r}; expected one of {', '.join(GLOBAL_METHODS)}")
    if walkers is not None and posterior == 0:
        raise ConfigError("--walkers", "only used with --posterior (the emcee sampler's walkers)")
    if reference is None:
        raise ConfigError("--reference", "required: a reference file of measured steps (see docs/experiments.md)")
    contest_key = parse_each(each) if each is not None else None
    quantities = tuple(quantity) if quantity else None
    problems = fit_problems(
        load(config_path, set_), load_reference(reference), param or [], skip, contest_key, quantities
    )
    priors = tuple(parse_prior(text) for text in prior or [])
    for _, problem in problems:
        priors_for(problem.parameters, priors)
        if posterior > 0:
            sampler_size(problem, posterior, walkers)
    out_dir = out or Path("results") / "fit" / config_path.stem
    check_output_dir(out_dir, FIT_OUTPUT)
    options = {"global_method": global_method, "draws": posterior, "walkers": walkers, "priors": priors}
    fits = []
    with study_executor(executor, jobs, scheduler) as pool:
        side = _checkpoints(out_dir)  # once the executor is up: a refused one leaves nothing behind
        for label, problem in problems:
            checkpoint = side / f"{label_dir(label or 'fit')}.checkpoint.json"
            fits.append((label, calibrate(problem, pool, checkpoint=checkpoint, progress=_progress(label), **options)))
    with staged_directory(out_dir, FIT_OUTPUT) as stage:
        if contest_key is None:
            docs = [write_calibration(fits[0][1], stage, str(config_path))]
        else:
            ranking, docs = write_contest(contest_key[0], [(str(lab), c) for lab, c in fits], stage, str(config_path))
        for checkpoint in side.glob("*.checkpoint.json"):
            shutil.copy2(checkpoint, stage / checkpoint.name)
    shutil.rmtree(side, ignore_errors=True)
    if as_json:
        shown = docs[0] if contest_key is None else {"each": each, "fits": docs}
        typer.echo(json.dumps(json_safe(shown), indent=2, allow_nan=False))
        return
    for (label, _), doc in zip(fits, docs, strict=True):
        _print(label, doc)
    if contest_key is not None:
        typer.echo(ranking.markdown())
    typer.echo(f"files: {out_dir}/")
