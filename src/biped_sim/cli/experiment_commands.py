"""``biped-sim sweep``, ``report``, ``plot``, ``animate`` and ``compare``: experiments on top of ``run``.

Each command checks all of its input, and its output location, before it computes or writes anything;
bad input is one line on stderr and exit code 2 (see :func:`~biped_sim.cli.common.user_errors` for the
exit codes).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from biped_sim.cli.common import SetOption, app, end_interrupted, fail, user_errors
from biped_sim.errors import ConfigError
from biped_sim.io.output import OutputKind, check_output_dir, check_writable_dir, staged_directory

if TYPE_CHECKING:
    from biped_sim.sweep import SweepProgress

NO_REFERENCE = (
    "not given: compare needs measured step periods; Liu's are not bundled (only the per-step "
    "errors Corral et al. 2020 report, configs/references/corral2020_liu_errors.yaml): add yours as a "
    "reference file, see docs/experiments.md"
)
COMPARE_OUTPUT = OutputKind("compare", ("compare_steps.*", "compare_stats.*", "compare.png", "compare.svg"))
DAMAGED_SHOWN = 5


def damaged_line(damaged: dict[str, str]) -> str:
    """One line naming the finished runs found damaged, which the sweep runs again."""
    named = [f"{name} ({why})" for name, why in list(damaged.items())[:DAMAGED_SHOWN]]
    more = f" and {len(damaged) - DAMAGED_SHOWN} more" if len(damaged) > DAMAGED_SHOWN else ""
    return f"warning: running {len(damaged)} damaged finished run(s) again: {', '.join(named)}{more}"


class SweepReporter:
    """Progress of a sweep: a rich bar on a terminal, else one line per finished run."""

    def __init__(self, console: Console, quiet: bool) -> None:
        self.console = console
        self.quiet = quiet
        self.bar: Progress | None = None
        self.task: TaskID | None = None

    def __enter__(self) -> SweepReporter:
        if not self.quiet and self.console.is_terminal:
            self.bar = Progress(
                TextColumn("[bold]sweep"),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("failed {task.fields[failed]}"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                console=self.console,
                transient=True,
            )
            self.bar.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.__exit__(None, None, None)

    def __call__(self, progress: SweepProgress, name: str | None, row: dict[str, Any] | None) -> None:
        if name is None:
            pending = progress.total - progress.skipped
            if progress.damaged:
                typer.echo(damaged_line(progress.damaged), err=True)
            if not self.quiet:
                self.console.print(
                    f"{progress.total} runs: {progress.skipped} already finished, {pending} to run", highlight=False
                )
            if self.bar is not None:
                self.task = self.bar.add_task("sweep", total=pending, failed=0)
            return
        if self.bar is not None and self.task is not None:
            self.bar.update(self.task, completed=progress.done, failed=progress.failed)
        elif not self.quiet and row is not None:
            detail = row["error"] or f"{row['n_steps']} steps, {row['wall_time_s']:.2f} s"
            self.console.print(
                f"[{progress.done}/{progress.total - progress.skipped}] {name}: {row['status']}, {detail}",
                highlight=False,
                soft_wrap=True,
            )


@app.command("sweep")
@user_errors
def sweep_command(
    sweep_file: Annotated[Path, typer.Argument(help="Sweep file (YAML): base config, grid/zip axes.")],
    set_: SetOption = None,
    jobs: Annotated[int | None, typer.Option("--jobs", "-j", help="Parallel runs (default: all cores).")] = None,
    resume: Annotated[
        bool, typer.Option("--resume/--no-resume", help="Skip runs already finished with the same config hash.")
    ] = True,
    executor: Annotated[str, typer.Option("--executor", help="local (processes) or dask.")] = "local",
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler address tcp://host:port (default: LocalCluster).")
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Sweep directory (default: the file's output).")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress output.")] = False,
) -> None:
    """Run every combination of a sweep file in parallel; write run directories and sweep.csv."""
    from biped_sim.sweep import (
        check_buildable,
        check_executor,
        load_sweep,
        make_executor,
        pending_runs,
        run_sweep,
        workers_for,
    )

    check_executor(executor, scheduler)
    sweep = load_sweep(sweep_file, set_ or [])
    sweep_dir = out or sweep.default_output_dir()
    check_writable_dir(sweep_dir)
    check_buildable(sweep)
    workers = workers_for(len(pending_runs(sweep, sweep_dir, resume)), jobs)
    console = Console()
    try:
        with make_executor(executor, workers, scheduler) as pool, SweepReporter(console, quiet) as reporter:
            outcome = run_sweep(sweep, sweep_dir, pool, resume=resume, on_progress=reporter)
    except KeyboardInterrupt as exc:
        end_interrupted(exc, f"finished runs are kept in {sweep_dir}/; the same command runs the rest")
    counts = ", ".join(f"{n} {status}" for status, n in sorted(outcome.progress.statuses.items()))
    console.print(
        f"sweep {sweep.spec.name}: {len(sweep.runs)} runs, {outcome.progress.skipped} already finished"
        + (f", ran {outcome.progress.done}: {counts}" if outcome.progress.done else ""),
        highlight=False,
        soft_wrap=True,
    )
    console.print(f"files: {sweep_dir}/ (sweep.csv, sweep.json, runs/)", highlight=False, soft_wrap=True)
    if outcome.failed:
        counts = ", ".join(f"{n} {status}" for status, n in sorted(outcome.failed.items()))
        fail(f"{sum(outcome.failed.values())} failed run(s) ({counts}); see {sweep_dir}/sweep.csv", code=1)


@app.command("report")
@user_errors
def report_command(
    sweep_dir: Annotated[Path, typer.Argument(help="Sweep directory (holds sweep.json and sweep.csv).")],
    out: Annotated[Path | None, typer.Option("--out", help="Report directory (default: SWEEP_DIR/report).")] = None,
) -> None:
    """Comparison tables (Markdown, CSV, LaTeX) and figures (PNG, SVG) of a sweep."""
    from biped_sim.report import build_report

    report = build_report(sweep_dir, out)
    typer.echo(
        f"report: {report.markdown_path} ({len(report.tables)} tables in tables/, "
        f"{len(report.figures)} figures in figures/)"
    )
    if report.missing:
        typer.echo(f"note: {report.missing}")


@app.command("plot")
@user_errors
def plot_command(
    run_dir: Annotated[Path, typer.Argument(help="Run directory (holds trajectory.h5 and summary.json).")],
    out: Annotated[Path | None, typer.Option("--out", help="Figure directory (default: RUN_DIR/figures).")] = None,
) -> None:
    """The single-run figures: step period, constraint violation, contact forces, energy, slip, phase portrait and
    the walker over a step (a rigid run: step period, energy, phase portrait and the walker)."""
    from biped_sim.io.trajectory import load_run
    from biped_sim.plots import PLOT_OUTPUT, plot_run

    out_dir = out or run_dir / "figures"
    check_output_dir(out_dir, PLOT_OUTPUT)
    run = load_run(run_dir)
    paths = plot_run(run, out_dir)
    typer.echo(f"figures: {out_dir}/ ({len(paths) // 2} figures, PNG and SVG)")
    if run.summary.get("stop_time") is not None:
        status, stop = run.summary.get("status"), run.summary["stop_time"]
        typer.echo(f"note: the run {status} at t = {stop:.3f} s; the figures end there")


@app.command("animate")
@user_errors
def animate_command(
    run_dir: Annotated[Path, typer.Argument(help="Run directory (holds trajectory.h5).")],
    out: Annotated[Path, typer.Option("--out", help="Output file: .gif, or .mp4 when ffmpeg is present.")],
    fps: Annotated[float, typer.Option("--fps", help="Frames per second of playback.")] = 25.0,
    speed: Annotated[float, typer.Option("--speed", help="Playback speed (1 = real time).")] = 1.0,
    t_start: Annotated[float, typer.Option("--start", help="First simulated time shown [s].")] = 0.0,
    t_end: Annotated[float | None, typer.Option("--end", help="Last simulated time shown [s].")] = None,
) -> None:
    """Draw the walker walking (any walker, compliant or rigid run), with contact force arrows and a time stamp."""
    from biped_sim.animate import animate_run, check_output, check_playback
    from biped_sim.io.trajectory import load_run

    check_playback(fps, speed, t_start, t_end)
    check_output(out)
    run = load_run(run_dir)
    frames = animate_run(run, out, fps=fps, speed=speed, t_start=t_start, t_end=t_end)
    typer.echo(f"animation: {out} ({frames} frames at {fps:g} fps)")


@app.command("compare")
@user_errors
def compare_command(
    target: Annotated[Path, typer.Argument(help="Config file (simulated), run directory or sweep directory.")],
    reference: Annotated[
        Path | None, typer.Option("--reference", help="Reference file of measured step periods (YAML).")
    ] = None,
    set_: SetOption = None,
    skip: Annotated[
        int, typer.Option("--skip-steps", help="Model steps to drop so that model step N+1 meets reference step 1.")
    ] = 0,
    out: Annotated[Path | None, typer.Option("--out", help="Output directory.")] = None,
) -> None:
    """Per-step error table (Markdown, CSV, LaTeX) and figure of model step periods against a reference."""
    from biped_sim.io.references import load_reference
    from biped_sim.plots import comparisons_figure, save_figure
    from biped_sim.report.targets import compare_targets
    from biped_sim.studies.compare import compare_periods, stats_table, step_table

    if reference is None:
        raise ConfigError("--reference", NO_REFERENCE)
    ref = load_reference(reference)
    if not ref.is_periods:
        raise ConfigError(
            "--reference",
            f"{reference} holds published relative errors, not measured step periods; "
            "compare needs a step_period reference (see docs/experiments.md)",
        )
    out_dir = out or (target / "compare" if target.is_dir() else Path("results") / "compare" / target.stem)
    check_output_dir(out_dir, COMPARE_OUTPUT)
    series, missing = compare_targets(target, set_ or [], skip)
    comparisons = [compare_periods(ref, periods, label) for label, periods in series]
    tables = [step_table(comparisons), stats_table(comparisons)]
    figure = comparisons_figure(comparisons)
    with staged_directory(out_dir, COMPARE_OUTPUT) as stage:
        for table in tables:
            table.write(stage)
        save_figure(figure, stage, "compare")
    typer.echo(tables[0].markdown() if len(comparisons) == 1 else "")
    typer.echo(tables[1].markdown())
    typer.echo(f"files: {out_dir}/ (compare_steps, compare_stats as .md/.csv/.tex; compare.png, compare.svg)")
    if missing:
        typer.echo(f"note: {missing}")
