"""`biped-sim run` end to end: bad input gives one line and exit 2; a run writes its files atomically."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from .conftest import DEFAULT_CONFIG, child_env, invoke, one_line_error, run_cli


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["run", "missing.yaml"], "missing.yaml: no such config file"),
        (["run", "bad.yaml"], "malformed YAML"),
        (["run", "default.yaml", "--set", "walker.leg_masss=1"], "walker.leg_masss: unknown key"),
        (["run", "default.yaml", "--set", "contact.model=flores2"], "contact.model: unknown name"),
        (["run", "default.yaml", "--set", "walker.hip_mass=-2"], "walker.hip_mass: Input should be greater than"),
        (["run", "default.yaml", "--set", "walker.foot_radius=-0.1"], "walker.foot_radius"),
        (["run", "default.yaml", "--set", "walker.foot_radius=0.7"], "smaller than walker.leg_length"),
        (["run", "default.yaml", "--set", "integrator.dt=0"], "integrator.dt: Input should be greater than 0"),
        (["run", "default.yaml", "--set", "ground.slope=1.2"], "ground.slope"),
        (["run", "default.yaml", "--set", "simulation.initial.stance_angle=1.5"], "simulation.initial.stance_angle"),
        (["run", "default.yaml", "--set", "novalue"], "--set: expected KEY=VALUE"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, args: list[str], expected: str
) -> None:
    (tmp_path / "default.yaml").write_text(DEFAULT_CONFIG.read_text())
    (tmp_path / "bad.yaml").write_text("walker: {leg_length: 0.5\n")
    monkeypatch.chdir(tmp_path)  # relative paths, and the default results/ directory, are here
    out = tmp_path / "out"
    result = invoke(*args, "--out", str(out))
    assert result.exit_code == 2, result.output
    assert expected in one_line_error(result.stderr)
    assert not out.exists()
    assert not (tmp_path / "results").exists()


def test_console_entry_point_reports_bad_input_in_one_line_with_exit_2(tmp_path: Path) -> None:
    """The real process: exit status 2 and one stderr line, no traceback (the in-process tests cannot see these)."""
    result = run_cli("run", "missing.yaml", "--set", "ground.slope=0.01", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert one_line_error(result.stderr) == "error: missing.yaml: no such config file"
    assert result.stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_run_writes_trajectory_summary_and_steps(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = invoke("run", str(DEFAULT_CONFIG), "--set", "simulation.t_end=2", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "walking" in result.stdout and str(out) in result.stdout
    assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "steps.csv", "summary.json", "trajectory.h5"]
    summary = json.loads((out / "summary.json").read_text())
    for key in (
        "status", "t_end", "n_steps", "step_times", "step_periods", "step_lengths", "mean_speed", "slip_per_step",
        "energy_residual_max", "constraint_violation_max", "rhs_evals", "wall_time_s", "config_hash", "version",
    ):  # fmt: skip
        assert key in summary
    assert summary["n_steps"] >= 3
    csv_rows = (out / "steps.csv").read_text().splitlines()
    assert len(csv_rows) == summary["n_steps"] + 1
    with h5py.File(out / "trajectory.h5") as f:
        assert f.attrs["config_hash"] == summary["config_hash"]
        assert "walker:" in f.attrs["config"]
        assert f.attrs["git_commit"]
        assert f["time"].attrs["units"] == "s"
        assert f["contact/normal_force"].shape == (len(f["time"]), 2)
        assert f["contact/normal_force"].attrs["units"] == "N"
        for name in ("kinetic", "potential", "elastic", "dissipated_normal", "dissipated_friction", "residual"):
            assert f[f"energy/{name}"].shape == f["time"].shape
        np.testing.assert_array_equal(f["steps/strike_time"][:], summary["step_times"])
        assert list(f["state_names"].asstr()[:4]) == ["x_leg0", "y_leg0", "phi_leg0", "x_leg1"]
    assert not list(out.glob(".*tmp"))


# what a command's start-up does not import (each costs 0.1-0.3 s of every command; imported where used)
DEFERRED_MODULES = ("pandas", "matplotlib", "scipy.integrate", "scipy.optimize", "scipy.spatial", "scipy.stats")


def test_the_command_line_starts_without_the_libraries_a_run_does_not_need() -> None:
    probe = f"import sys, biped_sim.cli; print(*[m for m in {DEFERRED_MODULES!r} if m in sys.modules])"
    result = subprocess.run([sys.executable, "-c", probe], env=child_env(), capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == []
