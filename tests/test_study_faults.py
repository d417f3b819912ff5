"""The studies' failure path under faults (issue 32, slow tier): a full disk under ``fit`` and ``uncertainty``,
SIGTERM to ``fit``, a Dask scheduler killed during a study and a Dask worker killed during a sweep.

Each is the real entry point in a fresh process (:func:`tests.conftest.run_cli`'s interpreter); the full disk
is a small tmpfs (root only: skipped elsewhere), the Dask cluster a scheduler and two workers on this machine.
"""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pandas as pd
import pytest

from biped_sim.sweep import load_sweep
from biped_sim.sweep.executors import SCHEDULER_LOST

from .conftest import CLI, CONFIGS, DEFAULT_CONFIG, child_env

pytestmark = pytest.mark.slow
REFERENCE = CONFIGS / "references" / "synthetic_round_foot_periods.yaml"
FIT = ["fit", str(DEFAULT_CONFIG), "--reference", str(REFERENCE), "--param", "walker.leg_inertia=0.0043:0.006"]
SHORT = ["--set", "simulation.t_end=1"]  # a second of walking: a chunk of 16 samples in seconds
UNCERTAINTY = ["uncertainty", str(CONFIGS / "simplest_walker.yaml"), "--param", "ground.slope=uniform:0.008:0.01",
               "-n", "8", "--json"]  # fmt: skip
TIMEOUT_S = 600  # a loaded machine (the studies of other sessions) slows every process here
Cluster = tuple[str, subprocess.Popen[bytes], list[subprocess.Popen[bytes]]]  # address, scheduler, workers


def start(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen([*CLI, *args], cwd=cwd, env=child_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip


def finish(process: subprocess.Popen[str]) -> tuple[int, str]:
    """Exit code and stderr's last line (asserting no traceback)."""
    _, stderr = process.communicate(timeout=TIMEOUT_S)
    assert "Traceback" not in stderr, stderr
    return process.returncode, stderr.strip().splitlines()[-1]


def one_line(process: subprocess.Popen[str]) -> tuple[int, str]:
    """Exit code and the single line on stderr."""
    _, stderr = process.communicate(timeout=TIMEOUT_S)
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    return process.returncode, lines[0]


def wait_for(condition: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + TIMEOUT_S
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.2)


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 4 MiB tmpfs (:func:`fill` takes every byte left on it)."""
    root = tmp_path / "disk"
    root.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(root)], capture_output=True)
    if mounted.returncode != 0:
        pytest.skip("mounting a tmpfs needs root")
    yield root
    subprocess.run(["umount", str(root)], check=True)


def fill(disk: Path) -> None:
    """A file on ``disk`` that takes every free byte."""
    with (disk / "filler").open("wb", buffering=0) as filler, pytest.raises(OSError, match="No space left"):
        while True:
            filler.write(b"\0" * 4096)


def test_fit_on_a_full_disk_is_one_line_exit_1(small_disk: Path, tmp_path: Path) -> None:
    fill(small_disk)
    code, line = one_line(start(*FIT, "--out", str(small_disk / "fit"), cwd=tmp_path))
    assert code == 1 and line.startswith("error: ") and line.endswith("No space left on device"), line


def test_uncertainty_h5_on_a_full_disk_is_one_line_exit_1(small_disk: Path, tmp_path: Path) -> None:
    """The study runs once with room (its samples' chunks stay), then again on the filled disk: the chunks are
    reused, so the first write is uncertainty.h5 (h5py's own write ended in a 65-line RuntimeError)."""
    out = small_disk / "u"
    first = start(*UNCERTAINTY, "--out", str(out), cwd=tmp_path)
    assert first.communicate(timeout=TIMEOUT_S) and first.returncode == 0
    for path in out.iterdir():
        if path.is_file():
            path.unlink()
    fill(small_disk)
    code, line = one_line(start(*UNCERTAINTY, "--out", str(out), cwd=tmp_path))
    assert (code, line) == (1, f"error: {out / 'uncertainty.h5'}: No space left on device")
    assert not (out / "uncertainty.h5").exists() and not list(out.glob(".*.tmp"))


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_sigterm_ends_a_fit_with_143_and_flushes_its_checkpoint(tmp_path: Path, jobs: str) -> None:
    checkpoint = tmp_path / ".fit.checkpoint" / "fit.checkpoint.json"
    process = start(*FIT, "--jobs", jobs, "--out", str(tmp_path / "fit"), cwd=tmp_path)
    wait_for(checkpoint.is_file, "the first checkpoint")
    first_save = checkpoint.stat().st_mtime_ns
    # at once: the first save ends the first batch, the fit's later batches take seconds (a fixed wait let a warm
    # fit finish before the signal, which then ended the exiting interpreter: -15)
    assert process.poll() is None, "the fit ended before it could be terminated"
    process.send_signal(signal.SIGTERM)
    code, line = finish(process)
    assert (code, line) == (143, "terminated: run the same command again to resume from the checkpoint")
    assert checkpoint.stat().st_mtime_ns > first_save  # flushed on the way out
    assert json.loads(checkpoint.read_text())["evaluations"]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_a_fit_whose_dask_scheduler_does_not_answer_leaves_nothing_behind(tmp_path: Path) -> None:
    scheduler = f"tcp://127.0.0.1:{free_port()}"
    code, line = one_line(start(*FIT, "--executor", "dask", "--scheduler", scheduler, "--out", "fit", cwd=tmp_path))
    assert code == 2 and line.startswith(f"error: --scheduler: cannot connect to '{scheduler}'"), line
    assert list(tmp_path.iterdir()) == []  # no checkpoint folder beside --out


@pytest.fixture
def dask_cluster(tmp_path: Path) -> Iterator[Cluster]:
    """A Dask scheduler and two single-threaded workers (no nanny: a killed worker stays dead) on this machine."""
    pytest.importorskip("distributed")
    address = f"tcp://127.0.0.1:{free_port()}"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": child_env(), "cwd": tmp_path}
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", address.rsplit(":", 1)[1], "--no-dashboard"], **quiet)  # fmt: skip
    workers = [
        subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                          "--no-nanny", "--no-dashboard", "--preload", "biped_sim.sweep.preload"], **quiet)
        for _ in range(2)
    ]  # fmt: skip
    yield address, scheduler, workers
    for process in [*workers, scheduler]:
        process.kill()
        process.wait()


def test_a_dask_scheduler_lost_during_a_study_is_one_line_and_a_rerun_resumes(
    dask_cluster: Cluster, tmp_path: Path
) -> None:
    address, scheduler, _ = dask_cluster
    out = tmp_path / "u"
    study = ["uncertainty", str(DEFAULT_CONFIG), *SHORT, "--param", "ground.slope=uniform:0.018:0.022", "-n", "64",
             "--json", "--out", str(out)]  # fmt: skip
    process = start(*study, "--executor", "dask", "--scheduler", address, cwd=tmp_path)
    wait_for(lambda: any((out / "samples").glob("*.json")), "the first chunk of samples")
    scheduler.kill()
    assert one_line(process) == (1, f"error: {SCHEDULER_LOST}")
    again = subprocess.run([*CLI, *study, "--jobs", "2"], cwd=tmp_path, env=child_env(), capture_output=True,
                           text=True, timeout=TIMEOUT_S)  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["chunks_reused"] >= 1


def dask_sweep(address: str, sweep: Path, out: Path) -> subprocess.Popen[str]:
    """The sweep CLI on the Dask cluster at ``address``."""
    return start("sweep", str(sweep), "--out", str(out), "--executor", "dask", "--scheduler", address, cwd=out.parent)


def test_a_dask_scheduler_lost_during_a_sweep_is_one_line_and_leaves_its_runs_pending(
    dask_cluster: Cluster, tiny_sweep_dir: Path, tmp_path: Path
) -> None:
    address, scheduler, _ = dask_cluster
    out = tmp_path / "dask"
    process = dask_sweep(address, tiny_sweep_dir.parent / "tiny.yaml", out)
    wait_for((out / "sweep.csv").is_file, "the sweep's table")
    scheduler.kill()
    assert one_line(process) == (1, f"error: {SCHEDULER_LOST}")
    statuses = pd.read_csv(out / "sweep.csv")["status"]
    assert set(statuses) <= {"walking", "pending"} and "pending" in set(statuses)
    assert not list(out.rglob("error.json"))


def test_a_dask_worker_killed_during_a_sweep_leaves_the_local_results(
    dask_cluster: Cluster, tiny_sweep_dir: Path, tmp_path: Path
) -> None:
    """The scheduler hands the killed worker's run to the other one: every run as the local processes made it."""
    address, _, workers = dask_cluster
    out = tmp_path / "dask"
    sweep = tiny_sweep_dir.parent / "tiny.yaml"
    process = dask_sweep(address, sweep, out)
    wait_for(lambda: any(out.glob("runs/*/summary.json")), "the sweep's first run")
    assert len(list(out.glob("runs/*/summary.json"))) < 8, "the sweep was over before the kill"
    workers[0].send_signal(signal.SIGKILL)
    _, stderr = process.communicate(timeout=TIMEOUT_S)
    assert process.returncode == 0, stderr
    timing = ["wall_time_s"]
    local = pd.read_csv(tiny_sweep_dir / "sweep.csv").drop(columns=timing)
    pd.testing.assert_frame_equal(local, pd.read_csv(out / "sweep.csv").drop(columns=timing))
    for run in load_sweep(sweep).runs:
        a = json.loads((tiny_sweep_dir / "runs" / run.name / "summary.json").read_text())
        b = json.loads((out / "runs" / run.name / "summary.json").read_text())
        assert a["step_times"] == b["step_times"] and a["rhs_evals"] == b["rhs_evals"]
