"""The executors studies and sweeps run on: a local pool of worker processes or a Dask cluster.

Everything runs against :class:`concurrent.futures.Executor`: a local :class:`~biped_sim.sweep.pool.WorkerPool`
(fresh interpreters, one BLAS/numba thread per worker; a dead worker fails only its own task) or a Dask cluster
through ``distributed.Client(...).get_executor()``, whose scheduler reschedules the task of a worker that dies.
A Dask scheduler that goes away takes the cluster's state with it: the block on its executor then ends with
:class:`SchedulerLostError` (one line: the files written so far stay, and the same command run again resumes).
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from concurrent.futures import Executor

from biped_sim.errors import ArgumentError, quote
from biped_sim.sweep.pool import WorkerPool

THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")
EXECUTORS = ("local", "dask")
SCHEDULER_LOST = "the Dask scheduler was lost; rerun resumes"
QUIET_LOGGERS = ("distributed", "distributed.client", "tornado.application")  # while a Dask executor is open


class SchedulerLostError(ConnectionError):
    """The Dask scheduler went away during a sweep or a study (an OSError: the system failed, not the input)."""

    def __init__(self) -> None:
        super().__init__(SCHEDULER_LOST)


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


def workers_for(tasks: int, jobs: int | None = None) -> int:
    """How many workers ``tasks`` tasks get: ``jobs`` (default: every core), no more than the tasks, at least one."""
    if jobs is not None and jobs < 1:
        raise ArgumentError("jobs", "must be at least 1")
    return max(1, min(jobs or default_jobs(), tasks))


@contextlib.contextmanager
def local_executor(jobs: int) -> Iterator[Executor]:
    """A pool of ``jobs`` single-threaded worker processes (fresh interpreters: no inherited threads or locks).

    The thread variables are in the workers' environment from the start: numpy reads OpenBLAS's thread
    count once, on import, before any initializer could set it.
    """
    with WorkerPool(jobs, env={**os.environ, **dict.fromkeys(THREAD_VARIABLES, "1")}) as pool:
        yield pool


@contextlib.contextmanager
def dask_executor(jobs: int, scheduler: str | None) -> Iterator[Executor]:
    """A Dask executor: on the cluster at ``scheduler`` (tcp://host:port), else on a LocalCluster of ``jobs`` workers.

    Workers must see the same file system as this process (they write the run directories).
    """
    try:
        from distributed import Client, LocalCluster  # optional extra (biped-sim[dask])
    except ImportError:
        raise ArgumentError("executor", "dask needs the optional extra: pip install 'biped-sim[dask]'") from None
    with contextlib.ExitStack() as stack:
        stack.enter_context(_client_log_quiet())
        if scheduler:
            try:
                client = stack.enter_context(Client(scheduler, timeout="10s"))
            except (OSError, TimeoutError, ValueError, TypeError) as exc:  # unreachable, or not an address at all
                reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise ArgumentError("scheduler", f"cannot connect to {scheduler!r}: {reason}") from None
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
        except BaseException as exc:
            lost = client.status != "running"  # the client closed, or trying to reconnect: its scheduler went away
            if lost and not isinstance(exc, KeyboardInterrupt | SystemExit | GeneratorExit):
                raise SchedulerLostError from None
            raise
        finally:
            executor.shutdown(wait=False)


@contextlib.contextmanager
def _client_log_quiet() -> Iterator[None]:
    """Dask's client and tornado log a lost scheduler's closed connections as errors with tracebacks on stderr: the
    command says it in its own one line (:class:`SchedulerLostError`) instead."""
    loggers = [logging.getLogger(name) for name in QUIET_LOGGERS]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


def check_executor(kind: str, scheduler: str | None = None) -> None:
    """ArgumentError unless ``kind`` is 'local' or 'dask' (and a ``scheduler`` comes with 'dask' only)."""
    if kind not in EXECUTORS:
        raise ArgumentError("executor", f"unknown executor {quote(kind)}; expected local or dask")
    if kind == "local" and scheduler:
        raise ArgumentError("scheduler", "only used with the dask executor")


@contextlib.contextmanager
def make_executor(kind: str, jobs: int, scheduler: str | None = None) -> Iterator[Executor]:
    """The executor ``kind``: 'local' (processes) or 'dask' (:func:`check_executor`)."""
    check_executor(kind, scheduler)
    if kind == "local":
        with local_executor(jobs) as executor:
            yield executor
    else:
        with dask_executor(jobs, scheduler) as executor:
            yield executor


@contextlib.contextmanager
def study_executor(kind: str, jobs: int, scheduler: str | None = None) -> Iterator[Executor | None]:
    """A study's executor: None (run in this process, no pool) for one local job, else :func:`make_executor`'s.

    Studies take ``executor: Executor | None`` and run serially on None: one job gains nothing from a
    pool and would pay its start-up and each worker's compilation.
    """
    check_executor(kind, scheduler)
    if kind == "local" and jobs == 1:
        yield None
        return
    with make_executor(kind, jobs, scheduler) as executor:
        yield executor
