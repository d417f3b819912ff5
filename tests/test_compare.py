"""Error tables against a reference: the arithmetic by hand, and `biped-sim compare` end to end."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from biped_sim.io.references import load_reference
from biped_sim.studies.compare import compare_periods, model_step_periods, stats_table, step_table
from biped_sim.testing import TINY_SWEEP_RUNS, write_reference

from .conftest import CONFIGS, DEFAULT_CONFIG, invoke, one_line_error

CORRAL = CONFIGS / "references" / "corral2020_liu_errors.yaml"


def fictitious_reference(tmp_path: Path, values: list[float], **extra: object) -> Path:
    """A step-period reference file in ``tmp_path`` with FICTITIOUS numbers (test data, not a measurement)."""
    return write_reference(tmp_path / "reference.yaml", values, **extra)


def test_error_table_arithmetic_by_hand(tmp_path: Path) -> None:
    reference = load_reference(fictitious_reference(tmp_path, [0.5, 0.4, 0.25]))
    comparison = compare_periods(reference, [0.55, 0.38, 0.25, 0.3])  # the 4th model step has no reference
    assert comparison.steps == [1, 2, 3]
    assert comparison.errors == pytest.approx([0.05, -0.02, 0.0])
    assert comparison.relative_errors == pytest.approx([10.0, 5.0, 0.0])
    stats = comparison.stats
    assert stats.n == 3
    assert stats.mean_abs == pytest.approx(0.07 / 3)
    assert stats.max_abs == pytest.approx(0.05)
    assert stats.rms_abs == pytest.approx(math.sqrt((0.05**2 + 0.02**2) / 3))  # 0.031091
    assert stats.mean_rel == pytest.approx(5.0)
    assert stats.max_rel == pytest.approx(10.0)
    assert stats.rms_rel == pytest.approx(math.sqrt(125 / 3))  # 6.4550


def test_steps_the_model_did_not_reach_are_left_out_of_the_statistics(tmp_path: Path) -> None:
    reference = load_reference(fictitious_reference(tmp_path, [0.5, 0.4, 0.25]))
    comparison = compare_periods(reference, [0.45], label="short")
    assert comparison.model_periods[0] == 0.45 and all(math.isnan(m) for m in comparison.model_periods[1:])
    assert (comparison.stats.n, comparison.stats.max_rel) == (1, pytest.approx(10.0))
    table = step_table([comparison])
    assert any("no model period for 2 reference step(s)" in note for note in table.notes)


def test_reference_step_numbers_and_skipped_model_steps(tmp_path: Path) -> None:
    reference = load_reference(fictitious_reference(tmp_path, [0.5, 0.25], steps=[2, 4]))
    comparison = compare_periods(reference, [0.1, 0.55, 0.2, 0.2])
    assert comparison.model_periods == [0.55, 0.2]
    assert comparison.relative_errors == pytest.approx([10.0, 20.0])
    assert model_step_periods([0.4, 0.9, 1.35]) == pytest.approx([0.4, 0.5, 0.45])  # the release is strike 0
    assert model_step_periods([0.4, 0.9, 1.35], skip=1) == pytest.approx([0.5, 0.45])


def test_published_errors_are_shown_step_by_step_beside_ours(tmp_path: Path) -> None:
    reference = load_reference(fictitious_reference(tmp_path, [0.5, 0.4, 0.25], published_errors=[str(CORRAL)]))
    comparison = compare_periods(reference, [0.5, 0.4, 0.25])
    assert comparison.published == {"Corral et al. 2020": [8.02, 0.42, 1.69]}
    table = step_table([comparison])
    assert table.rows[0]["published::Corral et al. 2020"] == 8.02
    assert "Corral et al. 2020 error [%]" in table.csv().splitlines()[0]
    stats = stats_table([comparison])
    published = stats.rows[1]
    assert published["label"] == "Corral et al. 2020 (published)"
    assert published["mean_rel"] == pytest.approx((8.02 + 0.42 + 1.69) / 3)
    assert published["max_rel"] == pytest.approx(8.02)
    assert "mean_abs" not in published  # no periods published: no errors in seconds


def test_compare_without_reference_says_so_in_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # where the default results/ directory would go
    result = invoke("compare", str(DEFAULT_CONFIG))
    assert result.exit_code == 2
    line = one_line_error(result.stderr)
    assert line.startswith("error: --reference: not given")
    assert "Liu's are not bundled" in line and "docs/experiments.md" in line
    assert list(tmp_path.iterdir()) == []


def test_compare_refuses_published_errors_as_a_reference(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    result = invoke("compare", str(DEFAULT_CONFIG), "--reference", str(CORRAL))
    assert result.exit_code == 2
    assert "holds published relative errors, not measured step periods" in one_line_error(result.stderr)
    assert list(tmp_path.iterdir()) == []


def test_compare_a_config_writes_tables_and_figure(tmp_path: Path) -> None:
    shutil.copy(CORRAL, tmp_path / "corral.yaml")
    reference = fictitious_reference(
        tmp_path, [0.40, 0.41, 0.42, 0.43], std=[0.01] * 4, published_errors=["corral.yaml"]
    )
    out = tmp_path / "cmp"
    result = invoke(
        "compare", str(DEFAULT_CONFIG), "--reference", str(reference), "--set", "simulation.t_end=2", "--out", str(out)
    )
    assert result.exit_code == 0, result.output
    assert "| step |" in result.stdout and "Corral et al. 2020 (published)" in result.stdout
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        [f"compare_{t}.{s}" for t in ("steps", "stats") for s in ("md", "csv", "tex")] + ["compare.png", "compare.svg"]
    )
    steps = pd.read_csv(out / "compare_steps.csv")
    assert list(steps["step"]) == [1, 2, 3, 4]
    model, ref = steps["model period [s]"], steps["reference period [s]"]
    assert (model > 0.3).all()
    pd.testing.assert_series_equal(steps["error (model - ref.) [s]"], model - ref, check_names=False)
    pd.testing.assert_series_equal(
        steps["relative error [%]"], (model - ref).abs() / ref * 100, check_names=False, rtol=1e-12
    )
    assert list(steps["Corral et al. 2020 error [%]"]) == [8.02, 0.42, 1.69, 2.56]
    stats = pd.read_csv(out / "compare_stats.csv")
    assert stats["mean rel. error [%]"].iloc[0] == pytest.approx(steps["relative error [%]"].mean())
    assert r"\toprule" in (out / "compare_steps.tex").read_text()


def test_compare_a_run_directory_reads_its_step_times(short_run_dir: Path, tmp_path: Path) -> None:
    reference = fictitious_reference(tmp_path, [0.40, 0.41, 0.42])
    result = invoke("compare", str(short_run_dir), "--reference", str(reference), "--out", str(tmp_path / "cmp"))
    assert result.exit_code == 0, result.output
    steps = pd.read_csv(tmp_path / "cmp" / "compare_steps.csv")
    assert list(steps["step"]) == [1, 2, 3] and "series" not in steps.columns  # one series: no series column
    times = json.loads((short_run_dir / "summary.json").read_text())["step_times"]
    np.testing.assert_allclose(steps["model period [s]"], np.diff([0.0, *times])[:3], rtol=1e-6)


def test_compare_a_sweep_directory(tiny_sweep_dir: Path, tmp_path: Path) -> None:
    """One series per run of the sweep, written below the sweep directory by default."""
    reference = fictitious_reference(tmp_path, [0.40, 0.41, 0.42])
    result = invoke("compare", str(tiny_sweep_dir), "--reference", str(reference))
    assert result.exit_code == 0, result.output
    out = tiny_sweep_dir / "compare"
    steps = pd.read_csv(out / "compare_steps.csv")
    runs = pd.read_csv(tiny_sweep_dir / "sweep.csv")
    labels = list(dict.fromkeys(steps["series"]))  # in order of first appearance
    assert len(labels) == TINY_SWEEP_RUNS == len(runs)
    assert list(steps["series"]) == [label for label in labels for _ in range(3)]
    assert labels[0].startswith("slope=0.015, ") and labels[-1].startswith("slope=0.02, ")
    assert steps["model period [s]"].between(0.3, 0.6).all()
    stats = pd.read_csv(out / "compare_stats.csv")
    assert list(stats["series"]) == labels
    assert (out / "compare.png").is_file()

    bad = invoke("compare", str(tiny_sweep_dir), "--reference", str(reference), "--set", "a.b=1")
    assert bad.exit_code == 2 and "--set: only applies when comparing a config file" in one_line_error(bad.stderr)
