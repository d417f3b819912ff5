"""``biped-sim bench``: the performance benchmark (a script, not a test)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from biped_sim.cli.common import app, user_errors
from biped_sim.io.output import check_writable_dir

DEFAULT_CONFIG = Path("configs/round_foot_walker.yaml")
DEFAULT_OUT = Path("results/bench")


@app.command()
@user_errors
def bench(
    quick: Annotated[
        bool, typer.Option("--quick", help="2 s simulated, 3 repeats, no sweep, compile or MuJoCo (under a minute).")
    ] = False,
    config: Annotated[Path, typer.Option("--config", help="Walker to benchmark.")] = DEFAULT_CONFIG,
    out: Annotated[Path, typer.Option("--out", help="Directory of bench.md and bench.json.")] = DEFAULT_OUT,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Print each measurement as it is made.")] = False,
) -> None:
    """Time the compiled loops against a solve_ivp baseline (and MuJoCo); print and write the table."""
    from biped_sim.bench.report import markdown, write_report
    from biped_sim.bench.runner import BenchSettings, run_bench
    from biped_sim.config import load_config

    load_config(config)  # bad input fails here, in one line
    check_writable_dir(out)
    settings = BenchSettings.quick_run(config) if quick else BenchSettings(config)
    result = run_bench(settings, log=lambda line: typer.echo(line, err=True) if verbose else None)
    md_path, json_path = write_report(result, out)
    typer.echo(markdown(result), nl=False)
    typer.echo(f"(written: {md_path}, {json_path})", err=True)
