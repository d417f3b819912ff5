"""Studies that survive failure: imperfect sweeps report, damaged runs run again, a dead worker fails only its
own run, a sweep locks its directory, Ctrl-C leaves a consistent sweep, output locations are checked first.

Fast tests drive the CLI in-process (typer's CliRunner) and the sweep on a thread pool with faults injected;
the ones that start worker processes and kill them, or draw a whole report, are marked slow.
"""

from __future__ import annotations

import errno
import io
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import Result
from typer.testing import CliRunner

from biped_sim.cli.common import app
from biped_sim.config import Config
from biped_sim.io import output as output_module
from biped_sim.io.atomic import write_text_atomic
from biped_sim.io.run_files import TrajectoryFile, write_run_directory
from biped_sim.io.tables import Column, Table
from biped_sim.report import SweepView
from biped_sim.report.tables import tables_for
from biped_sim.simulate import simulate
from biped_sim.sweep import load_sweep, run_sweep
from biped_sim.sweep import runner as sweep_runner
from biped_sim.sweep.lock import sweep_lock
from biped_sim.sweep.pool import WorkerDiedError, WorkerPool
from biped_sim.sweep.spec import run_stem

from .conftest import DEFAULT_CONFIG, MEMORY_BOUND, allocation_peak, freezing_env, wait_frozen
from .test_compare import fictitious_reference

CLI = [sys.executable, "-m", "biped_sim.cli"]

# walking, diverged (rk4 at 3 ms), fell (steep slope), error, and two runs an interrupt leaves pending
IMPERFECT = f"""name: imperfect
base: {DEFAULT_CONFIG}
set: {{simulation.t_end: 1.0}}
zip:
  integrator.method: [dopri5, rk4, dopri5, dopri5, dopri5, dopri5]
  integrator.dt: [1.0e-4, 3.0e-3, 1.0e-4, 1.0e-4, 1.0e-4, 1.0e-4]
  ground.slope: [0.02, 0.02, 0.06, 0.015, 0.018, 0.019]
"""
STATUSES = ["walking", "diverged", "fell", "error", "pending", "pending"]
SIX_RUNS = f"""name: six
base: {DEFAULT_CONFIG}
set: {{simulation.t_end: 12.0}}
grid:
  ground.slope: {{from: 0.010, to: 0.020, num: 6}}
"""


def faulty_simulate(config: Config) -> object:
    """The sweep's simulate with faults injected: slope 0.015 raises, 0.018 and up are interrupted (Ctrl-C: the thread
    pool may start the last run before the interrupt reaches the sweep). The rk4 run at 3 ms blows up by itself."""
    if config.ground.slope == 0.015:
        raise RuntimeError("injected failure")
    if config.ground.slope in (0.018, 0.019):
        raise KeyboardInterrupt
    return simulate(config)


def invoke(*args: str | Path) -> Result:
    return CliRunner().invoke(app, [str(arg) for arg in args])


def assert_one_line(result: Result, code: int, expected: str) -> None:
    """Exit ``code`` and exactly one line on stderr, 'error: ...' containing ``expected``; never a traceback."""
    assert result.exit_code == code, (result.exit_code, result.stderr, result.exception)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], result.stderr


def leftovers(directory: Path) -> list[str]:
    """Temporary entries (files or staged directories) anywhere below ``directory``."""
    return [str(path) for path in directory.rglob(".*.tmp")]


@pytest.fixture(scope="module")
def imperfect_sweep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The six runs on one thread, interrupted at the fifth: a sweep directory with every kind of row."""
    root = tmp_path_factory.mktemp("imperfect")
    (root / "imperfect.yaml").write_text(IMPERFECT)
    sweep = load_sweep(root / "imperfect.yaml")
    with pytest.MonkeyPatch.context() as patch, ThreadPoolExecutor(max_workers=1) as executor:
        patch.setattr(sweep_runner, "simulate", faulty_simulate)
        with pytest.raises(KeyboardInterrupt):
            run_sweep(sweep, root / "sweep", executor)
    return root / "sweep"


@pytest.fixture
def sweep_copy(imperfect_sweep: Path, tmp_path: Path) -> Path:
    """A copy of the imperfect sweep that a test may damage."""
    return Path(shutil.copytree(imperfect_sweep, tmp_path / "sweep"))


def run_dir_of(sweep_dir: Path, status: str) -> Path:
    table = pd.read_csv(sweep_dir / "sweep.csv")
    return sweep_dir / "runs" / table.loc[table["status"] == status, "run"].iloc[0]


# 1. report, compare and plot on imperfect sweeps; nothing partial


def test_interrupted_sweep_table_matches_its_run_directories(imperfect_sweep: Path) -> None:
    table = pd.read_csv(imperfect_sweep / "sweep.csv", keep_default_na=False)
    assert list(table["status"]) == STATUSES
    assert table.loc[3, "error"] == "RuntimeError: injected failure"
    for name, status in zip(table["run"], table["status"], strict=True):
        run_dir = imperfect_sweep / "runs" / name
        assert (run_dir / "summary.json").is_file() == (status in ("walking", "diverged", "fell"))
        assert (run_dir / "error.json").is_file() == (status == "error")  # the interrupted run left no record


def test_report_tables_carry_every_status_and_leave_absent_metrics_empty(imperfect_sweep: Path) -> None:
    tables = {table.name: table for table in tables_for(SweepView.load(imperfect_sweep))}
    assert set(tables) == {"runs", "by_integrator"}
    runs = tables["runs"]
    markdown = runs.markdown()
    for status in set(STATUSES):
        assert f"| {status} |" in markdown
    rows = pd.read_csv(io.StringIO(runs.csv()), keep_default_na=False)
    assert list(rows["status"]) == STATUSES
    assert (rows.loc[3:, ["steps", "mean period [s]", "wall time [s]"]] == "").all().all()
    assert rows.loc[0, "steps"] == "2"  # an integer column with gaps still shows integers
    assert "| pending | – | – |" in markdown and r"pending & -- & --" in runs.latex()


def test_integer_format_accepts_the_floats_of_a_column_with_gaps() -> None:
    table = Table("t", "T", [Column("n", "steps", "", "d")], [{"n": 34.0}, {"n": float("nan")}, {"n": 2.5}])
    assert [cells[0] for cells in table.cells()] == ["34", "–", "2.5"]


def test_report_on_an_imperfect_sweep_exits_0_and_says_what_is_missing(sweep_copy: Path) -> None:
    result = invoke("report", sweep_copy)
    assert result.exit_code == 0, result.stderr
    assert "note: 3 of 6 runs have no results and are not drawn (1 error, 2 pending)" in result.stdout
    report = sweep_copy / "report"
    runs = pd.read_csv(report / "tables" / "runs.csv", keep_default_na=False)
    assert list(runs["status"]) == STATUSES
    assert "*3 of 6 runs have no results and are not drawn (1 error, 2 pending).*" in (report / "report.md").read_text()
    assert (report / "figures" / "constraint_violation.svg").is_file()
    assert leftovers(sweep_copy) == []


def test_compare_on_an_imperfect_sweep_compares_the_runs_with_results(sweep_copy: Path, tmp_path: Path) -> None:
    reference = fictitious_reference(tmp_path, [0.40, 0.40])
    result = invoke("compare", sweep_copy, "--reference", reference)
    assert result.exit_code == 0, result.stderr
    assert "note: 3 of 6 runs have no results and are not compared (1 error, 2 pending)" in result.stdout
    steps = pd.read_csv(sweep_copy / "compare" / "compare_steps.csv")
    assert len(steps) == 2 * 3  # two reference steps for each of the three runs with results


def test_plot_on_a_diverged_run_draws_what_exists(sweep_copy: Path) -> None:
    run_dir = run_dir_of(sweep_copy, "diverged")
    result = invoke("plot", run_dir)
    assert result.exit_code == 0, result.stderr
    assert "note: the run diverged at t = " in result.stdout
    drawn = {path.stem for path in (run_dir / "figures").glob("*.png")}
    assert len(drawn) == 7 and "walker" in drawn  # every single-run figure, the walker's poses among them


def test_report_failing_on_a_missing_trajectory_leaves_the_old_report(sweep_copy: Path) -> None:
    old = sweep_copy / "report"
    (old / "figures").mkdir(parents=True)
    (old / "report.md").write_text("old report\n")
    (old / "figures" / "gone.png").write_bytes(b"old figure")
    (run_dir_of(sweep_copy, "walking") / "trajectory.h5").unlink()
    result = invoke("report", sweep_copy)
    assert_one_line(result, 2, "no trajectory.h5 in the run directory")
    assert (old / "report.md").read_text() == "old report\n"
    assert sorted(p.name for p in old.rglob("*")) == ["figures", "gone.png", "report.md"]
    assert leftovers(sweep_copy) == []


def test_plot_failing_to_write_leaves_the_old_figures(sweep_copy: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """No space left on the second figure: one line, exit 1 (the input was fine), the old figures untouched."""
    run_dir = run_dir_of(sweep_copy, "fell")
    figures = run_dir / "figures"
    figures.mkdir()
    (figures / "step_period.png").write_bytes(b"old")
    writes: list[Path] = []

    def full_disk(target: Path, writer: object) -> None:
        writes.append(target)
        if len(writes) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(target))
        Path(target).write_bytes(b"new")

    monkeypatch.setattr("biped_sim.plots.write_with", full_disk)
    result = invoke("plot", run_dir)
    assert_one_line(result, 1, f"{figures}: No space left on device")
    assert [p.name for p in figures.iterdir()] == ["step_period.png"]
    assert (figures / "step_period.png").read_bytes() == b"old"
    assert leftovers(run_dir) == []


# 2. a damaged finished run is run again on resume


def test_verified_summary_names_what_is_damaged(imperfect_sweep: Path, tmp_path: Path) -> None:
    run_dir = Path(shutil.copytree(run_dir_of(imperfect_sweep, "walking"), tmp_path / "run"))
    config_hash = json.loads((run_dir / "summary.json").read_text())["config_hash"]
    summary, problem = sweep_runner.verified_summary(run_dir, config_hash)
    assert summary is not None and problem is None
    assert sweep_runner.verified_summary(run_dir, "0" * 16) == (None, "summary.json unreadable or of another config")
    data = (run_dir / "trajectory.h5").read_bytes()
    (run_dir / "trajectory.h5").write_bytes(data[: len(data) // 2])
    summary, problem = sweep_runner.verified_summary(run_dir, config_hash)
    assert summary is None and problem is not None and problem.startswith("trajectory.h5 unreadable")
    (run_dir / "trajectory.h5").unlink()
    assert sweep_runner.verified_summary(run_dir, config_hash) == (None, "trajectory.h5 missing")
    (run_dir / "summary.json").unlink()
    assert sweep_runner.verified_summary(run_dir, config_hash) == (None, None)  # never finished: not damaged


def test_resume_runs_again_only_the_damaged_runs(tmp_path: Path) -> None:
    (tmp_path / "s.yaml").write_text(
        f"name: s\nbase: {DEFAULT_CONFIG}\nset: {{simulation.t_end: 0.4}}\ngrid:\n  ground.slope: [0.01, 0.015, 0.02]\n"
    )
    sweep = load_sweep(tmp_path / "s.yaml")
    out = tmp_path / "out"
    with ThreadPoolExecutor(max_workers=1) as executor:
        run_sweep(sweep, out, executor)
    first, second, third = (out / "runs" / run.name for run in sweep.runs)
    (first / "trajectory.h5").unlink()
    (second / "summary.json").write_text('{"status": "walk')
    untouched = (third / "summary.json").stat().st_mtime_ns
    with ThreadPoolExecutor(max_workers=1) as executor:
        outcome = run_sweep(sweep, out, executor)
    assert outcome.progress.damaged == {
        first.name: "trajectory.h5 missing",
        second.name: "summary.json unreadable or of another config",
    }
    assert (outcome.progress.skipped, outcome.progress.done) == (1, 2)
    assert (third / "summary.json").stat().st_mtime_ns == untouched
    assert [row["status"] for row in outcome.rows] == ["walking"] * 3


# 3. a dead worker fails only its own task


def test_a_dead_worker_fails_only_its_own_task() -> None:
    with WorkerPool(2) as pool:
        killed = pool.submit(signal.raise_signal, signal.SIGKILL)
        others = [pool.submit(pow, 2, k) for k in range(4)]
        assert [future.result(timeout=60) for future in others] == [1, 2, 4, 8]
        with pytest.raises(WorkerDiedError, match=r"^worker died \(signal 9\)$"):
            killed.result(timeout=60)
        assert pool.submit(pow, 3, 2).result(timeout=60) == 9  # a new worker took the dead one's place


# 4. writing a run removes the old completion marker first


def test_writing_a_run_removes_the_old_summary_first_and_stale_temporaries(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run_dir = tmp_path / "run"
    (run_dir / ".staged.ab12.tmp").mkdir(parents=True)
    (run_dir / ".summary.json.cd34.tmp").write_text('{"status": "walk')
    (run_dir / "summary.json").write_text('{"status": "walking"}')
    trajectory = TrajectoryFile(np.arange(3.0), "s", np.zeros((3, 2)), ["a", "b"], "m", [])
    files = {"config_yaml": "a: 1\n", "config_hash": "0123", "status": "walking", "steps_csv": "step\n"}

    def no_space(target: Path, text: str) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(target))

    monkeypatch.setattr("biped_sim.io.run_files.write_text_atomic", no_space)
    with pytest.raises(OSError, match="No space left"):
        write_run_directory(run_dir, trajectory, summary={"status": "walking"}, **files)
    assert sorted(p.name for p in run_dir.iterdir()) == ["trajectory.h5"]  # no old summary beside new data
    monkeypatch.undo()
    write_run_directory(run_dir, trajectory, summary={"status": "fell"}, **files)
    assert json.loads((run_dir / "summary.json").read_text()) == {"status": "fell"}


# 5. one sweep at a time per directory


def test_a_second_sweep_into_a_locked_directory_says_who_holds_it(tmp_path: Path) -> None:
    (tmp_path / "s.yaml").write_text(f"name: s\nbase: {DEFAULT_CONFIG}\ngrid:\n  ground.slope: [0.01]\n")
    out = tmp_path / "out"
    out.mkdir()
    with sweep_lock(out):
        result = invoke("sweep", tmp_path / "s.yaml", "--out", out)
    assert_one_line(
        result, 2, f"another sweep is writing this directory (pid {os.getpid()} on host {socket.gethostname()})"
    )
    assert sorted(p.name for p in out.iterdir()) == [".sweep.lock"]


def test_taking_the_lock_clears_what_dead_writers_left_of_the_sweeps_own_files_only(tmp_path: Path) -> None:
    (tmp_path / ".sweep.csv.ab12.tmp").write_text("run,status\n")  # a sweep killed while writing its table
    (tmp_path / ".report.cd34.tmp").mkdir()  # a report being staged by another command, alive
    with sweep_lock(tmp_path, owned=("sweep.csv", "sweep.json")):
        assert sorted(p.name for p in tmp_path.iterdir()) == [".report.cd34.tmp", ".sweep.lock"]


# 7. limits, names, permissions


@pytest.mark.parametrize(
    ("axes", "expected"),
    [
        ("grid:\n  ground.slope: {from: 0.01, to: 0.02, num: 1e8}\n", "expands to 100,000,000 runs"),
        ("grid:\n  ground.slope: {from: 0.01, to: 0.02, num: 1001}\n  gravity: {from: 9, to: 10, num: 1000}\n",
         "expands to 1,001,000 runs, more than the limit of 1,000,000"),
    ],
)  # fmt: skip
def test_a_sweep_beyond_the_run_limit_is_refused_before_expanding(tmp_path: Path, axes: str, expected: str) -> None:
    (tmp_path / "big.yaml").write_text(f"name: big\nbase: {DEFAULT_CONFIG}\n{axes}")
    result, peak = allocation_peak(lambda: invoke("sweep", tmp_path / "big.yaml", "--out", tmp_path / "out"))
    assert_one_line(result, 2, expected)
    assert peak < MEMORY_BOUND and not (tmp_path / "out").exists()


def test_run_names_keep_minus_signs() -> None:
    assert run_stem({"ground.slope": -0.3, "walker.kind": "a b"}, {"ground.slope": "slope", "walker.kind": "kind"}) == (
        "slope=-0.3_kind=a-b"
    )


def test_output_files_and_directories_get_the_usual_permissions(tmp_path: Path) -> None:
    old_umask = os.umask(0o022)
    try:
        write_text_atomic(tmp_path / "a.txt", "x")
        with output_module.staged_directory(tmp_path / "out", output_module.OutputKind("t", ("*.txt",))) as stage:
            write_text_atomic(stage / "b.txt", "y")
    finally:
        os.umask(old_umask)
    assert oct((tmp_path / "a.txt").stat().st_mode & 0o777) == oct(0o644)
    assert oct((tmp_path / "out").stat().st_mode & 0o777) == oct(0o755)
    assert oct((tmp_path / "out" / "b.txt").stat().st_mode & 0o777) == oct(0o644)


# 8. output locations checked before any work; write errors in one line


@pytest.fixture
def read_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every directory is on a read-only file system (as far as the output check's probe can tell)."""

    def refuse(target: Path, *, directory: bool = False) -> Path:
        raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(target))

    monkeypatch.setattr(output_module, "temporary_sibling", refuse)


@pytest.mark.parametrize("command", ["sweep", "report", "plot", "compare"])
@pytest.mark.parametrize(
    ("where", "expected"),
    [("file", "is a file, not a directory"), ("under_file", "cannot be created: "), ("other", "")],
)
def test_an_unusable_output_location_is_one_line_before_any_work(
    imperfect_sweep: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, command: str, where: str, expected: str
) -> None:
    (tmp_path / "file").write_text("not a directory")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("the user's own")
    out = {"file": tmp_path / "file", "under_file": tmp_path / "file" / "out", "other": tmp_path / "other"}[where]
    if command == "sweep" and where == "other":
        pytest.skip("a sweep writes into an existing directory of any content")
    if where == "other":
        expected = f"holds files that biped-sim {command} did not write"
    (tmp_path / "s.yaml").write_text(f"name: s\nbase: {DEFAULT_CONFIG}\ngrid:\n  ground.slope: [0.01]\n")
    reference = fictitious_reference(tmp_path, [0.4])
    args = {
        "sweep": ["sweep", tmp_path / "s.yaml"],
        "report": ["report", imperfect_sweep],
        "plot": ["plot", run_dir_of(imperfect_sweep, "walking")],
        "compare": ["compare", DEFAULT_CONFIG, "--reference", reference],
    }[command]
    simulate_module = sys.modules["biped_sim.simulate"]  # the package's attribute of that name is the function
    monkeypatch.setattr(simulate_module, "simulate", lambda *a, **k: pytest.fail("computed before checking --out"))
    assert_one_line(invoke(*args, "--out", out), 2, f"{out}: {expected}")
    assert (tmp_path / "file").read_text() == "not a directory" and leftovers(tmp_path) == []


@pytest.mark.usefixtures("read_only")
@pytest.mark.parametrize("command", ["sweep", "report"])
def test_a_read_only_output_location_is_one_line(imperfect_sweep: Path, tmp_path: Path, command: str) -> None:
    (tmp_path / "s.yaml").write_text(f"name: s\nbase: {DEFAULT_CONFIG}\ngrid:\n  ground.slope: [0.01]\n")
    args = ["sweep", tmp_path / "s.yaml"] if command == "sweep" else ["report", imperfect_sweep]
    result = invoke(*args, "--out", tmp_path / "out")
    assert_one_line(result, 2, f"cannot write in {tmp_path}: Read-only file system")


# 9. damaged inputs, bad scheduler


@pytest.mark.parametrize(
    ("damage", "command"),
    [
        ("trajectory.h5", "plot"),
        ("trajectory.h5", "animate"),
        ("summary.json", "plot"),
        ("summary.json", "compare"),
        ("trajectory.h5", "report"),
        ("sweep.csv", "report"),
    ],
)
def test_a_truncated_input_is_one_line_exit_2(sweep_copy: Path, tmp_path: Path, damage: str, command: str) -> None:
    run_dir = run_dir_of(sweep_copy, "walking")
    path = (sweep_copy if damage == "sweep.csv" else run_dir) / damage
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 3])
    target = sweep_copy if command == "report" else run_dir
    extra = {
        "animate": ["--out", tmp_path / "walk.gif"],
        "compare": ["--reference", fictitious_reference(tmp_path, [0.4])],
    }.get(command, [])
    assert_one_line(invoke(command, target, *extra), 2, "damaged or truncated")
    assert not (tmp_path / "walk.gif").exists() and leftovers(sweep_copy) == []


def test_a_garbage_dask_scheduler_is_one_line(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    (tmp_path / "s.yaml").write_text(f"name: s\nbase: {DEFAULT_CONFIG}\ngrid:\n  ground.slope: [0.01]\n")
    result = invoke(
        "sweep", tmp_path / "s.yaml", "--out", tmp_path / "out", "--executor", "dask", "--scheduler", "garbage"
    )
    assert_one_line(result, 2, "--scheduler: cannot connect to 'garbage'")


# Slow: real worker processes, killed; interrupts


def start_sweep(sweep_file: Path, out: Path) -> tuple[subprocess.Popen[str], list[int], int]:
    """The sweep CLI on two workers in its own session (as a terminal's foreground job), once a worker has frozen
    while finishing its second run (conftest.freezing_env: that run never finishes); with the workers' pids and the
    frozen one's. Its first run is finished, and the other worker is in a run or done."""
    markers = out.parent / "markers"
    process = subprocess.Popen(
        [*CLI, "sweep", str(sweep_file), "--out", str(out), "--jobs", "2"],
        cwd=sweep_file.parent,
        env=freezing_env(markers, "summary.json@2"),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=interruptible,
    )
    frozen = wait_frozen(process, markers, "summary.json")["summary.json"]
    return process, children(process.pid), frozen


def interruptible() -> None:
    """Ctrl-C's default action in the child, as in a terminal's foreground job (a shell's background job, e.g.
    a test run started with ``&``, would hand down SIGINT ignored, and the sweep would never see the Ctrl-C)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def children(pid: int) -> list[int]:
    """The child processes of ``pid`` (Linux /proc: every thread's children)."""
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        found += [int(child) for child in (task / "children").read_text().split()]
    return found


def is_dead(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1].startswith("Z")  # a zombie: exited, not reaped
    except (FileNotFoundError, ProcessLookupError):
        return True


@pytest.fixture
def six_runs(tmp_path: Path) -> Iterator[Path]:
    path = tmp_path / "six.yaml"
    path.write_text(SIX_RUNS)
    yield path
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):  # no process of this test outlives it
        try:
            assert str(tmp_path) not in cmdline.read_text(errors="replace"), cmdline
        except OSError:  # it ended meanwhile
            continue


@pytest.mark.slow
@pytest.mark.serial
def test_killing_one_worker_fails_only_its_run_and_resume_runs_it_again(six_runs: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    process, _, frozen = start_sweep(six_runs, out)
    os.kill(frozen, signal.SIGKILL)
    _, stderr = process.communicate(timeout=300)
    assert process.returncode == 1, stderr
    table = pd.read_csv(out / "sweep.csv", keep_default_na=False)
    assert sorted(table["status"]) == ["error"] + ["walking"] * 5
    assert list(table.loc[table["status"] == "error", "error"]) == ["worker died (signal 9)"]
    again = subprocess.run([*CLI, "sweep", str(six_runs), "--out", str(out)], capture_output=True, text=True)
    assert again.returncode == 0 and "6 runs: 5 already finished, 1 to run" in again.stdout, again.stderr
    assert list(pd.read_csv(out / "sweep.csv")["status"]) == ["walking"] * 6


@pytest.mark.slow
@pytest.mark.serial
@pytest.mark.parametrize(
    ("stop", "code", "word"),
    [
        (lambda process: os.killpg(process.pid, signal.SIGINT), 130, "interrupted"),  # Ctrl-C: the foreground group
        (lambda process: process.send_signal(signal.SIGTERM), 143, "terminated"),  # a scheduler or Dask: the process
    ],
    ids=["ctrl-c", "sigterm"],
)
def test_an_interrupt_cancels_the_queue_and_leaves_a_consistent_sweep(
    six_runs: Path, tmp_path: Path, stop: Callable[[subprocess.Popen[str]], None], code: int, word: str
) -> None:
    out = tmp_path / "out"
    process, workers, _ = start_sweep(six_runs, out)
    stop(process)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == code, stderr
    assert "Traceback" not in stderr and stderr.strip().splitlines()[-1].startswith(f"{word}: ")
    deadline = time.monotonic() + 10
    while not all(is_dead(pid) for pid in workers):
        assert time.monotonic() < deadline, "workers outlived the sweep"
        time.sleep(0.05)
    finished = {p.parent.name for p in out.glob("runs/*/summary.json")}
    time.sleep(2)
    assert {p.parent.name for p in out.glob("runs/*/summary.json")} == finished  # nothing queued went on running
    table = pd.read_csv(out / "sweep.csv")
    assert 0 < len(finished) < 6
    assert {name: status for name, status in zip(table["run"], table["status"], strict=True)} == {
        name: "walking" if name in finished else "pending" for name in table["run"]
    }
    assert not list(out.rglob("error.json"))
    # the frozen worker's run keeps its temporary summary, and a run in flight when the sweep ended may keep its
    # own (a resume clears them): temporaries of unfinished runs only, never of the table or the manifest
    left = [Path(path).parent.parent for path in leftovers(out)]
    assert left and set(left) == {out / "runs"}
    assert {Path(path).parent.name for path in leftovers(out)}.isdisjoint(finished)


@pytest.mark.slow
@pytest.mark.serial
def test_two_ctrl_c_in_a_row_still_end_with_130(six_runs: Path, tmp_path: Path) -> None:
    """The second arrives once the first has stopped the sweep, as it exits: the exit code stays 130."""
    process, _, _ = start_sweep(six_runs, tmp_path / "out")
    os.killpg(process.pid, signal.SIGINT)
    time.sleep(0.05)
    os.killpg(process.pid, signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr


@pytest.mark.slow
@pytest.mark.serial
def test_workers_die_with_their_parent(six_runs: Path, tmp_path: Path) -> None:
    process, workers, _ = start_sweep(six_runs, tmp_path / "out")
    assert len(workers) == 2
    process.kill()  # the parent alone, not its process group
    process.communicate()
    deadline = time.monotonic() + 10
    while not all(is_dead(pid) for pid in workers):
        assert time.monotonic() < deadline, "orphan workers"
        time.sleep(0.05)


@pytest.mark.slow
def test_cli_resume_runs_again_only_the_run_whose_trajectory_was_deleted(tmp_path: Path) -> None:
    path = tmp_path / "three.yaml"
    path.write_text(SIX_RUNS.replace("12.0", "0.5").replace("num: 6", "num: 3"))
    out = tmp_path / "out"
    first = subprocess.run([*CLI, "sweep", str(path), "--out", str(out)], capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    runs = sorted((out / "runs").iterdir())
    (runs[1] / "trajectory.h5").unlink()
    stamps = {run.name: (run / "summary.json").stat().st_mtime_ns for run in runs}
    again = subprocess.run([*CLI, "sweep", str(path), "--out", str(out)], capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert "3 runs: 2 already finished, 1 to run" in again.stdout
    assert again.stderr.strip() == (
        f"warning: running 1 damaged finished run(s) again: {runs[1].name} (trajectory.h5 missing)"
    )
    changed = [run.name for run in runs if (run / "summary.json").stat().st_mtime_ns != stamps[run.name]]
    assert changed == [runs[1].name] and (runs[1] / "trajectory.h5").is_file()
