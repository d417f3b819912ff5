"""``biped-sim run`` and ``biped-sim drop-test``."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from biped_sim.cli.common import ConfigArgument, SetOption, app, load, user_errors
from biped_sim.config import default_output_dir
from biped_sim.errors import ConfigError
from biped_sim.io.output import check_writable_dir
from biped_sim.io.run_files import previous_run
from biped_sim.measure.steps import LATERAL_STEP_COLUMNS
from biped_sim.rigid.start import NONDIMENSIONAL
from biped_sim.simulate import RunResult, simulate
from biped_sim.simulate.aside import join, prepare_compiling_aside
from biped_sim.simulate.warmup import warm_up_configs, warm_up_in_processes

LATERAL_NAMES = {name for name, _ in LATERAL_STEP_COLUMNS}


def _fmt(value: float, digits: int = 5) -> str:
    return "" if not math.isfinite(value) else f"{value:.{digits}f}"


def _header(name: str, unit: str) -> str:
    """A column header with its unit; the simplest walker's nondimensional columns go bare (see the title)."""
    return name if unit == NONDIMENSIONAL else f"{name} [{unit}]"


def _quantity(value: float, digits: int, unit: str) -> str:
    """A value and its unit (bare when nondimensional)."""
    return f"{value:.{digits}f}" + ("" if unit == NONDIMENSIONAL else f" {unit}")


def step_table_rich(result: RunResult) -> Table:
    """The per-step table printed after a run (a rigid run's angles are the touchdown ones, as compliant runs'),
    with a run in space's lateral columns (width, heading, sway, bank)."""
    seconds, metres = result.unit("s"), result.unit("m")
    title = "Steps" if seconds != NONDIMENSIONAL else "Steps (nondimensional: g = l = 1)"
    table = Table(title=title, show_lines=False)
    s = result.steps
    lateral = [(name, unit) for name, unit in s.columns if name in LATERAL_NAMES]
    for column in (
        "step",
        _header("t", seconds),
        "foot",
        _header("period", seconds),
        _header("length", metres),
        _header("slip", metres),
        "stance [rad]",
        "swing [rad]",
        *(_header(name, result.unit(unit)) for name, unit in lateral),
    ):
        table.add_column(column, justify="right")
    for k in range(len(s.strike_time)):
        table.add_row(
            str(k + 1),
            _fmt(s.strike_time[k], 4),
            str(int(s.foot[k])),
            _fmt(s.period[k]),
            _fmt(s.length[k]),
            f"{s.slip[k]:.2e}" if math.isfinite(s.slip[k]) else "",
            _fmt(s.stance_angle[k], 4),
            _fmt(s.swing_angle[k], 4),
            *(_fmt(getattr(s, name)[k], 4) for name, _ in lateral),
        )
    return table


def summary_line(result: RunResult) -> str:
    """One line: status, steps, mean period, speed, energy residual, constraint violation (compliant) or impact
    losses (rigid), cost."""
    s = result.summary
    seconds = result.unit("s")
    status = s["status"] + (f" at t={_quantity(s['stop_time'], 3, seconds)}" if s["stop_time"] is not None else "")
    status += f" ({s['status_reason']})" if s.get("status_reason") else ""
    period = s["mean_step_period"]
    gait = (
        f"mean period {_quantity(period, 5, seconds)}, speed {_quantity(s['mean_speed'], 4, result.unit('m/s'))}, "
        if period is not None
        else ""
    )
    model = ""
    if s.get("dynamics") == "rigid":
        model = " (rigid model" + (", nondimensional: g = l = 1)" if seconds == NONDIMENSIONAL else ")")
    return (
        f"{status}: {s['n_steps']} steps, {gait}energy residual {s['energy_residual_max_relative']:.1e} m g l, "
        f"{result.integrity_text()}, {s['rhs_evals']} RHS evaluations in {s['wall_time_s']:.2f} s{model}"
    )


@app.command("run")
@user_errors
def run_command(
    config_path: ConfigArgument,
    set_: SetOption = None,
    out: Annotated[
        Path | None, typer.Option("--out", help="Run directory (default: output.dir or results/runs/<stem>).")
    ] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar and no step table.")] = False,
) -> None:
    """Simulate one walker and write trajectory.h5, summary.json and steps.csv."""
    config = load(config_path, set_)
    out_dir = out or default_output_dir(config, config_path)
    check_writable_dir(out_dir)  # before any computation
    replaced = previous_run(out_dir)
    had_figures = (out_dir / "figures").is_dir()
    # validates geometry and the initial state before anything is written; on a cold compile cache, a second
    # process compiles the run's measures meanwhile
    model, aside = prepare_compiling_aside(config)
    console = Console(stderr=False)
    show_progress = not quiet and sys.stdout.isatty()
    if show_progress:
        with Progress(
            TextColumn("[bold]simulating"),
            BarColumn(),
            TextColumn("t = {task.completed:.2f} / {task.total:.2f} s"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=console,
            transient=True,
        ) as bar:
            task = bar.add_task("run", total=config.simulation.t_end)
            result = simulate(config, model=model, progress=lambda t: bar.update(task, completed=t))
    else:
        result = simulate(config, model=model)
    join(aside)  # its measures compiled: write loads them from the cache
    result.write(out_dir)
    if not quiet:
        console.print(step_table_rich(result))
    console.print(summary_line(result), highlight=False, soft_wrap=True)
    console.print(f"files: {out_dir}/ (trajectory.h5, summary.json, steps.csv, config.yaml)", highlight=False)
    if replaced:
        console.print(f"replaced {replaced}" + (" and its figures" if had_figures else ""), highlight=False)


@app.command("warmup")
@user_errors
def warmup_command(
    every: Annotated[
        bool, typer.Option("--all", help="Every formulation x integrator family (every contact law is in each).")
    ] = False,
    jobs: Annotated[
        int, typer.Option("--jobs", "-j", min=0, help="Groups compiled at once, each in a process (0: one per core).")
    ] = 0,
) -> None:
    """Compile (or load from the cache) the default walker's kernels, so that the first run starts in seconds."""
    for done in warm_up_in_processes(warm_up_configs(every), jobs or None):
        if done is not None:
            typer.echo(done.line())


@app.command("drop-test")
@user_errors
def drop_test_command(
    model: Annotated[list[str] | None, typer.Option("--model", help="Normal law (repeatable; default: all).")] = None,
    restitution: Annotated[
        list[float] | None, typer.Option("--restitution", help="Nominal e (repeatable; default 0.3 0.5 0.7 0.9).")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
) -> None:
    """Drop a disc on the ground without friction: effective restitution of each normal law."""
    from biped_sim.contact.normal import NORMAL_LAWS
    from biped_sim.studies.drop_test import DROP_TEST_RESTITUTIONS, drop_test_table

    models = model or list(NORMAL_LAWS)
    for name in models:
        if name not in NORMAL_LAWS:
            raise ConfigError("--model", f"unknown normal law {name!r}; expected one of {', '.join(NORMAL_LAWS)}")
    values = restitution or list(DROP_TEST_RESTITUTIONS)
    for e in values:
        if not 0.0 < e <= 1.0:
            raise ConfigError("--restitution", f"{e} is not in (0, 1]")
    rows = drop_test_table(models, values)
    if as_json:
        typer.echo(json.dumps(rows, indent=2))
        return
    table = Table(title="Drop test: effective restitution (separation / approach speed)")
    table.add_column("model")
    for e in values:
        table.add_column(f"e = {e:g}", justify="right")
    for name in models:
        cells = [f"{r['effective_restitution']:.4f}" for r in rows if r["model"] == name]
        table.add_row(name, *cells)
    Console().print(table)
