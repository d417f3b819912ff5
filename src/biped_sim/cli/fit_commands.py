"""``biped-sim fit``: config parameters fitted to a reference's step periods, and the contest of laws (``--each``).

Every input (config, reference, parameters, --each values, output location) is checked before the first
simulation; bad input is one line and exit code 2, with nothing written.
"""

from __future__ import annotations

import contextlib
import json
import re
from collections.abc import Callable, Iterator
from concurrent.futures import Executor
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from biped_sim.cli.common import ConfigArgument, SetOption, app, load, user_errors
from biped_sim.errors import ConfigError
from biped_sim.io.output import OutputKind, check_output_dir, staged_directory

if TYPE_CHECKING:
    from biped_sim.io.references import Reference
    from biped_sim.studies.fit import FitProblem, StartResult
    from biped_sim.studies.fit_stats import FitResult

FIT_FILES = (
    "fit.json", "fitted.yaml", "fit_parameters.*", "fit_steps.*", "fit_stats.*", "fit_periods.png",
    "fit_periods.svg", "compare_steps.*", "compare_stats.*", "compare.png", "compare.svg",
)  # fmt: skip
FIT_OUTPUT = OutputKind("fit", (*FIT_FILES, *(f"*/{name}" for name in FIT_FILES), "ranking.*"))


def _reference(path: Path) -> Reference:
    """A step-period reference whose std (if any) can weight residuals; ConfigError otherwise."""
    from biped_sim.io.references import load_reference
    from biped_sim.studies.fit import reference_sigma

    reference = load_reference(path)
    if not reference.is_periods:
        raise ConfigError("--reference", f"{path} holds published relative errors, not measured step periods")
    reference_sigma(reference)
    return reference


def _each(text: str | None) -> tuple[str, list[str]] | None:
    """--each KEY=V1,V2,...: the key and its distinct values."""
    if text is None:
        return None
    key, sep, values = text.partition("=")
    items = [v.strip() for v in values.split(",") if v.strip()]
    if not sep or not key.strip() or not items:
        raise ConfigError("--each", f"expected KEY=V1,V2,..., got {text!r}")
    if len(set(items)) != len(items):
        raise ConfigError("--each", "a value is listed twice")
    return key.strip(), items


def _problems(
    config_path: Path, overrides: list[str], reference: Reference, params: list[str], skip: int, each: str | None
) -> list[tuple[str | None, FitProblem]]:
    """One fit problem, or one per --each value (label, problem); every one checked now."""
    from biped_sim.studies.fit import FitProblem, parse_parameter

    if not params:
        raise ConfigError("--param", "give at least one KEY=LO:HI to fit")
    contest = _each(each)
    variants: list[tuple[str | None, list[str]]] = [(None, overrides)]
    if contest is not None:
        variants = [(value, [*overrides, f"{contest[0]}={value}"]) for value in contest[1]]
    problems = []
    for label, assignments in variants:
        config = load(config_path, assignments)
        parameters = tuple(parse_parameter(text, config) for text in params)
        keys = [p.key for p in parameters]
        if len(set(keys)) != len(keys):
            raise ConfigError("--param", "a key is given twice")
        if contest is not None and contest[0] in keys:
            raise ConfigError("--each", f"{contest[0]} is also a fitted --param")
        problems.append((label, FitProblem(config, reference, parameters, skip)))
    return problems


@contextlib.contextmanager
def _executor(kind: str, jobs: int, scheduler: str | None) -> Iterator[Executor | None]:
    """None for --jobs 1 on the local executor (runs in this process, no pool), else the sweep's executor."""
    if kind == "local" and jobs == 1 and scheduler is None:
        yield None
        return
    from biped_sim.sweep import make_executor

    with make_executor(kind, jobs, scheduler) as executor:
        yield executor


def _document(result: FitResult, config_path: Path) -> dict[str, Any]:
    """fit.json: the fit, the resolved configs (start and fitted), hashes and provenance."""
    from biped_sim.io.provenance import provenance

    problem = result.run.problem
    return {
        **result.to_json(),
        "config_path": str(config_path),
        "start_config": problem.config.model_dump(mode="json"),
        "start_config_hash": problem.config.hash(),
        "config": result.fitted_config.model_dump(mode="json"),
        "config_hash": result.fitted_config.hash(),
        "provenance": provenance(),
    }


def _write_fit(result: FitResult, doc: dict[str, Any], directory: Path) -> None:
    """One fit's files: fit.json, fitted.yaml, its tables and the two figures."""
    from biped_sim.io.atomic import write_json_atomic, write_text_atomic
    from biped_sim.plots import comparisons_figure, save_figure
    from biped_sim.studies.compare import stats_table, step_table
    from biped_sim.studies.fit_stats import parameter_table

    directory.mkdir(parents=True, exist_ok=True)
    reference = result.run.problem.reference
    header = f"# Fitted by biped-sim fit against {reference.path} (see fit.json); runnable with biped-sim run.\n"
    write_text_atomic(directory / "fitted.yaml", header + result.fitted_config.to_yaml())
    tables = [
        parameter_table(result),
        step_table([result.before, result.after], "fit_steps"),
        stats_table([result.before, result.after], "fit_stats"),
        step_table([result.after]),
        stats_table([result.after]),
    ]
    for table in tables:
        table.write(directory)
    for name, series in (("compare", [result.after]), ("fit_periods", [result.before, result.after])):
        save_figure(comparisons_figure(series), directory, name)
    write_json_atomic(directory / "fit.json", doc)


def _progress(label: str | None, starts: int) -> Callable[[int, StartResult], None]:
    """One line on stderr per finished start (a fit can take minutes)."""

    def report(index: int, start: StartResult) -> None:
        prefix = f"{label}: " if label else ""
        typer.echo(f"{prefix}start {index + 1}/{starts}: cost {start.cost:.6g} ({start.message})", err=True)

    return report


def _print_fit(label: str | None, result: FitResult) -> None:
    """One line per fit (values, RMS error, evaluations, convergence) and its identifiability warnings."""
    stats = result.after.stats
    typer.echo(
        (f"{label}: " if label else "")
        + ", ".join(f"{k} = {v:.6g}" for k, v in result.parameters.items())
        + f"; RMS error {stats.rms_abs:.4g} s ({stats.rms_rel:.3g} %), {result.run.evaluations} evaluations "
        + f"in {result.run.wall_time_s:.1f} s, "
        + ("converged" if result.converged else "NOT converged")
        + f" ({result.run.best.message})"
    )
    for warning in result.identifiability.warnings:
        typer.echo(f"  warning: {warning}")


def _label_dir(label: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", label)


@app.command("fit")
@user_errors
def fit_command(
    config_path: ConfigArgument,
    reference: Annotated[
        Path | None, typer.Option("--reference", help="Reference file of step periods (YAML).")
    ] = None,
    param: Annotated[
        list[str] | None, typer.Option("--param", help="Numeric config key to fit within bounds: KEY=LO:HI.")
    ] = None,
    set_: SetOption = None,
    skip: Annotated[int, typer.Option("--skip-steps", help="Model steps before reference step 1.")] = 0,
    starts: Annotated[int, typer.Option("--starts", help="Starts: the config's values, then a Latin hypercube.")] = 1,
    jobs: Annotated[int, typer.Option("--jobs", "-j", help="Parallel runs of each Jacobian (1: in-process).")] = 1,
    executor: Annotated[str, typer.Option("--executor", help="local (processes) or dask.")] = "local",
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler address tcp://host:port.")
    ] = None,
    each: Annotated[
        str | None, typer.Option("--each", help="One fit per value, and a ranking: KEY=V1,V2,... (a law contest).")
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Output directory (default results/fit/<stem>).")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print fit.json (or the contest) to stdout.")] = False,
) -> None:
    """Fit config parameters so that the model's step periods match a reference (bounded least squares)."""
    from biped_sim.io.atomic import json_safe
    from biped_sim.studies.fit import run_fit
    from biped_sim.studies.fit_stats import ranking_table, summarize

    for option, value, least in (("--skip-steps", skip, 0), ("--starts", starts, 1), ("--jobs", jobs, 1)):
        if value < least:
            raise ConfigError(option, f"must be at least {least}")
    if executor not in ("local", "dask"):
        raise ConfigError("--executor", f"unknown executor {executor!r}; expected local or dask")
    if reference is None:
        raise ConfigError("--reference", "required: a reference file of step periods (see docs/experiments.md)")
    ref = _reference(reference)
    problems = _problems(config_path, set_ or [], ref, param or [], skip, each)
    out_dir = out or Path("results") / "fit" / config_path.stem
    check_output_dir(out_dir, FIT_OUTPUT)
    fits: list[tuple[str | None, FitResult, dict[str, Any]]] = []
    with _executor(executor, jobs, scheduler) as pool:
        for label, problem in problems:
            result = summarize(run_fit(problem, starts, pool, _progress(label, starts)))
            fits.append((label, result, _document(result, config_path)))
    with staged_directory(out_dir, FIT_OUTPUT) as stage:
        for label, result, doc in fits:
            _write_fit(result, doc, stage if label is None else stage / _label_dir(label))
        if each is not None:
            ranking = ranking_table(each.partition("=")[0].strip(), [(str(lab), res) for lab, res, _ in fits])
            ranking.write(stage)
    if as_json:
        docs = [doc for _, _, doc in fits]
        shown = docs[0] if each is None else {"each": each, "fits": docs}
        typer.echo(json.dumps(json_safe(shown), indent=2, allow_nan=False))
        return
    for label, result, _ in fits:
        _print_fit(label, result)
    if each is not None:
        typer.echo(ranking.markdown())
    typer.echo(f"files: {out_dir}/")
