"""Running a sweep: the worker function, resume, and the sweep table.

The runner is written against :class:`concurrent.futures.Executor` (:mod:`biped_sim.sweep.executors`: a local
pool of worker processes, in which a dead worker fails only its own run, or a Dask cluster), with no second
code path. Each worker simulates one run, writes its own run directory (every file
atomically, summary.json last) and returns one small row; the parent never touches a run's HDF5 file
while it is written. A sweep holds a lock on its directory (:mod:`biped_sim.sweep.lock`).

Layout of a sweep directory::

    sweep.json            manifest: name, source, axes, overrides, one entry per run
    sweep.csv             one row per run (rows.py), rewritten atomically after every run
    sweep.parquet         the same table, when pyarrow is installed
    .sweep.lock           held while a sweep writes the directory
    runs/<stem>-<hash>/   trajectory.h5, steps.csv, config.yaml, summary.json (or error.json)

A run is finished when its summary.json exists and names the run's config hash and its trajectory.h5
opens and carries that hash; resuming skips exactly those, and runs again (and names) the damaged ones.
A run that raised, or whose worker died, leaves error.json (and no summary.json) and is retried on resume.
Interrupted (Ctrl-C), a sweep cancels what has not started, stops what runs and leaves a table that
matches the run directories: finished runs as finished, the others pending.
"""

from __future__ import annotations

import errno
import inspect
import json
import traceback
from collections.abc import Callable
from concurrent.futures import CancelledError, Executor, Future, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from biped_sim.config import Config
from biped_sim.io.atomic import write_json_atomic
from biped_sim.io.run_files import start_run_directory
from biped_sim.io.trajectory import trajectory_problem
from biped_sim.simulate import simulate
from biped_sim.simulate.warmup import warm_up
from biped_sim.sweep.lock import sweep_lock
from biped_sim.sweep.pool import WorkerDiedError
from biped_sim.sweep.rows import metrics_from_summary, settings_of, table_frame, unfinished_metrics, write_table
from biped_sim.sweep.spec import RunSpec, Sweep

RUN_FILES = ("steps.csv", "config.yaml")  # besides summary.json and trajectory.h5, checked on their own
FAILED_STATUSES = ("error", "diverged")  # a sweep holding such a run exits with 1
SWEEP_FILES = ("sweep.json", "sweep.csv", "sweep.parquet")  # written by the sweep holding the lock, and no one else


@dataclass(frozen=True)
class RunTask:
    """What a worker needs for one run (plain data: pickles to any process or cluster node)."""

    name: str
    run_dir: str
    config: dict[str, Any]


def record_error(run_dir: Path, name: str, message: str, trace: str) -> None:
    """error.json of a run that raised or whose worker died: it has no results, and is retried on resume."""
    write_json_atomic(run_dir / "error.json", {"status": "error", "error": message, "traceback": trace, "name": name})


def _clear_unfinished(run_dir: Path) -> None:
    """Remove what an earlier attempt may have left: the old marker and temp files, an error record."""
    start_run_directory(run_dir)
    (run_dir / "error.json").unlink(missing_ok=True)


def disk_full(exc: BaseException) -> bool:
    """Whether ``exc`` says the disk (or the user's quota) is full: every later run would fail the same way."""
    return isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT)


def execute_run(task: RunTask) -> dict[str, Any]:
    """Worker: simulate one run, write its directory, return its metric columns.

    Any exception is recorded (error.json and the returned row) rather than raised, so one bad
    run never stops a sweep; but a full disk is raised (:func:`disk_full`): it stops the sweep.
    """
    run_dir = Path(task.run_dir)
    _clear_unfinished(run_dir)
    try:
        config = Config.model_validate(task.config)
        warm_up(config)  # compiling is not counted in the first run's wall time: a sweep compares runs
        result = simulate(config)
        result.write(run_dir)
        return metrics_from_summary(result.summary)
    except Exception as exc:
        if disk_full(exc):
            raise
        message = error_message(exc)
        record_error(run_dir, task.name, message, traceback.format_exc())
        return unfinished_metrics("error", message)


def error_message(exc: BaseException) -> str:
    """The one line the sweep table shows for a failed run: 'RuntimeError: ...', or 'worker died (signal 9)'."""
    text = str(exc) if isinstance(exc, WorkerDiedError) else f"{type(exc).__name__}: {exc}"
    return text.splitlines()[0]


def finished_summary(run_dir: Path, config_hash: str) -> dict[str, Any] | None:
    """The summary of a finished run with this config hash, or None (not run, unfinished or another config)."""
    path = run_dir / "summary.json"
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(summary, dict) or summary.get("config_hash") != config_hash:
        return None
    return summary


@dataclass
class SweepProgress:
    """Counts reported to the progress callback after every run."""

    total: int
    skipped: int = 0
    done: int = 0
    failed: int = 0
    statuses: dict[str, int] = field(default_factory=dict)
    damaged: dict[str, str] = field(default_factory=dict)  # finished runs found damaged (run again): name -> why

    def add(self, status: str) -> None:
        self.done += 1
        self.statuses[status] = self.statuses.get(status, 0) + 1
        if status in FAILED_STATUSES:
            self.failed += 1


@dataclass
class SweepOutcome:
    """What a sweep did: its rows (in run order) and the counts."""

    sweep_dir: Path
    rows: list[dict[str, Any]]
    progress: SweepProgress

    @property
    def errors(self) -> int:
        return self.progress.statuses.get("error", 0)

    @property
    def failed(self) -> dict[str, int]:
        """The sweep's failed runs by status (``FAILED_STATUSES``), finished before this resume or now."""
        counts: dict[str, int] = {}
        for row in self.rows:
            if row["status"] in FAILED_STATUSES:
                counts[row["status"]] = counts.get(row["status"], 0) + 1
        return counts

    def to_pandas(self) -> pd.DataFrame:
        """The sweep table (sweep.csv) as a DataFrame: one row per run, its swept values, status and gait."""
        return table_frame(self.rows)

    def __repr__(self) -> str:
        statuses: dict[str, int] = {}
        for row in self.rows:
            statuses[row["status"]] = statuses.get(row["status"], 0) + 1
        counts = ", ".join(f"{n} {status}" for status, n in sorted(statuses.items()))
        return f"<SweepOutcome {self.sweep_dir}: {len(self.rows)} runs ({counts})>"


def manifest(sweep: Sweep) -> dict[str, Any]:
    """sweep.json: enough to know, without the sweep file, what each run directory is."""
    return {
        "name": sweep.spec.name,
        "description": sweep.spec.description,
        "source": str(sweep.source),
        "base": str(sweep.base_path),
        "axes": sweep.axes,
        "grid_axes": list(sweep.spec.grid),
        "zip_axes": list(sweep.spec.zipped),
        "overrides": list(sweep.overrides),
        "runs": [
            {"name": run.name, "dir": f"runs/{run.name}", "config_hash": run.config_hash, "params": run.params}
            for run in sweep.runs
        ],
    }


def verified_summary(run_dir: Path, config_hash: str) -> tuple[dict[str, Any] | None, str | None]:
    """(summary, None) for a finished, intact run; (None, why) for a damaged one; (None, None) if it never finished.

    Intact: summary.json parses and names ``config_hash``, trajectory.h5 opens and carries it, and the other
    files are there.
    """
    if not (run_dir / "summary.json").exists():
        return None, None
    summary = finished_summary(run_dir, config_hash)
    if summary is None:
        return None, "summary.json unreadable or of another config"
    problem = trajectory_problem(run_dir / "trajectory.h5", config_hash)
    missing = [name for name in RUN_FILES if not (run_dir / name).is_file()]
    if problem is None and missing:
        problem = f"{missing[0]} missing"
    return (summary, None) if problem is None else (None, problem)


@dataclass
class Survey:
    """What a sweep directory already holds: the intact finished runs and the damaged ones."""

    finished: dict[str, dict[str, Any]]  # run name -> summary
    damaged: dict[str, str]  # run name -> what is wrong


def survey(sweep: Sweep, sweep_dir: Path, resume: bool) -> Survey:
    """Check every run directory of ``sweep`` (nothing is finished without ``resume``)."""
    found = Survey({}, {})
    if resume:
        for run in sweep.runs:
            summary, problem = verified_summary(sweep_dir / "runs" / run.name, run.config_hash)
            if summary is not None:
                found.finished[run.name] = summary
            elif problem is not None:
                found.damaged[run.name] = problem
    return found


def pending_runs(sweep: Sweep, sweep_dir: Path, resume: bool) -> list[RunSpec]:
    """The runs still to do: all of them without ``resume``, else those not finished intact."""
    finished = survey(sweep, sweep_dir, resume).finished
    return [run for run in sweep.runs if run.name not in finished]


def _row(run: RunSpec, metrics: dict[str, Any]) -> dict[str, Any]:
    return {"run": run.name, "config_hash": run.config_hash, **run.params, **settings_of(run.config), **metrics}


def _metrics(future: Future[dict[str, Any]], run: RunSpec, run_dir: Path) -> dict[str, Any]:
    """A finished task's metric columns; a task the executor could not run (e.g. its worker died) is recorded
    as an error here, since its worker could not record it. A full disk stops the sweep, and so does a task the
    executor cancelled (Dask's, when its scheduler is lost: the run is not at fault and stays pending)."""
    try:
        return future.result()
    except Exception as exc:
        if disk_full(exc) or isinstance(exc, CancelledError):
            raise
        message = error_message(exc)
        record_error(run_dir, run.name, message, "".join(traceback.format_exception(exc)))
        return unfinished_metrics("error", message)


def _stop(executor: Executor) -> None:
    """Cancel the queue and stop running tasks where the executor can (``cancel_futures``: the local pool ends its
    workers); Dask's executor cannot, and only stops being waited for."""
    if "cancel_futures" in inspect.signature(executor.shutdown).parameters:
        executor.shutdown(wait=True, cancel_futures=True)
    else:
        executor.shutdown(wait=False)


@dataclass
class _Ledger:
    """The sweep table being filled in, the counts, and the progress callback."""

    sweep_dir: Path
    rows: list[dict[str, Any]]
    progress: SweepProgress
    on_progress: Callable[[SweepProgress, str | None, dict[str, Any] | None], None] | None

    def record(self, run: RunSpec, metrics: dict[str, Any], announce: bool = True) -> None:
        self.rows[run.index] = _row(run, metrics)
        self.progress.add(metrics["status"])
        write_table(self.rows, self.sweep_dir)
        if announce and self.on_progress is not None:
            self.on_progress(self.progress, run.name, self.rows[run.index])

    def settle(self, runs: list[RunSpec]) -> None:
        """After an interrupt: record the runs that finished on disk meanwhile, so that the table matches the
        run directories (the others stay pending). The table is written again at the end: the interrupt may have
        come between a row's update and its table's write."""
        for run in runs:
            if self.rows[run.index]["status"] == "pending":
                summary = finished_summary(self.sweep_dir / "runs" / run.name, run.config_hash)
                if summary is not None:
                    self.record(run, metrics_from_summary(summary), announce=False)
        write_table(self.rows, self.sweep_dir)


def _execute(pending: list[RunSpec], executor: Executor, ledger: _Ledger) -> None:
    """Submit every pending run and record each as it finishes; on an interrupt stop the executor, settle, re-raise."""
    futures: dict[Future[dict[str, Any]], RunSpec] = {}
    runs_dir = ledger.sweep_dir / "runs"
    try:
        for run in pending:
            task = RunTask(run.name, str(runs_dir / run.name), run.config.model_dump(mode="json"))
            futures[executor.submit(execute_run, task)] = run
        for future in as_completed(futures):
            run = futures[future]
            ledger.record(run, _metrics(future, run, runs_dir / run.name))
    except BaseException:
        for future in futures:
            future.cancel()
        _stop(executor)
        ledger.settle(pending)
        raise


def run_sweep(
    sweep: Sweep,
    sweep_dir: Path,
    executor: Executor,
    *,
    resume: bool = True,
    on_progress: Callable[[SweepProgress, str | None, dict[str, Any] | None], None] | None = None,
) -> SweepOutcome:
    """Run every pending run of ``sweep`` on ``executor``; write the run directories and the sweep table.

    ``on_progress(progress, run_name, row)`` is called once before the first run (name None) and
    after each run. With ``resume``, runs finished intact are not run again; damaged ones are (and are
    listed in ``progress.damaged``). The sweep directory is locked for the duration (ConfigError naming
    the holder if another sweep writes it), and the temporaries a killed sweep left of its table and manifest
    are removed. Interrupted (KeyboardInterrupt), the queue is cancelled, the executor stopped and the table
    of what finished written before the interrupt propagates; so does a full disk's OSError (no space left:
    the sweep stops at the first run that meets it).
    """
    sweep_dir.mkdir(parents=True, exist_ok=True)
    with sweep_lock(sweep_dir, owned=SWEEP_FILES):
        write_json_atomic(sweep_dir / "sweep.json", manifest(sweep))
        found = survey(sweep, sweep_dir, resume)
        progress = SweepProgress(total=len(sweep.runs), skipped=len(found.finished), damaged=found.damaged)
        rows = [
            _row(run, metrics_from_summary(found.finished[run.name]))
            if run.name in found.finished
            else _row(run, unfinished_metrics("pending", ""))
            for run in sweep.runs
        ]
        write_table(rows, sweep_dir)
        if on_progress is not None:
            on_progress(progress, None, None)
        pending = [run for run in sweep.runs if run.name not in found.finished]
        _execute(pending, executor, _Ledger(sweep_dir, rows, progress, on_progress))
        return SweepOutcome(sweep_dir=sweep_dir, rows=rows, progress=progress)
