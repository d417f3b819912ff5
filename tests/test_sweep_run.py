"""Running sweeps: parallel workers, a failing run, resume after kill -9, the Dask executor."""

from __future__ import annotations

import json
import os
import signal
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest

from biped_sim.config import Config
from biped_sim.simulate import simulate
from biped_sim.sweep import dask_executor, load_sweep, run_sweep
from biped_sim.sweep import runner as sweep_runner
from biped_sim.sweep.rows import METRIC_COLUMNS, SETTING_COLUMNS
from biped_sim.testing import TINY_SWEEP_METHODS, TINY_SWEEP_RUNS, TINY_SWEEP_SLOPES, write_sweep

from .conftest import CLI, freezing_env, invoke, one_line_error, wait_frozen

# Columns that legitimately differ between two executions of the same run.
TIMING_COLUMNS = ["wall_time_s"]


def test_parallel_sweep_writes_every_run_and_the_table(tiny_sweep_dir: Path) -> None:
    table = pd.read_csv(tiny_sweep_dir / "sweep.csv")
    # run order (grid in file order, zip fastest), not the order in which the two workers finished
    assert list(table["ground.slope"]) == [s for s in TINY_SWEEP_SLOPES for _ in range(TINY_SWEEP_RUNS // 2)]
    assert list(table["integrator.method"]) == [m for m in TINY_SWEEP_METHODS for _ in range(2)] * 2
    assert list(table["contact.model"]) == ["flores", "hunt_crossley"] * (TINY_SWEEP_RUNS // 2)
    assert list(table["status"]) == ["walking"] * TINY_SWEEP_RUNS
    for column in ("run", "config_hash", *SETTING_COLUMNS, "step_control", *METRIC_COLUMNS):
        assert column in table.columns
    assert list(table["step_control"][:4]) == ["rtol = 1e-08, atol = 1e-10"] * 2 + ["dt = 5e-05 s"] * 2
    manifest = json.loads((tiny_sweep_dir / "sweep.json").read_text())
    assert manifest["axes"] == [
        "ground.slope",
        "integrator.method",
        "contact.model",
        "friction.model",
        "formulation.baumgarte.alpha",
        "formulation.baumgarte.beta",
    ]
    for entry, row in zip(manifest["runs"], table.itertuples(), strict=True):
        run_dir = tiny_sweep_dir / entry["dir"]
        summary = json.loads((run_dir / "summary.json").read_text())
        assert entry["name"] == row.run and run_dir.name.endswith(summary["config_hash"])
        assert summary["status"] == row.status and summary["n_steps"] == row.n_steps
        assert sorted(p.name for p in run_dir.iterdir()) == [
            "config.yaml",
            "steps.csv",
            "summary.json",
            "trajectory.h5",
        ]
    assert (table["n_steps"] == 3).all() and (table["mean_period_s"] > 0.3).all()
    assert (table["rhs_evals"] > table["accepted_steps"]).all()


def test_failing_run_is_recorded_and_the_sweep_goes_on(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A run whose simulation raises gets status 'error' and error.json; the others finish (one falls, a finished
    run too); resume retries the failed one only."""

    def flaky(config: Config) -> object:
        if config.ground.slope == 0.015:
            raise RuntimeError("solver exploded\nsecond line")
        return simulate(config)

    path = write_sweep(tmp_path, "flaky", set_={"simulation.t_end": 0.6}, grid={"ground.slope": [0.01, 0.015, 0.2]})
    sweep = load_sweep(path)
    out = tmp_path / "out"
    monkeypatch.setattr(sweep_runner, "simulate", flaky)
    seen: list[str | None] = []
    with ThreadPoolExecutor(max_workers=1) as executor:
        outcome = run_sweep(sweep, out, executor, on_progress=lambda progress, name, row: seen.append(name))
    assert [row["status"] for row in outcome.rows] == ["walking", "error", "fell"]
    assert outcome.rows[1]["error"] == "RuntimeError: solver exploded"
    assert 0 < outcome.rows[2]["stop_time_s"] < 0.6  # the steep slope: a fall is a finished run, with its time
    assert outcome.errors == 1 and outcome.progress.failed == 1
    assert seen[0] is None and sorted(n for n in seen[1:] if n) == sorted(r.name for r in sweep.runs)
    bad_dir = out / "runs" / sweep.runs[1].name
    assert not (bad_dir / "summary.json").exists()
    assert json.loads((bad_dir / "error.json").read_text())["error"] == "RuntimeError: solver exploded"
    table = pd.read_csv(out / "sweep.csv", keep_default_na=False)
    assert list(table["status"]) == ["walking", "error", "fell"]

    monkeypatch.setattr(sweep_runner, "simulate", simulate)
    with ThreadPoolExecutor(max_workers=1) as executor:
        again = run_sweep(sweep, out, executor)
    assert again.progress.skipped == 2 and again.progress.done == 1
    assert [row["status"] for row in again.rows] == ["walking", "walking", "fell"]
    assert not (bad_dir / "error.json").exists()


def test_no_resume_runs_everything_again(tmp_path: Path) -> None:
    sweep = load_sweep(write_sweep(tmp_path, "again", set_={"simulation.t_end": 0.5}, grid={"ground.slope": [0.01]}))
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
    """kill -9 the whole sweep (a real process group) at a known point: the sweep frozen while writing its table
    after the first run, its worker while finishing the second; the restart reruns exactly the unfinished runs and
    leaves no temporary file of the killed sweep."""
    n_runs = 4
    path = write_sweep(
        tmp_path,
        "killed",
        set_={"simulation.t_end": 0.5},
        grid={"ground.slope": {"from": 0.010, "to": 0.020, "num": n_runs}},
    )
    out, markers = tmp_path / "out", tmp_path / "markers"
    process = subprocess.Popen(
        [*CLI, "sweep", str(path), "--jobs", "1", "--out", str(out), "-q"],
        cwd=tmp_path,
        env=freezing_env(markers, "sweep.csv@2", "summary.json@2"),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # its own process group: the kill takes the workers too
    )
    wait_frozen(process, markers, "sweep.csv", "summary.json")
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    manifest = json.loads((out / "sweep.json").read_text())
    first, second, third = (out / run["dir"] for run in manifest["runs"][:3])
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    assert list(finished) == [first.name]
    # what the kill left: the table's temporary file, the second run's files but its summary (written, not renamed)
    assert len(list(out.glob(".sweep.csv.*.tmp"))) == 1
    assert sorted(p.name for p in second.iterdir() if not p.name.startswith(".")) == [
        "config.yaml",
        "steps.csv",
        "trajectory.h5",
    ]
    assert len(list(second.glob(".summary.json.*.tmp"))) == 1
    assert set(pd.read_csv(out / "sweep.csv")["status"]) == {"pending"}  # the table as before the first run's row
    third.mkdir(parents=True)  # and what a kill in the middle of a write leaves: a torn HDF5 file
    (third / "trajectory.h5").write_bytes(b"\x89HDF\r\n\x1a\n truncated")

    with ThreadPoolExecutor(max_workers=1) as executor:  # the restart needs no process of its own
        outcome = run_sweep(load_sweep(path), out, executor)
    assert (outcome.progress.skipped, outcome.progress.done) == (1, n_runs - 1)
    assert (first / "summary.json").stat().st_mtime_ns == finished[first.name], "the finished run was run again"
    table = pd.read_csv(out / "sweep.csv")
    assert list(table["status"]) == ["walking"] * n_runs
    for run in manifest["runs"]:
        assert json.loads((out / run["dir"] / "summary.json").read_text())["config_hash"] == run["config_hash"]
    assert not list(out.rglob("*.tmp"))


@pytest.mark.slow  # a LocalCluster takes about 4 s to start and stop
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_dask_local_cluster_gives_the_same_results_as_local_processes(tiny_sweep_dir: Path, tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    sweep = load_sweep(tiny_sweep_dir.parent / "tiny.yaml")
    with dask_executor(jobs=2, scheduler=None) as executor:
        outcome = run_sweep(sweep, tmp_path / "dask", executor)
    assert outcome.progress.done == TINY_SWEEP_RUNS
    local = pd.read_csv(tiny_sweep_dir / "sweep.csv").drop(columns=TIMING_COLUMNS)
    dask = pd.read_csv(tmp_path / "dask" / "sweep.csv").drop(columns=TIMING_COLUMNS)
    pd.testing.assert_frame_equal(local, dask)
    for run in sweep.runs:
        a = json.loads((tiny_sweep_dir / "runs" / run.name / "summary.json").read_text())
        b = json.loads((tmp_path / "dask" / "runs" / run.name / "summary.json").read_text())
        assert a["step_times"] == b["step_times"] and a["rhs_evals"] == b["rhs_evals"]


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["sweep", "missing.yaml"], "missing.yaml: no such sweep file"),
        (["sweep", "ok.yaml", "--jobs", "0"], "--jobs: must be at least 1"),
        (["sweep", "ok.yaml", "--executor", "mpi"], "--executor: unknown executor 'mpi'"),
        (["sweep", "ok.yaml", "--scheduler", "tcp://localhost:1"], "--scheduler: only used with the dask executor"),
        (["sweep", "ok.yaml", "--set", "ground.slope=0.01"], "--set: ground.slope is a sweep axis"),
        (["sweep", "ok.yaml", "--set", "walker.hip_mass=-1"], "walker.hip_mass"),
        (["sweep", "bad.yaml"], "run 2 (slope=0.9): ground.slope"),
    ],
)
def test_bad_sweep_input_is_one_line_exit_2_and_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, args: list[str], expected: str
) -> None:
    base = write_sweep(tmp_path, "ok", grid={"ground.slope": [0.01]}).with_name("ok_base.yaml")
    write_sweep(tmp_path, "bad", base=base, grid={"ground.slope": [0.01, 0.9]})
    monkeypatch.chdir(tmp_path)  # the sweep files are named relative to here
    before = sorted(tmp_path.iterdir())
    result = invoke(*args, "--out", str(tmp_path / "out"))
    assert result.exit_code == 2, result.output
    assert expected in one_line_error(result.stderr)
    assert sorted(tmp_path.iterdir()) == before


def test_study_executor_is_serial_for_one_local_job_and_a_pool_otherwise() -> None:
    from biped_sim.sweep import study_executor

    with study_executor("local", 1) as serial:
        assert serial is None
    with study_executor("local", 2) as pool:
        assert pool is not None and pool.submit(abs, -3).result() == 3
