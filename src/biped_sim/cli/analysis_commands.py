"""``biped-sim limit-cycle``, ``bifurcation``, ``converge`` and ``validate``: gait analysis commands."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from biped_sim.cli.common import ConfigArgument, SetOption, app, fail, load, user_errors
from biped_sim.io.output import check_writable_dir


@app.command("limit-cycle")
@user_errors
def limit_cycle_command(
    config_path: ConfigArgument,
    set_: SetOption = None,
    guess: Annotated[
        str | None,
        typer.Option(
            "--guess",
            help="Initial guess: the walker's initial-state keys as a mapping, or their values in order "
            "('[stance_angle, stance_rate, swing_angle, swing_rate]' for the compass); rigid: or its section's.",
        ),
    ] = None,
    settle_steps: Annotated[
        int | None,
        typer.Option(
            "--settle-steps",
            min=0,
            help="Steps walked from the guess before Newton (default: 30 rigid, 20 compliant); 0 finds the cycle "
            "nearest the guess, stable or not.",
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
) -> None:
    """Period-1 gait (fixed point of the step map at heel strike) and its Floquet multipliers."""
    from biped_sim.rigid.limit_cycle import SearchFellError
    from biped_sim.studies.limit_cycle import guess_keys, limit_cycle, parse_guess

    config = load(config_path, set_)
    start = parse_guess(guess, *guess_keys(config)) if guess is not None else None
    try:
        cycle = limit_cycle(config, start, settle_steps)
    except SearchFellError as exc:  # the search failed: no gait from its starts (the input was fine)
        fail(exc.reason, 1)
    doc = cycle.to_json()
    if as_json:
        typer.echo(json.dumps(doc, indent=2))
    if not cycle.converged:
        fail(cycle.failure(), 1)
    if as_json:
        return
    table = Table(title=f"{doc['dynamics']} {doc['walker']} limit cycle, slope {doc['slope']:g}")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_row("converged", f"{doc['converged']} (residual {doc['residual']:.1e}, tolerance {doc['tolerance']:g})")
    for key, value in doc["fixed_point"].items():
        table.add_row(key, f"{value:.10f}")
    for where, lines in doc["lines"].items():
        for key, value in lines.items():
            table.add_row(f"{key} ({where.replace('_', ' ')})", f"{value:.10f}")
    table.add_row("step period [s]", f"{doc['step_period']:.8f}")
    table.add_row("step length [m]", f"{doc['step_length']:.8f}")
    table.add_row("speed [m/s]", f"{doc['speed']:.6f}")
    for re, im in doc["multipliers"]:
        table.add_row("multiplier", f"{re:.8f} {im:+.8f}i  (|{math.hypot(re, im):.6f}|)")
    table.add_row("stable", str(doc["stable"]))
    console = Console()
    console.print(table)
    for note in doc["notes"]:
        console.print(f"  {note}", highlight=False)


@app.command("converge")
@user_errors
def converge_command(
    config_path: ConfigArgument,
    set_: SetOption = None,
    levels: Annotated[int, typer.Option("--levels", help="Contact settings, 2 to 7 (stiffness x10 each).")] = 5,
    mu_kinetic: Annotated[float | None, typer.Option("--mu-kinetic", help="LuGre mu_k [default 1.0].")] = None,
    mu_static: Annotated[float | None, typer.Option("--mu-static", help="LuGre mu_s [default 1.2].")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
) -> None:
    """The compliant gait against the rigid gait of the same walker as the contact stiffens."""
    from dataclasses import asdict

    from biped_sim.studies.convergence import converge, strike_violations

    config = load(config_path, set_)
    rigid, rows = converge(config, levels, mu_kinetic=mu_kinetic, mu_static=mu_static)
    check, violations = strike_violations(config, rigid, mu_kinetic, mu_static)
    if as_json:
        doc = {
            "rigid": rigid.to_json(),
            "rigid_strike": None if check is None else {**asdict(check), "violations": violations},
            "levels": [asdict(r) for r in rows],
        }
        typer.echo(json.dumps(doc, indent=2))
        return
    table = Table(title=f"Compliant -> rigid, rigid step period {rigid.step_period:.8f} s")
    for column in (
        "stiffness",
        "restitution",
        "LuGre sigma0",
        "touchdown diff",
        "period diff [s]",
        "settled",
        "slip [m]",
    ):
        table.add_column(column, justify="right")
    for r in rows:
        table.add_row(
            f"{r.stiffness:.3e}",
            f"{r.restitution:.4f}",
            f"{r.bristle_stiffness:.0e}",
            f"{r.touchdown_difference:.2e}",
            f"{r.period_difference:.2e}",
            f"{r.settled:.1e}",
            f"{r.slip:.1e}",
        )
    console = Console()
    console.print(table)
    smallest = min((r.touchdown_difference for r in rows if math.isfinite(r.touchdown_difference)), default=math.nan)
    console.print(f"smallest touchdown-state difference: {smallest:.2e}", highlight=False)
    for violation in violations:
        console.print(
            f"warning: the rigid strike is not the stiff-contact limit: {violation}", highlight=False, soft_wrap=True
        )


@app.command("bifurcation")
@user_errors
def bifurcation_command(
    config_path: ConfigArgument,
    set_: SetOption = None,
    param: Annotated[str, typer.Option("--param", help="Parameter to vary (ground.slope).")] = "ground.slope",
    start: Annotated[float, typer.Option("--from", help="First slope [rad].")] = 0.005,
    stop: Annotated[float, typer.Option("--to", help="Last slope [rad].")] = 0.019,
    n: Annotated[int, typer.Option("--n", help="Number of slopes (at least 2).")] = 57,
    out: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path("results/bifurcation"),
) -> None:
    """Continuation of the rigid period-1 gait and brute-force steady states against the slope (CSV, PNG, SVG)."""
    from biped_sim.plots import save_figure
    from biped_sim.report.bifurcation import bifurcation_figure
    from biped_sim.studies.bifurcation import bifurcation_diagram, check_bifurcation, write_bifurcation

    config = load(config_path, set_)
    check_bifurcation(config, start, stop, n, param)
    check_writable_dir(out)
    t0 = time.perf_counter()
    diagram = bifurcation_diagram(config, start, stop, n, param)
    write_bifurcation(diagram, out)
    save_figure(bifurcation_figure(diagram), out, "bifurcation")
    flip = diagram.period_doubling_slope
    Console().print(
        f"{n} slopes in {time.perf_counter() - t0:.1f} s; period doubling at slope "
        + (f"{flip:.6f}" if flip is not None else "none in range")
        + f"; files: {out}/ (bifurcation.csv, brute_force.csv, bifurcation.png, bifurcation.svg)",
        highlight=False,
    )


@app.command("validate")
@user_errors
def validate_command(
    out: Annotated[Path, typer.Option("--out", help="Report directory.")] = Path("results/validation"),
) -> None:
    """Every physics check against published or analytic numbers; writes report.md; exit 1 on any failure."""
    from biped_sim.bench.mujoco_check import SKIP, mujoco_stages
    from biped_sim.studies.validation import run_validation

    check_writable_dir(out)
    console = Console()
    extra = mujoco_stages()
    if not extra:
        console.print(SKIP, highlight=False, soft_wrap=True)
    checks, extras = run_validation(
        out, progress=lambda stage: console.print(f"checking: {stage}", highlight=False), extra=extra
    )
    failed = [c for c in checks if not c.passed]
    for c in checks:
        mark = "pass" if c.passed else "FAIL"
        console.print(f"{mark}  {c.group}: {c.check}: {c.obtained} (expected {c.expected})", highlight=False)
    console.print(
        f"{len(checks) - len(failed)} of {len(checks)} checks pass in {extras['wall_time_s']:.0f} s; report: "
        f"{out / 'report.md'}",
        highlight=False,
    )
    if failed:
        fail(f"{len(failed)} validation check(s) failed", code=1)
