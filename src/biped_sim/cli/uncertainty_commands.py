"""``biped-sim uncertainty``: a walker's predictions with error bars and which parameters matter."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

from biped_sim.cli.common import ConfigArgument, SetOption, app, load, user_errors
from biped_sim.errors import ArgumentError
from biped_sim.io.output import check_writable_dir

ParamOption = Annotated[
    list[str] | None,
    typer.Option(
        "--param",
        help="KEY=DIST:N1:N2 with DIST uniform:LO:HI, normal:MEAN:SD, lognormal:MEDIAN:SIGMA, "
        "triangular:LO:MODE:HI or interval:LO:HI (repeatable).",
    ),
]
JobsOption = Annotated[int | None, typer.Option("--jobs", "-j", help="Parallel workers (default: all cores).")]
ExecutorOption = Annotated[str, typer.Option("--executor", help="local (processes) or dask.")]
SchedulerOption = Annotated[
    str | None, typer.Option("--scheduler", help="Dask scheduler address (with --executor dask).")
]


def _print_summary(doc: dict[str, Any], out: Path) -> None:
    console = Console(stderr=True, soft_wrap=True)
    stats = doc["statistics"]
    walking = stats["probability_walking"]
    console.print(
        f"{doc['runs']} runs in {doc['wall_time_s']:.1f} s ({doc['chunks_reused']} chunks reused): P(walk) = "
        f"{walking['value']:.3f} [{walking['ci'][0]:.3f}, {walking['ci'][1]:.3f}]",
        highlight=False,
    )
    for name, d in stats["outputs"].items():
        if d["mean"] is not None:
            console.print(f"  {name}: {d['mean']:.6g} +- {d['sd']:.3g} (n {d['n']})", highlight=False)
    for name, o in (doc["sobol"] or {"outputs": {}})["outputs"].items():
        if o["indices"] is not None:
            top = ", ".join(f"{k} {o['indices'][k]['ST']:.2f}" for k in o["ranking_total"][:3])
            console.print(f"  total Sobol index of {name}: {top}", highlight=False)
    for name, o in (doc["surrogate"] or {}).items():
        if o["indices"] is not None:
            top = sorted(o["indices"], key=lambda k: -o["indices"][k]["ST"])[:3]
            ranked = ", ".join(f"{k} {o['indices'][k]['ST']:.2f}" for k in top)
            console.print(
                f"  surrogate total index of {name}: {ranked} "
                f"(hold-out error {o['holdout_relative_rms_error']:.2g} sd)",
                highlight=False,
            )
    for note in doc["notes"]:
        console.print(f"  {note}", highlight=False)
    console.print(f"files: {out}/", highlight=False)


@app.command("uncertainty")
@user_errors
def uncertainty_command(
    config_path: ConfigArgument,
    param: ParamOption = None,
    spec_file: Annotated[
        Path | None, typer.Option("--spec", help="YAML file with an 'uncertainty' section: parameters, samples, seed.")
    ] = None,
    posterior: Annotated[
        Path | None, typer.Option("--from-fit", help="A fit directory: its posterior samples (posterior.h5).")
    ] = None,
    set_: SetOption = None,
    samples: Annotated[
        int | None,
        typer.Option("--samples", "-n", help="Samples (a power of two for sobol; base points with --sobol)."),
    ] = None,
    method: Annotated[str | None, typer.Option("--method", help="sobol (scrambled, default) or lhs.")] = None,
    sobol_indices: Annotated[
        bool, typer.Option("--sobol", help="Sobol indices: Saltelli's design, samples x (keys + 2) runs.")
    ] = False,
    seed: Annotated[int | None, typer.Option("--seed", help="Seed of the design.")] = None,
    surrogate_order: Annotated[
        int | None, typer.Option("--surrogate", help="Also a polynomial-chaos surrogate's indices, of this degree.")
    ] = None,
    jobs: JobsOption = None,
    executor: ExecutorOption = "local",
    scheduler: SchedulerOption = None,
    out: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path("results/uncertainty"),
    as_json: Annotated[bool, typer.Option("--json", help="Print the statistics and indices as JSON.")] = False,
) -> None:
    """Propagate what is known of config keys through runs: statistics of the gait, probability of walking,
    bands, histograms and (--sobol) Sobol indices (uncertainty.h5, samples.csv, PNG, SVG).

    Finished chunks of samples are kept in OUT/samples: a rerun of the same study resumes where it stopped.
    """
    from biped_sim.io.posterior import read_posterior
    from biped_sim.report.uncertainty import save_study_figures
    from biped_sim.studies.uncertainty.distributions import parse_param, read_spec
    from biped_sim.studies.uncertainty.files import write_study
    from biped_sim.studies.uncertainty.study import DEFAULT_SAMPLES, UncertaintySpec, run_study
    from biped_sim.sweep import study_executor, workers_for

    config = load(config_path, set_)
    distributions, options = read_spec(str(spec_file)) if spec_file is not None else ([], {})
    distributions += [parse_param(text) for text in param or []]
    chosen = "saltelli" if sobol_indices else method or options.get("method", "sobol")
    count = samples if samples is not None else options.get("samples", DEFAULT_SAMPLES)  # -n 0 is refused, not 256
    spec = UncertaintySpec(
        config, tuple(distributions), count, chosen,
        seed if seed is not None else options.get("seed", 0),
        read_posterior(posterior) if posterior is not None else None, surrogate_order,
    )  # fmt: skip
    check_writable_dir(out)
    console = Console(stderr=True)
    progress = None if as_json else lambda done, total: console.print(f"samples {done}/{total}", end="\r")
    with study_executor(executor, workers_for(spec.rows, jobs), scheduler) as pool:
        study = run_study(spec, out, pool, progress)
    files = write_study(study, out) + save_study_figures(study, out)
    doc = study.to_json()
    if as_json:
        typer.echo(json.dumps({**doc, "files": [str(p) for p in files]}, indent=2))
        return
    _print_summary(doc, out)


@app.command("mfpt")
@user_errors
def mfpt_command(
    config_path: ConfigArgument,
    set_: SetOption = None,
    roughness: Annotated[
        str, typer.Option("--roughness", help="Comma-separated levels: height sd [leg lengths] or slope sd [rad].")
    ] = "0.0005,0.001,0.002",
    ground: Annotated[
        str | None, typer.Option("--ground", help="height (random profile) or slope (rimless wheel, walkers in space).")
    ] = None,
    seeds: Annotated[int, typer.Option("--seeds", help="Walks (seeds) per roughness level.")] = 20,
    cap: Annotated[int, typer.Option("--cap", help="Steps after which a walk stops (censored).")] = 100,
    jobs: JobsOption = None,
    executor: ExecutorOption = "local",
    scheduler: SchedulerOption = None,
    out: Annotated[Path, typer.Option("--out", help="Output directory.")] = Path("results/mfpt"),
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
) -> None:
    """Mean first-passage time (steps before a fall) on random ground against roughness, with its confidence
    interval; for the rigid rimless wheel on random slopes also the Markov chain's (mfpt.json, PNG, SVG)."""
    from biped_sim.io.atomic import write_json_atomic
    from biped_sim.plots import save_figure
    from biped_sim.report.uncertainty import mfpt_figure
    from biped_sim.studies.uncertainty.mfpt import check_mfpt_input, mfpt_curve
    from biped_sim.studies.uncertainty.rimless_chain import walks_random_slopes
    from biped_sim.sweep import study_executor, workers_for

    config = load(config_path, set_)
    try:
        levels = [float(text) for text in roughness.split(",")]
    except ValueError:
        raise ArgumentError("roughness", f"{roughness[:60]!r}: expected comma-separated numbers") from None
    chosen = ground or ("slope" if walks_random_slopes(config) else "height")
    check_mfpt_input(config, chosen, levels, seeds, cap)
    check_writable_dir(out)
    workers = 1 if chosen == "slope" else workers_for(len(levels) * seeds, jobs)
    with study_executor(executor, workers, scheduler) as pool:
        curve = mfpt_curve(config, chosen, levels, seeds, cap, pool)
    doc = curve.to_json()
    out.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out / "mfpt.json", doc)
    files = [out / "mfpt.json", *save_figure(mfpt_figure([curve]), out, "mfpt")]
    if as_json:
        typer.echo(json.dumps({**doc, "files": [str(p) for p in files]}, indent=2))
        return
    console = Console(soft_wrap=True)
    for row in doc["levels"]:
        chain = f", chain {row['chain_mfpt']:.4g}" if "chain_mfpt" in row else ""
        console.print(
            f"roughness {row['roughness']:g}: MFPT {row['mfpt']:.4g} steps [{row['ci'][0]:.4g}, {row['ci'][1]:.4g}] "
            f"({row['falls']} falls, {row['censored']} at the cap{chain})",
            highlight=False,
        )
    console.print(f"files: {out}/", highlight=False)
