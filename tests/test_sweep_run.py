"""Running sweeps: parallel workers, a failing run, resume after kill -9, the Dask executor."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest

from biped_sim.config import Config
from biped_sim.simulate import simulate
from biped_sim.sweep import load_sweep, run_sweep
from biped_sim.sweep import runner as sweep_runner
from biped_sim.sweep.rows import METRIC_COLUMNS, SETTING_COLUMNS

from .conftest import DEFAULT_CONFIG

CLI = [sys.executable, "-m", "biped_sim.cli"]
# Columns that legitimately differ between two executions of the same run.
TIMING_COLUMNS = ["wall_time_s"]


def write_sweep(tmp_path: Path, name: str, body: str) -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(f"name: {name}\nbase: {DEFAULT_CONFIG}\n{body}")
    return path


PARALLEL_SWEEP = """
set:
  simulation.t_end: 1.0
zip:
  integrator.method: [dopri5, rk4, euler]
  integrator.dt: [1.0e-4, 1.0e-4, 5.0e-3]   # euler at 5 ms is unstable: the integration diverges
"""


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], cwd=cwd, capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The 3-run sweep on 2 local worker processes, through the CLI (not a terminal: one line per run)."""
    root = tmp_path_factory.mktemp("local")
    path = write_sweep(root, "parallel", PARALLEL_SWEEP)
    result = run_cli("sweep", str(path), "--jobs", "2", "--out", str(root / "out"), cwd=root)
    assert result.returncode == 0, result.stderr
    assert "3 runs: 0 already finished, 3 to run" in result.stdout
    assert result.stdout.count("[") >= 3  # one progress line per run
    return root / "out"


def test_parallel_sweep_writes_every_run_and_the_table(local_sweep: Path) -> None:
    table = pd.read_csv(local_sweep / "sweep.csv")
    assert list(table["integrator.method"]) == ["dopri5", "rk4", "euler"]  # run order, not completion order
    assert list(table["status"]) == ["walking", "walking", "diverged"]
    for column in ("run", "config_hash", "integrator.dt", *SETTING_COLUMNS, "step_control", *METRIC_COLUMNS):
        assert column in table.columns
    assert list(table["step_control"]) == ["rtol = 1e-08, atol = 1e-10", "dt = 1e-04 s", "dt = 5e-03 s"]
    manifest = json.loads((local_sweep / "sweep.json").read_text())
    assert manifest["axes"] == ["integrator.method", "integrator.dt"]
    for entry, row in zip(manifest["runs"], table.itertuples(), strict=True):
        run_dir = local_sweep / entry["dir"]
        summary = json.loads((run_dir / "summary.json").read_text())
        assert entry["name"] == row.run and run_dir.name.endswith(summary["config_hash"])
        assert summary["status"] == row.status and summary["n_steps"] == row.n_steps
        assert sorted(p.name for p in run_dir.iterdir()) == [
            "config.yaml",
            "steps.csv",
            "summary.json",
            "trajectory.h5",
        ]
    walking = table[table["status"] == "walking"]
    assert (walking["n_steps"] >= 2).all() and (walking["mean_period_s"] > 0.3).all()
    assert (walking["rhs_evals"] > walking["accepted_steps"]).all()
    diverged = table[table["status"] == "diverged"].iloc[0]
    assert diverged["stop_time_s"] < 1.0


def test_failing_run_is_recorded_and_the_sweep_goes_on(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A run whose simulation raises gets status 'error' and error.json; the others finish; resume retries it."""

    def flaky(config: Config) -> object:
        if config.ground.slope == 0.015:
            raise RuntimeError("solver exploded\nsecond line")
        return simulate(config)

    sweep = load_sweep(
        write_sweep(tmp_path, "flaky", "set: {simulation.t_end: 0.6}\ngrid:\n  ground.slope: [0.01, 0.015, 0.02]\n")
    )
    out = tmp_path / "out"
    monkeypatch.setattr(sweep_runner, "simulate", flaky)
    seen: list[str | None] = []
    with ThreadPoolExecutor(max_workers=1) as executor:
        outcome = run_sweep(sweep, out, executor, on_progress=lambda progress, name, row: seen.append(name))
    assert [row["status"] for row in outcome.rows] == ["walking", "error", "walking"]
    assert outcome.rows[1]["error"] == "RuntimeError: solver exploded"
    assert outcome.errors == 1 and outcome.progress.failed == 1
    assert seen[0] is None and sorted(n for n in seen[1:] if n) == sorted(r.name for r in sweep.runs)
    bad_dir = out / "runs" / sweep.runs[1].name
    assert not (bad_dir / "summary.json").exists()
    assert json.loads((bad_dir / "error.json").read_text())["error"] == "RuntimeError: solver exploded"
    table = pd.read_csv(out / "sweep.csv", keep_default_na=False)
    assert list(table["status"]) == ["walking", "error", "walking"]

    monkeypatch.setattr(sweep_runner, "simulate", simulate)
    with ThreadPoolExecutor(max_workers=1) as executor:
        again = run_sweep(sweep, out, executor)
    assert again.progress.skipped == 2 and again.progress.done == 1
    assert [row["status"] for row in again.rows] == ["walking"] * 3
    assert not (bad_dir / "error.json").exists()


def test_no_resume_runs_everything_again(tmp_path: Path) -> None:
    sweep = load_sweep(write_sweep(tmp_path, "again", "set: {simulation.t_end: 0.5}\ngrid:\n  ground.slope: [0.01]\n"))
    out = tmp_path / "out"
    with ThreadPoolExecutor(max_workers=1) as executor:
        first = run_sweep(sweep, out, executor)
        skipped = run_sweep(sweep, out, executor)
        rerun = run_sweep(sweep, out, executor, resume=False)
    assert (first.progress.done, skipped.progress.skipped, skipped.progress.done) == (1, 1, 0)
    assert (rerun.progress.done, rerun.progress.skipped) == (1, 0)
    assert first.rows[0]["n_steps"] == rerun.rows[0]["n_steps"]


def test_summary_of_another_config_is_not_a_finished_run(tmp_path: Path) -> None:
    (tmp_path / "summary.json").write_text(json.dumps({"config_hash": "abc", "status": "walking"}))
    assert sweep_runner.finished_summary(tmp_path, "abc") is not None
    assert sweep_runner.finished_summary(tmp_path, "def") is None
    (tmp_path / "summary.json").write_text('{"config_hash": "ab')  # torn file
    assert sweep_runner.finished_summary(tmp_path, "abc") is None


def test_resume_after_kill_skips_finished_runs_and_ignores_partial_files(tmp_path: Path) -> None:
    """kill -9 the whole sweep mid-way; the restart reruns exactly the unfinished runs."""
    n_runs = 6
    path = write_sweep(
        tmp_path,
        "killed",
        "set: {simulation.t_end: 2.0}\ngrid:\n  ground.slope: {from: 0.010, to: 0.020, num: 6}\n",
    )
    out = tmp_path / "out"
    process = subprocess.Popen(
        [*CLI, "sweep", str(path), "--jobs", "1", "--out", str(out), "-q"],
        cwd=tmp_path,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own process group: the kill takes the workers too
    )
    deadline = time.monotonic() + 180
    while not list(out.glob("runs/*/summary.json")):
        assert process.poll() is None, process.stderr.read().decode() if process.stderr else ""
        assert time.monotonic() < deadline
        time.sleep(0.02)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    if process.stderr:
        process.stderr.close()
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    assert 0 < len(finished) < n_runs, "the kill came too late to test anything"

    # what a kill can leave in an unfinished run: a torn HDF5 file and a temp file, but no summary.json
    manifest = json.loads((out / "sweep.json").read_text())
    unfinished = next(run for run in manifest["runs"] if run["name"] not in finished)
    torn = out / "runs" / unfinished["name"]
    torn.mkdir(parents=True, exist_ok=True)
    (torn / "trajectory.h5").write_bytes(b"\x89HDF\r\n\x1a\n truncated")
    (torn / ".summary.json.x1y2.tmp").write_text('{"status": "walk')
    table = pd.read_csv(out / "sweep.csv")
    assert set(table.loc[~table["run"].isin(finished), "status"]) <= {"pending"}

    result = run_cli("sweep", str(path), "--jobs", "1", "--out", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert f"{n_runs} runs: {len(finished)} already finished, {n_runs - len(finished)} to run" in result.stdout
    for name, mtime in finished.items():
        assert (out / "runs" / name / "summary.json").stat().st_mtime_ns == mtime, f"{name} was run again"
    table = pd.read_csv(out / "sweep.csv")
    assert list(table["status"]) == ["walking"] * n_runs
    summary = json.loads((torn / "summary.json").read_text())
    assert summary["config_hash"] == unfinished["config_hash"]
    assert not list(out.rglob("*.tmp"))


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_dask_local_cluster_gives_the_same_results_as_local_processes(local_sweep: Path, tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    sweep = load_sweep(write_sweep(tmp_path, "parallel", PARALLEL_SWEEP))
    with sweep_runner.dask_executor(jobs=2, scheduler=None) as executor:
        outcome = run_sweep(sweep, tmp_path / "dask", executor)
    assert outcome.progress.done == 3
    local = pd.read_csv(local_sweep / "sweep.csv").drop(columns=TIMING_COLUMNS)
    dask = pd.read_csv(tmp_path / "dask" / "sweep.csv").drop(columns=TIMING_COLUMNS)
    pd.testing.assert_frame_equal(local, dask)
    for run in sweep.runs:
        a = json.loads((local_sweep / "runs" / run.name / "summary.json").read_text())
        b = json.loads((tmp_path / "dask" / "runs" / run.name / "summary.json").read_text())
        assert a["step_times"] == b["step_times"] and a["rhs_evals"] == b["rhs_evals"]


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["sweep", "missing.yaml"], "missing.yaml: no such sweep file"),
        (["sweep", "ok.yaml", "--jobs", "0"], "--jobs: must be at least 1"),
        (["sweep", "ok.yaml", "--executor", "mpi"], "--executor: unknown executor 'mpi'"),
        (["sweep", "ok.yaml", "--scheduler", "tcp://localhost:1"], "--scheduler: only used with --executor dask"),
        (["sweep", "ok.yaml", "--set", "ground.slope=0.01"], "--set: ground.slope is a sweep axis"),
        (["sweep", "ok.yaml", "--set", "walker.hip_mass=-1"], "walker.hip_mass"),
        (["sweep", "bad.yaml"], "run 2 (slope=0.9): ground.slope"),
    ],
)
def test_bad_sweep_input_is_one_line_exit_2_and_writes_nothing(tmp_path: Path, args: list[str], expected: str) -> None:
    write_sweep(tmp_path, "ok", "grid:\n  ground.slope: [0.01]\n")
    write_sweep(tmp_path, "bad", "grid:\n  ground.slope: [0.01, 0.9]\n")
    result = run_cli(*args, "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], result.stderr
    assert not (tmp_path / "out").exists()
