"""The benchmark's pieces that can fail: the baseline simulates the same walker, the report's format."""

from __future__ import annotations

import importlib.util
import math
import re
from pathlib import Path

import numpy as np
import pytest

from biped_sim.bench.report import markdown, summary_line, targets
from biped_sim.bench.runner import CASES, HEADLINE, BenchSettings, run_bench

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "round_foot_walker.yaml"


@pytest.fixture(scope="module")
def short_bench() -> dict:
    """The benchmark on 1 s of walking (two heel strikes), one repeat, no start-up/sweep/compile/MuJoCo runs."""
    settings = BenchSettings(
        CONFIG, t_end=1.0, repeats=1, slow_repeats=1, sweep_runs=0, compile_time=False, mujoco=False
    )
    return run_bench(settings)


def test_baseline_step_periods_match_dopri5_at_the_same_tolerance(short_bench: dict) -> None:
    rows = {row["label"]: row for row in short_bench["rows"]}
    baseline = next(row for row in short_bench["rows"] if row["method"] == "baseline")
    assert baseline["status"] == "walking"
    assert baseline["n_strikes"] == rows[HEADLINE]["n_strikes"] == 2
    assert short_bench["baseline_vs_headline_max_period_difference_s"] < 1e-6
    assert baseline["period_error"] < 1e-5


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
