"""``biped-sim basin``: the basin of attraction of a walker over two initial-state keys (or one and a parameter)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from biped_sim.cli.common import ConfigArgument, SetOption, app, load, user_errors
from biped_sim.io.output import check_writable_dir

AxisOption = (
    "KEY=LO:HI:N, KEY a simulation.initial key (e.g. stance_angle=0:0.4:41) or, on one axis, a named parameter "
    "(walker.parameters.NAME)."
)


@app.command("basin")
@user_errors
def basin_command(
    config_path: ConfigArgument,
    x: Annotated[str, typer.Option("--x", help=f"Horizontal axis: {AxisOption}")],
    y: Annotated[str, typer.Option("--y", help=f"Vertical axis: {AxisOption}")],
    set_: SetOption = None,
    steps: Annotated[int, typer.Option("--steps", help="Steps each cell walks.")] = 30,
    tolerance: Annotated[
        float,
        typer.Option("--tolerance", help="Converged: last state this close to the gait (max over its keys)."),
    ] = 1e-4,
    jobs: Annotated[int | None, typer.Option("--jobs", "-j", help="Parallel workers (default: all cores).")] = None,
    executor: Annotated[str, typer.Option("--executor", help="local (processes) or dask.")] = "local",
    out: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path("results/basin"),
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a summary line.")] = False,
) -> None:
    """Which starts walk K steps, converge to the period-1 gait, or fall (basin.h5, basin.csv, PNG, SVG).

    Finished grid rows are kept in OUT/cells: a rerun of the same basin resumes where it stopped.
    """
    from biped_sim.plots import save_figure
    from biped_sim.report.basin import basin_figure
    from biped_sim.studies.basin import BasinSpec, map_basin, parse_axis
    from biped_sim.studies.basin_files import write_basin
    from biped_sim.sweep import study_executor, workers_for

    spec = BasinSpec(load(config_path, set_), parse_axis("x", x), parse_axis("y", y), steps, tolerance)
    check_writable_dir(out)
    console = Console(stderr=True)
    workers = workers_for(spec.y.n, jobs)
    progress = None if as_json else lambda done, total: console.print(f"rows {done}/{total}", end="\r")
    with study_executor(executor, workers) as pool:
        basin = map_basin(spec, out, pool, progress)
    files = write_basin(basin, out) + save_figure(basin_figure(basin), out, "basin")
    doc = basin.to_json()
    if as_json:
        typer.echo(json.dumps({**doc, "files": [str(p) for p in files]}, indent=2))
        return
    console.print(
        f"{doc['n_cells']} cells in {doc['wall_time_s']:.1f} s ({workers} workers, {basin.rows_reused} rows reused): "
        f"{doc['fraction_walking']:.1%} walk {steps} steps, {doc['fraction_converged']:.1%} converge; files: {out}/",
        highlight=False,
    )
