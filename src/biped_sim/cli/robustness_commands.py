"""``biped-sim robustness``: the largest disturbances a walker survives, rough ground, the gait sensitivity norm."""

from __future__ import annotations

import json
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from biped_sim.cli.common import ConfigArgument, SetOption, app, load, user_errors


@app.command("robustness")
@user_errors
def robustness_command(
    config_path: ConfigArgument,
    set_: SetOption = None,
    dynamics: Annotated[
        str, typer.Option("--dynamics", help="rigid, compliant, or both (those the walker has).")
    ] = "both",
    seeds: Annotated[int, typer.Option("--seeds", min=1, help="Rough-ground seeds per roughness level.")] = 20,
    jobs: Annotated[int, typer.Option("--jobs", min=1, help="Worker processes.")] = 1,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
) -> None:
    """Started on its gait: the largest step down and up, forward and backward push it survives, its survival on
    random ground, and its gait sensitivity norm, for rigid and compliant dynamics."""
    from biped_sim.studies.robustness import robustness, robustness_configs, robustness_table
    from biped_sim.sweep import study_executor

    configs = robustness_configs(load(config_path, set_), dynamics)
    with study_executor("local", jobs) as executor:
        results = [robustness(config, executor, seeds=seeds) for config in configs]
    if as_json:
        typer.echo(json.dumps([r.to_json() for r in results], indent=2))
        return
    table = robustness_table(results)
    shown = Table(title=table.title)
    for column in table.columns:
        shown.add_column(column.title, justify="right")
    for cells in table.cells():
        shown.add_row(*cells)
    console = Console()
    console.print(shown)
    for note in table.notes:
        console.print(f"  {note}", highlight=False)
