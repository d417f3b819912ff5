"""The benchmark's pieces that can fail: the baseline simulates the same walker, the report's format."""

from __future__ import annotations

import importlib.util
import math
import re
import sys
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from biped_sim.bench.report import markdown, summary_line, targets
from biped_sim.bench.runner import (
    BASELINE,
    CASES,
    HEADLINE,
    MINIMAL,
    PERIOD_TOLERANCE,
    SLOW_RUN_S,
    BenchSettings,
    Row,
    case_config,
    environment,
    integrate,
    run_bench,
)
from biped_sim.walkers import build_model

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "round_foot_walker.yaml"


@pytest.fixture(scope="module")
def short_bench() -> dict:
    """``bench --quick`` (no cold start-up, sweep, compile, basin, space, fit, uncertainty or MuJoCo rows) on 1 s of
    walking (two heel strikes), one repeat.

    About 20 s (45 s on a busy machine): the baseline alone is pure Python, and the fixed-step rows search
    their step size. Slow tier only.
    """
    settings = replace(BenchSettings.quick_run(CONFIG), t_end=1.0, repeats=1)
    return run_bench(settings)


@pytest.mark.slow
def test_baseline_step_periods_match_dopri5_at_the_same_tolerance(short_bench: dict) -> None:
    rows = {row["label"]: row for row in short_bench["rows"]}
    baseline = next(row for row in short_bench["rows"] if row["method"] == "baseline")
    assert baseline["status"] == "walking"
    assert baseline["n_strikes"] == rows[HEADLINE]["n_strikes"] == 2
    assert short_bench["baseline_vs_headline_max_period_difference_s"] < 1e-6
    assert baseline["period_error"] < 1e-5


@pytest.mark.slow
def test_bench_table_has_every_case_and_ends_with_the_summary_line(short_bench: dict) -> None:
    text = markdown(short_bench)
    lines = text.rstrip("\n").splitlines()
    assert re.fullmatch(r"ratio_vs_baseline=[0-9.]+ rtf=[0-9.]+ rhs_us=[0-9.]+", lines[-1])
    assert lines[-1] == summary_line(short_bench)
    for case in CASES:
        assert any(line.startswith(f"| {case.label} |") for line in lines)
    head = next(row for row in short_bench["rows"] if row["label"] == HEADLINE)
    assert head["ratio_vs_baseline"] > 1.0 and math.isfinite(head["rtf"])
    assert all(met is not None for _, _, met in targets(short_bench))


def test_baseline_strikes_when_the_compiled_dopri5_does_at_the_same_tolerance() -> None:
    """0.45 s, the first heel strike (2 s of pure Python): the same walker, events and all (1 s: slow tier)."""
    settings = BenchSettings(CONFIG, t_end=0.45)
    baseline_case = next(case for case in CASES if case.method == BASELINE)
    headline_case = next(case for case in CASES if case.label == HEADLINE)
    config = case_config(settings, baseline_case)
    assert config == case_config(settings, headline_case)  # same walker, method and tolerances
    model = build_model(config)
    baseline, compiled = integrate(model, config, BASELINE), integrate(model, config, "dopri5")
    assert baseline.status == compiled.status == "walking"
    assert len(baseline.strike_t) == len(compiled.strike_t) == 1
    assert abs(baseline.strike_t[0] - compiled.strike_t[0]) < 1e-6
    np.testing.assert_allclose(baseline.y[-1], compiled.y[-1], rtol=0, atol=1e-4)


def made_up_result() -> dict[str, Any]:
    """A bench.json of made-up numbers in the shape run_bench returns: every case, the baseline fell-free.

    The formatting needs no measurement; the measured result is checked in the slow tier above.
    """
    rows = []
    for k, case in enumerate(CASES):
        fixed = case.rtol is None
        wall = 8.0 if case.method == BASELINE else 0.2 + 0.1 * k
        row = Row(
            label=case.label,
            method=case.method,
            rtol=None if fixed else case.rtol,
            atol=None if fixed else 1e-3 * case.rtol,
            dt=1e-5 if fixed else None,
            status="walking",
            wall_s=wall,
            walls_s=[wall],
            rhs_evals=50_000,
            accepted_steps=8_000,
            n_strikes=2,
            us_per_eval=wall / 50_000 * 1e6,
            rtf=1.0 / wall,
            period_error=math.inf if case.method == "euler" else 1e-6,
            ratio_vs_baseline=8.0 / wall,
        )
        rows.append(asdict(row))
    return {
        "quick": False,
        "config": str(CONFIG),
        "t_end": 1.0,
        "repeats": 1,
        "slow_repeats": 1,
        "slow_run_s": SLOW_RUN_S,
        "period_tolerance": PERIOD_TOLERANCE,
        "reference": {"method": "dop853", "rtol": 1e-12, "atol": 1e-15, "n_strikes": 2, "periods": [0.3954]},
        "rows": rows,
        "headline": HEADLINE,
        "minimal": MINIMAL,
        "rhs_alone_us": 1.5,
        "rhs_alone_minimal_us": 0.35,
        "loop_overhead": 0.4,
        "baseline_vs_headline_max_period_difference_s": 2e-8,
        "startup": {
            "cold": {"import_s": 0.3, "build_s": 1.0, "first_integration_s": 12.0, "to_first_step_s": 13.4},
            "cached": {"import_s": 0.3, "build_s": 0.2, "first_integration_s": 0.02, "to_first_step_s": 0.6},
        },
        "environment": environment(),
    }


def test_bench_markdown_has_a_row_per_case_targets_and_the_summary_line_last() -> None:
    result = made_up_result()
    lines = markdown(result).rstrip("\n").splitlines()
    assert lines[0].startswith("biped-sim bench: Python ")
    for case in CASES:
        assert sum(line.startswith(f"| {case.label} |") for line in lines) == 1, case.label
    euler = next(line for line in lines if line.startswith("| euler |"))
    assert "| fell |" in euler  # an infinite period error is a fall, not a number
    assert lines[-1] == summary_line(result) == "ratio_vs_baseline=26.7 rtf=3.33 rhs_us=6.000"  # the headline row
    met = {name: ok for name, _, ok in targets(result)}
    assert met["RHS evaluation < 2 us"] and not met["loop overhead < 25 %"] and met["cached start-up < 1.5 s"]
    assert met["minimal-coordinate RHS < 0.4 us"]  # 0.35 us
    assert not met[
        "minimal-coordinate RTF >= 2x absolute (dopri5 rtol 1e-6)"
    ]  # its made-up wall is twice the headline's
    assert not met["cold first run < 12 s"]
    assert "Targets: " in "\n".join(lines)


def test_bench_markdown_reports_the_cold_compile_of_each_group() -> None:
    result = made_up_result()
    cold = {
        "wall_s": 40.0, "cpu_s": 26.4, "functions": 76, "lowering_cpu_s": 16.8, "front_end_cpu_s": 7.5,
        "top": [{"function": "biped_sim.integrate.explicit.advance_python_entry", "cpu_s": 10.2}],
    }  # fmt: skip
    cached = {**cold, "wall_s": 2.5, "cpu_s": 2.4, "functions": 0, "top": []}
    result["compile"] = [{"group": "planar explicit flat", "cold": cold, "cached": cached}]
    text = markdown(result)
    assert (
        "Cold compile, planar explicit flat: 76 functions, 26.4 CPU s (40.0 s wall; lowering 16.8, numba's front "
        "end 7.5; costliest: advance_python_entry 10.2); cached 2.4 CPU s (2.5 s wall, 0 compiled)."
    ) in text


def test_bench_markdown_reports_the_rigid_map_rows_and_the_basin_targets() -> None:
    result = made_up_result()
    result["rigid_map"] = {
        "per_step": {"simplest": {"scipy_us": 2000.0, "compiled_us": 40.0, "speedup": 50.0}},
        "basins": {
            "simplest_41x41x30": {
                "cells": 1681,
                "steps": 30,
                "workers": 2,
                "wall_s": 12.0,
                "target_s": 60.0,
                "fraction_walking": 0.01,
            },
            "compliant_21x21x10": {
                "cells": 441,
                "steps": 10,
                "workers": 2,
                "wall_s": 700.0,
                "target_s": 600.0,
                "fraction_walking": 0.1,
            },
        },
    }
    text = markdown(result)
    assert "simplest 2000 -> 40.0 us (50x)" in text and "Basin compliant_21x21x10: 441 cells" in text
    met = {name: ok for name, _, ok in targets(result)}
    assert met["basin simplest_41x41x30, 2 workers < 60 s"] and not met["basin compliant_21x21x10, 2 workers < 600 s"]


def test_bench_markdown_reports_the_walkers_in_space_beside_the_four_legged_walker_and_mujoco() -> None:
    result = made_up_result()
    agreement = {"ours": [0.7, 0.7], "mujoco": [0.7, 0.7], "relative_difference": [0.0003, -0.0121]}
    result["space"] = {
        "rigid_step": {"tinkertoy": {"step_us": 2500.0, "steps_per_s": 400.0}},
        "compliant_run": {"status": "walking", "t_final": 3.0, "wall_s": 6.0, "rtf": 0.5},
        "mujoco": {"available": True, "mujoco": {"rtf": 2.0, "status": "walking"},
                   "quantities": dict.fromkeys(("period", "length", "width", "sway"), agreement)},
    }  # fmt: skip
    text = markdown(result)
    assert "tinkertoy 2.50 ms (400 steps/s)" in text
    four = next(r["rtf"] for r in result["rows"] if r["label"] == "dopri5 1e-6, four-legged, spatial")
    assert f"3 s walking in 6.00 s, RTF 0.5 (four-legged walker: four-legged, spatial RTF {four:.3g}" in text
    assert "MuJoCo on that walker: RTF 2 (walking); against ours [%], periods +0.03, -1.21;" in text
    result["space"]["mujoco"] = {"available": False, "reason": "No module named 'mujoco'"}
    assert "MuJoCo on the walker in space: not run (No module named 'mujoco')." in markdown(result)


def test_bench_markdown_reports_the_uncertainty_rows_and_their_targets() -> None:
    result = made_up_result()
    result["uncertainty"] = {
        "t_end": 4.0,
        "ensemble": {"runs": 1024, "wall_s": 120.0, "runs_per_s": 8.5, "target_s": 300.0},
        "sobol": {"runs": 1536, "wall_s": 700.0, "runs_per_s": 2.2, "target_s": 600.0},
        "mujoco_rollout": {"available": True, "version": "3.3", "rollouts": 32, "threads": 2, "timestep": 1e-4,
                           "runs_per_s": 2.5, "ensemble_over_mujoco": 3.4},
    }  # fmt: skip
    text = markdown(result)
    assert "8.50 runs/s on 2 workers" in text and "ratio 3.40x" in text
    met = {name: ok for name, _, ok in targets(result)}
    assert met["1,024-sample ensemble (4 s runs), 2 workers < 300 s"]
    assert not met["Sobol indices, 4 keys, N = 256, 2 workers < 600 s"]


def test_bench_markdown_reports_the_run_cost_rows_against_their_target() -> None:
    result = made_up_result()
    result["run_cost"] = {
        "t_end": 10.0,
        "repeats": 5,
        "rows": [
            {"label": "simulate, minimal", "target": 1.2, "simulate_ratio": 1.05, "with_measures_ratio": 1.3,
             "met": True},
            {"label": "uncertainty sample", "target": 1.2, "call_ratio": 1.4, "met": False},
        ],
    }  # fmt: skip
    found = {name: (measured, ok) for name, measured, ok in targets(result)}
    assert found["simulate, minimal <= 1.2x its integration"] == (
        "1.05x (1.30x with every measure of its files)",
        True,
    )
    assert found["uncertainty sample <= 1.2x its integration"] == ("1.40x", False)
    assert "simulate, minimal <= 1.2x its integration" in markdown(result)


@pytest.mark.slow
def test_bench_times_a_run_and_a_study_evaluation_against_their_integration(short_bench: dict) -> None:
    rows = {row["label"]: row for row in short_bench["run_cost"]["rows"]}
    assert set(rows) == {
        *(f"simulate, {kind}" for kind in ("planar", "minimal", "spatial", "rigid")),
        "fit evaluation",
        "uncertainty sample",
    }
    for row in rows.values():
        ratio = row.get("simulate_ratio", row.get("call_ratio"))
        assert row["integration_s"] > 0.0 and 0.5 < ratio < 20.0, row


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="MuJoCo is the optional extra 'bench'")
def test_mujoco_walker_matches_initial_state_and_walks_one_step() -> None:
    from biped_sim import load_config
    from biped_sim.bench.mujoco_walker import MujocoWalker

    walker = MujocoWalker(load_config(CONFIG))
    result = walker.run(0.6)
    assert result["status"] == "walking"
    np.testing.assert_allclose(walker.qpos0[2:], [0.25, -0.5])
    assert len(result["strikes"]) == 1
    assert result["strikes"][0] == pytest.approx(0.389, abs=0.01)  # ours: 0.38908 s


def test_bench_markdown_reports_the_recovery_check_cost_per_fit_against_its_target() -> None:
    result = made_up_result()
    row = {"cases": 2, "recovered": 2, "rate": 1.0, "dishonest_misses": 0, "evaluations_per_fit": 280.0}
    result["fit"] = {"recovery": {"inertia+restitution": row | {"wall_s_per_fit": 21.0, "target_s_per_fit": 15.0}}}
    met = {name: (shown, ok) for name, shown, ok in targets(result)}
    assert met["recovery check (inertia+restitution), per fit, 2 workers < 15 s"] == ("21.0 s", False)


@pytest.mark.slow
def test_the_space_rows_step_from_the_gaits_they_name() -> None:
    """The 3D step map's rows time steps from gaits: each section point maps to itself (8-digit constants)."""
    from biped_sim.bench.space import CONFIGS as SPACE
    from biped_sim.bench.space import RIGID_CASES, rigid_space_steps
    from biped_sim.config import load_config
    from biped_sim.rigid.space_cycle import SpaceMap, space_walker_model

    for config_file, overrides, point in RIGID_CASES.values():
        step_map = SpaceMap(space_walker_model(load_config(SPACE / config_file, list(overrides))))
        np.testing.assert_allclose(step_map(np.array(point)), point, atol=2e-7)
    assert all(row["steps_per_s"] > 0.0 for row in rigid_space_steps(repeats=2).values())


def test_the_space_rows_say_why_mujoco_did_not_run(monkeypatch: pytest.MonkeyPatch) -> None:
    from biped_sim.bench.space import mujoco_space_run

    monkeypatch.setitem(sys.modules, "biped_sim.bench.mujoco_space", None)  # as without the extra
    out = mujoco_space_run()
    assert out["available"] is False and out["reason"].endswith("(install with make setup-bench)")
