"""Running a sweep: executors, the worker function, resume, and the sweep table.

The runner is written against :class:`concurrent.futures.Executor`: a local
``ProcessPoolExecutor`` (explicit ``spawn`` context, one BLAS/numba thread per worker) or a Dask
cluster through ``distributed.Client(...).get_executor()``, with no second code path. Each
worker simulates one run, writes its own run directory (every file atomically, summary.json
last) and returns one small row; the parent never touches a run's HDF5 file while it is written.

Layout of a sweep directory::

    sweep.json            manifest: name, source, axes, overrides, one entry per run
    sweep.csv             one row per run (rows.py), rewritten atomically after every run
    sweep.parquet         the same table, when pyarrow is installed
    runs/<stem>-<hash>/   trajectory.h5, steps.csv, config.yaml, summary.json (or error.json)

A run is finished when its summary.json exists and names the run's config hash; resuming skips
exactly those. A run that raised leaves error.json (and no summary.json) and is retried on resume.
"""

from __future__ import annotations

import contextlib
import importlib.util
import json
import multiprocessing
import os
import traceback
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from biped_sim.config import Config, config_from_dict
from biped_sim.errors import ConfigError
from biped_sim.io.atomic import write_json_atomic, write_text_atomic, write_with
from biped_sim.simulate import simulate
from biped_sim.sweep.rows import METRIC_COLUMNS, metrics_from_summary, settings_of, unfinished_metrics
from biped_sim.sweep.spec import RunSpec, Sweep

THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")
INTEGER_COLUMNS = ("n_steps", "rhs_evals", "accepted_steps", "rejected_steps")
FAILED_STATUSES = ("error", "diverged")
STIFF_METHODS = ("radau", "bdf")
WARM_UP_TIME = 1e-3  # s of simulated time


def init_worker() -> None:
    """Worker initializer: one thread per BLAS/OpenMP/numba pool, so N workers use N cores, not N^2."""
    for name in THREAD_VARIABLES:
        os.environ[name] = "1"


def default_jobs() -> int:
    """Number of cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def single_threaded_children() -> Iterator[None]:
    """Set the thread variables to 1 in this process's environment while child processes start.

    A spawned worker imports numpy (and with it OpenBLAS, which reads its thread count once)
    before any initializer runs, so the variables must already be in the environment it inherits.
    """
    saved = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    os.environ.update(dict.fromkeys(THREAD_VARIABLES, "1"))
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


@contextlib.contextmanager
def local_executor(jobs: int) -> Iterator[Executor]:
    """A process pool of ``jobs`` single-threaded workers, started with ``spawn`` (no inherited threads or locks)."""
    context = multiprocessing.get_context("spawn")
    with (
        single_threaded_children(),
        ProcessPoolExecutor(max_workers=jobs, mp_context=context, initializer=init_worker) as pool,
    ):
        yield pool


@contextlib.contextmanager
def dask_executor(jobs: int, scheduler: str | None) -> Iterator[Executor]:
    """A Dask executor: on the cluster at ``scheduler`` (tcp://host:port), else on a LocalCluster of ``jobs`` workers.

    Workers must see the same file system as this process (they write the run directories).
    """
    try:
        from distributed import Client, LocalCluster  # optional extra (biped-sim[dask])
    except ImportError:
        raise ConfigError("--executor", "dask needs the optional extra: pip install 'biped-sim[dask]'") from None
    with contextlib.ExitStack() as stack:
        if scheduler:
            try:
                client = stack.enter_context(Client(scheduler, timeout="10s"))
            except (OSError, TimeoutError) as exc:
                raise ConfigError("--scheduler", f"cannot connect to {scheduler}: {exc}") from None
        else:
            cluster = stack.enter_context(
                LocalCluster(
                    n_workers=jobs,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    env=dict.fromkeys(THREAD_VARIABLES, "1"),
                )
            )
            client = stack.enter_context(Client(cluster))
        client.run(init_worker)
        executor = client.get_executor()
        try:
            yield executor
        finally:
            executor.shutdown(wait=False)


@contextlib.contextmanager
def make_executor(kind: str, jobs: int, scheduler: str | None = None) -> Iterator[Executor]:
    """The executor named on the command line: 'local' (processes) or 'dask'."""
    if kind == "local":
        if scheduler:
            raise ConfigError("--scheduler", "only used with --executor dask")
        with local_executor(jobs) as executor:
            yield executor
    elif kind == "dask":
        with dask_executor(jobs, scheduler) as executor:
            yield executor
    else:
        raise ConfigError("--executor", f"unknown executor {kind!r}; expected local or dask")


@dataclass(frozen=True)
class RunTask:
    """What a worker needs for one run (plain data: pickles to any process or cluster node)."""

    name: str
    run_dir: str
    config: dict[str, Any]


def _clear_unfinished(run_dir: Path) -> None:
    """Remove what an earlier, unfinished attempt may have left: temp files, an old marker, an error record."""
    for path in run_dir.glob(".*.tmp"):
        path.unlink(missing_ok=True)
    (run_dir / "summary.json").unlink(missing_ok=True)
    (run_dir / "error.json").unlink(missing_ok=True)


_WARMED: set[str] = set()


def warm_up(config: Config) -> None:
    """Run ``config`` for 1 ms once per process and integrator family, so that compiling (or loading
    the cached) numba code is not counted in the first run's wall time: wall times of a sweep
    compare integrators, not process start-up. Rigid runs have no compiled code to warm.
    """
    if config.dynamics == "rigid":
        return
    family = "stiff" if config.integrator.method in STIFF_METHODS else "explicit"
    if family in _WARMED:
        return
    simulate(config_from_dict(config.model_dump(mode="json"), [f"simulation.t_end={WARM_UP_TIME}"]))
    _WARMED.add(family)


def execute_run(task: RunTask) -> dict[str, Any]:
    """Worker: simulate one run, write its directory, return its metric columns.

    Any exception is recorded (error.json and the returned row) rather than raised, so one bad
    run never stops a sweep.
    """
    run_dir = Path(task.run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    _clear_unfinished(run_dir)
    try:
        config = Config.model_validate(task.config)
        warm_up(config)
        result = simulate(config)
        result.write(run_dir)
        return metrics_from_summary(result.summary)
    except Exception as exc:
        message = f"{type(exc).__name__}: {exc}".splitlines()[0]
        write_json_atomic(
            run_dir / "error.json",
            {"status": "error", "error": message, "traceback": traceback.format_exc(), "name": task.name},
        )
        return unfinished_metrics("error", message)


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


def parquet_available() -> bool:
    """pyarrow (or fastparquet) present: the sweep table is also written as Parquet."""
    return any(importlib.util.find_spec(name) is not None for name in ("pyarrow", "fastparquet"))


def table_frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    """The sweep table as a DataFrame (integer counters stay integers where present)."""
    frame = pd.DataFrame(rows)
    for column in INTEGER_COLUMNS:
        frame[column] = frame[column].astype("Int64")
    return frame


def write_table(rows: list[dict[str, Any]], sweep_dir: Path) -> None:
    """Write sweep.csv (and sweep.parquet) atomically."""
    frame = table_frame(rows)
    write_text_atomic(sweep_dir / "sweep.csv", frame.to_csv(index=False))
    if parquet_available():
        write_with(sweep_dir / "sweep.parquet", lambda tmp: frame.to_parquet(tmp, index=False))


@dataclass
class SweepProgress:
    """Counts reported to the progress callback after every run."""

    total: int
    skipped: int = 0
    done: int = 0
    failed: int = 0
    statuses: dict[str, int] = field(default_factory=dict)

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


def pending_runs(sweep: Sweep, sweep_dir: Path, resume: bool) -> list[RunSpec]:
    """The runs still to do: all of them without ``resume``, else those without a finished summary."""
    if not resume:
        return list(sweep.runs)
    return [run for run in sweep.runs if finished_summary(sweep_dir / "runs" / run.name, run.config_hash) is None]


def _row(run: RunSpec, metrics: dict[str, Any]) -> dict[str, Any]:
    return {"run": run.name, "config_hash": run.config_hash, **run.params, **settings_of(run.config), **metrics}


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
    after each run. With ``resume``, runs whose summary.json carries their config hash are not
    run again. Interrupted (KeyboardInterrupt), the table of what finished is still written.
    """
    sweep_dir.mkdir(parents=True, exist_ok=True)
    write_json_atomic(sweep_dir / "sweep.json", manifest(sweep))
    rows: list[dict[str, Any]] = []
    pending: list[RunSpec] = []
    progress = SweepProgress(total=len(sweep.runs))
    for run in sweep.runs:
        run_dir = sweep_dir / "runs" / run.name
        summary = finished_summary(run_dir, run.config_hash) if resume else None
        if summary is not None:
            rows.append(_row(run, metrics_from_summary(summary)))
            progress.skipped += 1
        else:
            rows.append(_row(run, unfinished_metrics("pending", "")))
            pending.append(run)
    write_table(rows, sweep_dir)
    if on_progress is not None:
        on_progress(progress, None, None)
    futures: dict[Future[dict[str, Any]], RunSpec] = {}
    try:
        for run in pending:
            task = RunTask(run.name, str(sweep_dir / "runs" / run.name), run.config.model_dump(mode="json"))
            futures[executor.submit(execute_run, task)] = run
        for future in as_completed(futures):
            run = futures[future]
            try:
                metrics = future.result()
            except Exception as exc:  # the worker process itself died (e.g. killed): record and go on
                metrics = unfinished_metrics("error", f"{type(exc).__name__}: {exc}".splitlines()[0])
            rows[run.index] = _row(run, metrics)
            progress.add(metrics["status"])
            write_table(rows, sweep_dir)
            if on_progress is not None:
                on_progress(progress, run.name, rows[run.index])
    except BaseException:
        for future in futures:
            future.cancel()
        raise
    finally:
        write_table(rows, sweep_dir)
    return SweepOutcome(sweep_dir=sweep_dir, rows=rows, progress=progress)


def read_sweep(sweep_dir: Path) -> tuple[dict[str, Any], pd.DataFrame]:
    """(manifest, table) of a sweep directory; ConfigError if it is not one."""
    manifest_path, table_path = sweep_dir / "sweep.json", sweep_dir / "sweep.csv"
    if not manifest_path.is_file() or not table_path.is_file():
        raise ConfigError(str(sweep_dir), "not a sweep directory (no sweep.json and sweep.csv)")
    data = json.loads(manifest_path.read_text())
    frame = pd.read_csv(table_path, keep_default_na=False, na_values=[""], dtype={"error": str})
    missing = [c for c in ("run", *METRIC_COLUMNS) if c not in frame.columns]
    if missing:
        raise ConfigError(str(table_path), f"missing columns {', '.join(missing)}")
    frame["error"] = frame["error"].fillna("")
    return data, frame
