"""Error tables against a reference: the arithmetic by hand, and `biped-sim compare` end to end."""

from __future__ import annotations

import math
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest
import yaml

from biped_sim.io.references import load_reference
from biped_sim.studies.compare import compare_periods, model_step_periods, stats_table, step_table
from biped_sim.sweep import load_sweep, run_sweep

from .conftest import CONFIGS, DEFAULT_CONFIG

CLI = [sys.executable, "-m", "biped_sim.cli"]
CORRAL = CONFIGS / "references" / "corral2020_liu_errors.yaml"


def fictitious_reference(tmp_path: Path, values: list[float], **extra: object) -> Path:
    """A step-period reference file with FICTITIOUS numbers (test data, not a measurement)."""
    data = {
        "experiment": "liu_round_foot_walker",
        "description": "FICTITIOUS step periods for tests; not a measurement",
        "citation": {"authors": ["A. Tester"], "title": "Test data", "year": 2024},
        "source": {"kind": "table", "label": "Table 0"},
        "quantity": {"name": "step_period", "unit": "s", "statistic": "mean", "n_trials": 3},
        "values": values,
        **extra,
    }
    path = tmp_path / "reference.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], cwd=cwd, capture_output=True, text=True, timeout=300)


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


def test_compare_without_reference_says_so_in_one_line(tmp_path: Path) -> None:
    result = run_cli("compare", str(DEFAULT_CONFIG), cwd=tmp_path)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: --reference: not given")
    assert "Liu's are not bundled" in lines[0] and "docs/experiments.md" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_compare_refuses_published_errors_as_a_reference(tmp_path: Path) -> None:
    result = run_cli("compare", str(DEFAULT_CONFIG), "--reference", str(CORRAL), cwd=tmp_path)
    assert result.returncode == 2
    assert "holds published relative errors, not measured step periods" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_compare_a_config_writes_tables_and_figure(tmp_path: Path) -> None:
    shutil.copy(CORRAL, tmp_path / "corral.yaml")
    reference = fictitious_reference(
        tmp_path, [0.40, 0.41, 0.42, 0.43], std=[0.01] * 4, published_errors=["corral.yaml"]
    )
    out = tmp_path / "cmp"
    result = run_cli(
        "compare", str(DEFAULT_CONFIG), "--reference", str(reference), "--set", "simulation.t_end=2.5",
        "--out", str(out), cwd=tmp_path,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
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


def test_compare_a_sweep_directory(tmp_path: Path) -> None:
    (tmp_path / "s.yaml").write_text(
        f"name: s\nbase: {DEFAULT_CONFIG}\nset: {{simulation.t_end: 1.3}}\ngrid:\n  ground.slope: [0.015, 0.02]\n"
    )
    with ThreadPoolExecutor(max_workers=1) as executor:
        run_sweep(load_sweep(tmp_path / "s.yaml"), tmp_path / "sweep", executor)
    reference = fictitious_reference(tmp_path, [0.40, 0.41, 0.42])
    result = run_cli("compare", str(tmp_path / "sweep"), "--reference", str(reference), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    steps = pd.read_csv(tmp_path / "sweep" / "compare" / "compare_steps.csv")
    assert list(steps["series"]) == ["slope=0.015"] * 3 + ["slope=0.02"] * 3
    stats = pd.read_csv(tmp_path / "sweep" / "compare" / "compare_stats.csv")
    assert list(stats["series"]) == ["slope=0.015", "slope=0.02"]
    assert (tmp_path / "sweep" / "compare" / "compare.png").is_file()

    bad = run_cli("compare", str(tmp_path / "sweep"), "--reference", str(reference), "--set", "a.b=1", cwd=tmp_path)
    assert bad.returncode == 2 and "--set: only applies when comparing a config file" in bad.stderr
