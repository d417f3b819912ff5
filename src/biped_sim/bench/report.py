"""Presentation of the benchmark: the Markdown table (printed and written), targets, bench.json.

``bench.md`` is exactly what ``biped-sim bench`` prints, so the performance table (docs/guide/) can be pasted
from either.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from biped_sim.io.atomic import write_json_atomic, write_text_atomic

COLUMNS = ("method", "dt [s]", "wall [s]", "RHS evals", "steps", "us/eval", "RTF", "period err", "vs baseline")


def _num(value: float | None, spec: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    if isinstance(value, float) and math.isinf(value):
        return "fell" if spec == "err" else "inf"
    if spec == "err":
        return f"{value:.1e}"
    return format(value, spec)


def table(result: dict[str, Any]) -> str:
    """The per-method Markdown table."""
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    for row in result["rows"]:
        cells = (
            row["label"],
            _num(row["dt"], "g"),
            _num(row["wall_s"], ".3f"),
            f"{row['rhs_evals']:,}",
            f"{row['accepted_steps']:,}",
            _num(row["us_per_eval"], ".2f"),
            _num(row["rtf"], ".3g"),
            _num(row["period_error"], "err"),
            f"{row['ratio_vs_baseline']:.3g}x",
        )
        lines.append("| " + " | ".join(cells) + " |")
    mj = result.get("mujoco") or {}
    if mj.get("available"):
        cells = (
            f"MuJoCo {mj['version']} RK4 (MJCF walker)",
            _num(mj["timestep"], "g"),
            _num(mj["wall_s"], ".3f"),
            "-",
            f"{mj['steps']:,}",
            f"{mj['us_per_step']:.2f}/step",
            _num(mj["rtf"], ".3g"),
            "-",
            "-",
        )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def headline_row(result: dict[str, Any]) -> dict[str, Any]:
    """The row of the summary line and the targets (dopri5 rtol 1e-6)."""
    return next(r for r in result["rows"] if r["label"] == result["headline"])


def fastest_accurate_row(result: dict[str, Any]) -> dict[str, Any] | None:
    """Our fastest row (by RTF) whose step periods meet the tolerance."""
    ok = [r for r in result["rows"] if r["method"] != "baseline" and r["period_error"] <= result["period_tolerance"]]
    return max(ok, key=lambda r: r["rtf"]) if ok else None


def targets(result: dict[str, Any]) -> list[tuple[str, str, bool | None]]:
    """(target, measured, met) for each target of issues 4 and 13; met is None when not measured."""
    head = headline_row(result)
    out: list[tuple[str, str, bool | None]] = [
        ("dopri5 rtol 1e-6 >= 50x baseline", f"{head['ratio_vs_baseline']:.0f}x", head["ratio_vs_baseline"] >= 50),
        ("RHS evaluation < 2 us", f"{result['rhs_alone_us']:.2f} us", result["rhs_alone_us"] < 2.0),
        ("loop overhead < 25 %", f"{result['loop_overhead']:.0%}", result["loop_overhead"] < 0.25),
    ]
    minimal = next((r for r in result["rows"] if r["label"] == result.get("minimal")), None)
    if minimal is not None:  # issue 13: the minimal-coordinate formulation
        rhs_us, ratio = result["rhs_alone_minimal_us"], minimal["rtf"] / head["rtf"]
        out.append(("minimal-coordinate RHS < 0.4 us", f"{rhs_us:.2f} us", rhs_us < 0.4))
        out.append(("minimal-coordinate RTF >= 2x absolute (dopri5 rtol 1e-6)", f"{ratio:.2f}x", ratio >= 2.0))
    cold = result.get("startup", {}).get("cold")
    if cold:
        out.append(("cold first run < 12 s", f"{cold['to_first_step_s']:.1f} s", cold["to_first_step_s"] < 12.0))
    cached = result.get("startup", {}).get("cached")
    if cached:
        out.append(("cached start-up < 1.5 s", f"{cached['to_first_step_s']:.2f} s", cached["to_first_step_s"] < 1.5))
    sweep = result.get("sweep")
    if sweep and "speedup_2_vs_1" in sweep:
        out.append(("2 workers >= 1.7x 1 worker", f"{sweep['speedup_2_vs_1']:.2f}x", sweep["speedup_2_vs_1"] >= 1.7))
    for name, basin in result.get("rigid_map", {}).get("basins", {}).items():
        out.append(
            (
                f"basin {name}, 2 workers < {basin['target_s']:g} s",
                f"{basin['wall_s']:.1f} s",
                basin["wall_s"] < basin["target_s"],
            )
        )
    for name, label in (("global_fit", "global fit, 2 parameters, 7 periods"), ("posterior", "4,000-draw posterior")):
        row = result.get("fit", {}).get(name)
        if row:
            ok = row["wall_s"] < row["target_s"]
            out.append((f"{label}, 2 workers < {row['target_s']:g} s", f"{row['wall_s']:.1f} s", ok))
    for pair, row in result.get("fit", {}).get("recovery", {}).items():
        ok = row["wall_s_per_fit"] < row["target_s_per_fit"]
        label = f"recovery check ({pair}), per fit, 2 workers < {row['target_s_per_fit']:g} s"
        out.append((label, f"{row['wall_s_per_fit']:.1f} s", ok))
    out += uncertainty_targets(result.get("uncertainty"))
    out += run_cost_targets(result.get("run_cost"))
    mj = result.get("mujoco") or {}
    best = fastest_accurate_row(result)
    if mj.get("available") and best is not None:
        out.append(
            (
                "RTF of our fastest accurate method >= MuJoCo's (timestep 1e-4 s)",
                f"{best['rtf']:.3g} ({best['label']}) vs {mj['rtf']:.3g}",
                best["rtf"] >= mj["rtf"],
            )
        )
    return out


def uncertainty_targets(section: dict[str, Any] | None) -> list[tuple[str, str, bool | None]]:
    """Issue 21's targets: the 1,024-sample ensemble and the N = 256 Sobol study, 2 workers."""
    out: list[tuple[str, str, bool | None]] = []
    for name, label in (("ensemble", "1,024-sample ensemble (4 s runs)"), ("sobol", "Sobol indices, 4 keys, N = 256")):
        row = (section or {}).get(name)
        if row:
            ok = row["wall_s"] < row["target_s"]
            out.append((f"{label}, 2 workers < {row['target_s']:g} s", f"{row['wall_s']:.1f} s", ok))
    return out


def run_cost_targets(section: dict[str, Any] | None) -> list[tuple[str, str, bool | None]]:
    """Issue 30's targets: a run, a fit evaluation and an uncertainty sample at most 1.2x their integration."""
    out: list[tuple[str, str, bool | None]] = []
    for row in (section or {}).get("rows", []):
        ratio = row.get("simulate_ratio", row.get("call_ratio"))
        measured = f"{ratio:.2f}x"
        if "with_measures_ratio" in row:
            measured += f" ({row['with_measures_ratio']:.2f}x with every measure of its files)"
        out.append((f"{row['label']} <= {row['target']:g}x its integration", measured, row["met"]))
    return out


def uncertainty_notes(section: dict[str, Any] | None) -> list[str]:
    """The ensemble's throughput against MuJoCo's rollouts."""
    if not section:
        return []
    ens, mj = section["ensemble"], section["mujoco_rollout"]
    line = f"Uncertainty ensemble: {ens['runs']} runs of {section['t_end']:g} s, {ens['runs_per_s']:.2f} runs/s"
    line += " on 2 workers"
    if mj.get("available"):
        line += f"; MuJoCo {mj['version']} rollout ({mj['rollouts']} rollouts, {mj['threads']} threads, timestep "
        line += f"{mj['timestep']:g} s, open loop): {mj['runs_per_s']:.2f} runs/s"
        line += f"; ratio {mj['ensemble_over_mujoco']:.2f}x"
    else:
        line += f"; MuJoCo rollout not run ({mj['reason']})"
    return [line + "."]


def notes(result: dict[str, Any]) -> list[str]:
    """The lines under the table: reference, RHS alone, start-up, sweep, MuJoCo, targets."""
    ref = result["reference"]
    lines = [
        f"Walker `{result['config']}`, {result['t_end']:g} s simulated, median of {result['repeats']} runs after a "
        f"warm-up ({result['slow_repeats']} for rows over {result['slow_run_s']:g} s a run); adaptive rows use "
        f"atol = 1e-3 rtol. Period error: worst relative step-period error against "
        f"{ref['method']} rtol {ref['rtol']:g} ({ref['n_strikes']} heel strikes). Fixed-step rows run at the "
        f"largest dt meeting {result['period_tolerance']:g}.",
        f"RHS alone (compiled, on the visited states, best of 3): {result['rhs_alone_us']:.3f} us; loop overhead "
        f"of the {result['headline']} row: {result['loop_overhead']:.0%} of its best wall time"
        + (
            f"; minimal coordinates: {result['rhs_alone_minimal_us']:.3f} us"
            if "rhs_alone_minimal_us" in result
            else ""
        )
        + (
            f"; the kneed walker (a tree of four bodies, two knee stops) in minimal coordinates: "
            f"{result['rhs_alone_kneed_minimal_us']:.3f} us ({result['kneed_minimal_vs_compass_minimal']:.2f}x the "
            "compass's)."
            if "rhs_alone_kneed_minimal_us" in result
            else "."
        ),
        f"Baseline vs {result['headline']} step periods: max difference "
        f"{result['baseline_vs_headline_max_period_difference_s']:.1e} s.",
    ]
    startup = result.get("startup", {})
    if "cold" in startup:
        cold = startup["cold"]
        compiling = cold["build_s"] + cold["first_integration_s"]
        lines.append(
            f"Cold first run (empty numba cache, median of {cold.get('runs', 1)}): {cold['to_first_step_s']:.1f} s "
            f"from the shell to the first integration step (compiling: {compiling:.1f} s)."
        )
    if "cached" in startup:
        cached = startup["cached"]
        lines.append(
            f"Cached start-up: {cached['to_first_step_s']:.2f} s from the shell to the first integration step "
            f"(imports {cached['import_s']:.2f} s, build {cached['build_s']:.2f} s, "
            f"first integration {cached['first_integration_s']:.3f} s)."
        )
    sweep = result.get("sweep")
    if sweep:
        per = sweep["per_jobs"]
        parts = [f"{n} worker{'s' if n != '1' else ''}: {v['runs_per_minute']:.0f} runs/min" for n, v in per.items()]
        lines.append(
            f"Sweep of {sweep['runs']} runs ({sweep['t_end']:g} s each, files written): " + ", ".join(parts)
            + (f" ({sweep['speedup_2_vs_1']:.2f}x)." if "speedup_2_vs_1" in sweep else ".")
        )  # fmt: skip
    lines += compile_notes(result.get("compile"))
    lines += rigid_map_notes(result.get("rigid_map"))
    lines += space_notes(result.get("space"), result.get("rows", []))
    lines += uncertainty_notes(result.get("uncertainty"))
    mj = result.get("mujoco")
    if mj is not None:
        if mj.get("available"):
            lines.append(
                f"MuJoCo {mj['version']} ({mj['integrator']}, timestep {mj['timestep']:g} s): RTF {mj['rtf']:.3g}, "
                f"{mj['us_per_step']:.1f} us/step, step period {mj['step_period_s']:.4f} s "
                f"({mj['n_strikes']} heel strikes, {mj['status']}; mean of the last five) vs ours "
                f"{mj['reference_step_period_s']:.4f} s."
            )
        else:
            lines.append(f"MuJoCo: not run ({mj['reason']}).")
    lines.append("")
    lines.append("Targets: " + "; ".join(f"{name}: {value} {_mark(met)}" for name, value, met in targets(result)))
    lines.append("")
    lines.append(summary_line(result))
    return lines


def rigid_map_notes(rigid: dict[str, Any] | None) -> list[str]:
    """The rigid step map's lines: per-step times compiled vs scipy, and the basins' wall times."""
    if not rigid:
        return []
    rows = rigid["per_step"]
    parts = [
        f"{name} {v['scipy_us']:.0f} -> {v['compiled_us']:.1f} us ({v['speedup']:.0f}x)"
        for name, v in rows.items()
        if "scipy_us" in v
    ]
    lines = [
        "Rigid step from the fixed point, scipy solve_ivp DOP853 over the same equations -> compiled (rtol 1e-12): "
        + ", ".join(parts)
        + "."
    ]
    if run := rows.get("kneed_run_step"):
        lines.append(
            f"Kneed run step (a push, a step down, samples at 1 kHz): {run['compiled_us']:.1f} us, "
            f"{run['over_plain']:.2f}x its plain step."
        )
    for name, basin in rigid.get("basins", {}).items():
        lines.append(
            f"Basin {name}: {basin['cells']} cells x {basin['steps']} steps in {basin['wall_s']:.1f} s with "
            f"{basin['workers']} workers (pool start included; {basin['fraction_walking']:.1%} of the cells walk)."
        )
    return lines


def space_notes(space: dict[str, Any] | None, rows: list[dict[str, Any]]) -> list[str]:
    """The walkers in space: the 3D rigid step map's rate, the compliant 3D run's real-time factor beside the
    four-legged walker's rows, and MuJoCo's run of that walker with the first steps' agreement."""
    if not space:
        return []
    steps = ", ".join(f"{name} {v['step_us'] / 1e3:.2f} ms ({v['steps_per_s']:.0f} steps/s)"
                      for name, v in space["rigid_step"].items())  # fmt: skip
    run = space["compliant_run"]
    four = ", ".join(f"{r['label'].split(', ', 1)[1]} RTF {r['rtf']:.3g}" for r in rows if "four-legged" in r["label"])
    lines = [
        f"Rigid step in space from the gait (compiled): {steps}.",
        f"Compliant Kuo-type compass on spheres (3D, K = 1e7, dopri5 rtol 1e-8): {run['t_final']:g} s {run['status']} "
        f"in {run['wall_s']:.2f} s, RTF {run['rtf']:.3g}" + (f" (four-legged walker: {four})." if four else "."),
    ]
    mj = space.get("mujoco")
    if mj and mj.get("available"):
        diff = {k: ", ".join(f"{100 * d:+.2f}" for d in v["relative_difference"]) for k, v in mj["quantities"].items()}
        lines.append(
            f"MuJoCo on that walker: RTF {mj['mujoco']['rtf']:.3g} ({mj['mujoco']['status']}); against ours [%], "
            f"periods {diff['period']}; lengths {diff['length']}; widths {diff['width']}; sways {diff['sway']}."
        )
    elif mj:
        lines.append(f"MuJoCo on the walker in space: not run ({mj['reason']}).")
    return lines


def compile_notes(rows: list[dict[str, Any]] | None) -> list[str]:
    """The report's lines: per group, the cold and the cached warm-up and the costliest functions."""
    lines = []
    for row in rows or []:
        cold, cached = row["cold"], row["cached"]
        top = ", ".join(f"{entry['function'].rsplit('.', 1)[-1]} {entry['cpu_s']:.1f}" for entry in cold["top"][:4])
        lines.append(
            f"Cold compile, {row['group']}: {cold['functions']} functions, {cold['cpu_s']:.1f} CPU s "
            f"({cold['wall_s']:.1f} s wall; lowering {cold['lowering_cpu_s']:.1f}, numba's front end "
            f"{cold['front_end_cpu_s']:.1f}; costliest: {top}); cached {cached['cpu_s']:.1f} CPU s "
            f"({cached['wall_s']:.1f} s wall, {cached['functions']} compiled)."
        )
    return lines


def _mark(met: bool | None) -> str:
    return "(met)" if met else "(missed)" if met is not None else "(not measured)"


def summary_line(result: dict[str, Any]) -> str:
    """``ratio_vs_baseline=<x> rtf=<y> rhs_us=<z>`` for the headline row (rhs_us: wall time per RHS evaluation)."""
    head = headline_row(result)
    return f"ratio_vs_baseline={head['ratio_vs_baseline']:.1f} rtf={head['rtf']:.2f} rhs_us={head['us_per_eval']:.3f}"


def markdown(result: dict[str, Any]) -> str:
    """bench.md: title, table and notes (what the command prints)."""
    title = "biped-sim bench" + (" --quick" if result["quick"] else "")
    env = result["environment"]
    header = (
        f"{title}: Python {env['python']}, numpy {env['numpy']}, scipy {env['scipy']}, numba {env['numba']}, "
        f"{env['cpus']} CPUs ({env['processor']})"
    )
    return "\n".join([header, "", table(result), "", *notes(result)]) + "\n"


def write_report(result: dict[str, Any], out_dir: Path) -> tuple[Path, Path]:
    """Write bench.json and bench.md into ``out_dir`` (atomically); returns their paths."""
    json_path, md_path = out_dir / "bench.json", out_dir / "bench.md"
    write_json_atomic(json_path, result)
    write_text_atomic(md_path, markdown(result))
    return md_path, json_path
