"""A pool of worker processes in which a dead worker fails only its own task.

``concurrent.futures.ProcessPoolExecutor`` marks every queued task failed (``BrokenProcessPool``) when
one worker dies, and hands tasks to its workers ahead of time, so that they go on running after a
cancel. :class:`WorkerPool` keeps what a sweep needs instead:

* each worker holds at most one task; a task that has not been handed out can still be cancelled;
* a worker that dies (``kill -9``, a crash in native code) fails its own task with :class:`WorkerDiedError`
  (``worker died (signal 9)``); the next task starts a new worker;
* ``shutdown(cancel_futures=True)`` cancels the queue and ends the running workers at once (Ctrl-C);
* workers run in their own session, so a Ctrl-C at the terminal reaches only the parent (no worker
  traceback, no task half-run by an interrupt), and on Linux the kernel kills them when the pool's
  thread ends (``PR_SET_PDEATHSIG``), e.g. when the parent is killed: no orphan workers.

A worker is ``python -c ...`` with the parent's ``sys.path``; tasks and results travel as pickles over its
stdin and stdout (anything a task prints goes to stderr). One dispatcher thread starts the workers, hands
out tasks and collects results, so the parent-death signal is tied to it.
"""

from __future__ import annotations

import collections
import contextlib
import ctypes
import os
import pickle
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from concurrent.futures import CancelledError, Executor, Future
from dataclasses import dataclass, field
from multiprocessing.connection import wait
from typing import IO, Any

PR_SET_PDEATHSIG = 1  # linux/prctl.h


class WorkerDiedError(RuntimeError):
    """The worker process running a task ended without answering."""


def death_message(returncode: int) -> str:
    """'worker died (signal 9)' or 'worker died (exit code 1)'."""
    return f"worker died (signal {-returncode})" if returncode < 0 else f"worker died (exit code {returncode})"


def die_with_parent(parent: int) -> None:
    """Linux: have the kernel SIGKILL this process when the thread that started it ends (with its process).

    Elsewhere prctl is missing and a worker ends when its stdin closes, after its current task.
    """
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != parent:  # the parent died before the request took effect
            os._exit(1)


def worker_main(parent: int) -> None:
    """A worker process: run ``(function, args, kwargs)`` pickles from stdin, answer ``(ok, value)`` on stdout."""
    die_with_parent(parent)
    inbox = sys.stdin.buffer
    outbox = os.fdopen(os.dup(1), "wb")  # the result stream; file descriptor 1 becomes stderr, so that
    os.dup2(2, 1)  # nothing a task prints (from Python or from C) can corrupt it
    sys.stdout = sys.stderr
    while True:
        try:
            task = pickle.load(inbox)
        except EOFError:  # the pool closed our stdin (shutdown) or went away
            return
        fn, args, kwargs = task
        try:
            reply: tuple[bool, Any] = (True, fn(*args, **kwargs))
        except Exception as exc:
            reply = (False, exc)
        try:
            data = pickle.dumps(reply)
        except Exception as exc:  # an unpicklable result or exception: send its text
            data = pickle.dumps((False, RuntimeError(f"{type(exc).__name__}: {exc}")))
        outbox.write(data)
        outbox.flush()


@dataclass
class _Job:
    future: Future[Any]
    call: tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]]
    started: bool = False


@dataclass
class _Worker:
    process: subprocess.Popen[bytes]
    job: _Job | None = None

    @property
    def stdin(self) -> IO[bytes]:
        assert self.process.stdin is not None
        return self.process.stdin

    @property
    def stdout(self) -> IO[bytes]:
        assert self.process.stdout is not None
        return self.process.stdout


@dataclass
class _State:
    queue: collections.deque[_Job] = field(default_factory=collections.deque)
    workers: list[_Worker] = field(default_factory=list)
    closed: bool = False  # no more submissions; finish the queue, then stop
    stopping: bool = False  # cancel the queue and end running workers now


class WorkerPool(Executor):
    """An Executor over ``jobs`` worker processes (see the module docstring); ``env`` is the workers' environment."""

    def __init__(self, jobs: int, env: dict[str, str] | None = None) -> None:
        self._jobs = jobs
        self._env = env
        self._state = _State()
        self._finished = False  # the dispatcher has ended and closed its wake-up pipe
        self._lock = threading.RLock()  # a future's done-callback, run by the dispatcher, may submit again
        self._wake_read, self._wake_write = os.pipe()
        os.set_blocking(self._wake_write, False)  # a full pipe already holds a wake-up
        self._thread = threading.Thread(target=self._run, name="biped-sim-worker-pool", daemon=True)
        self._thread.start()

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future[Any]:
        """Queue ``fn(*args, **kwargs)`` for the next free worker."""
        job = _Job(Future(), (fn, args, kwargs))
        with self._lock:
            if self._state.closed:
                raise RuntimeError("cannot submit to a pool that is shut down")
            self._state.queue.append(job)
        self._wake()
        return job.future

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop taking tasks; ``cancel_futures`` also cancels the queue and ends the running workers at once."""
        with self._lock:
            self._state.closed = True
            self._state.stopping = self._state.stopping or cancel_futures
        self._wake()
        if wait:
            self._thread.join()

    def __exit__(self, exc_type: object, *rest: object) -> None:
        """Leaving a ``with`` block on an exception (e.g. Ctrl-C) stops the pool instead of draining its queue."""
        self.shutdown(wait=True, cancel_futures=exc_type is not None)

    def _wake(self) -> None:
        """Interrupt the dispatcher's wait (new task, shutdown)."""
        with self._lock, contextlib.suppress(BlockingIOError):
            if not self._finished:
                os.write(self._wake_write, b"x")

    def _start_worker(self) -> _Worker:
        code = f"import sys; sys.path[:] = {sys.path!r}; import biped_sim.sweep.pool as p; p.worker_main({os.getpid()})"
        process = subprocess.Popen(
            [sys.executable, "-c", code],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=self._env,
            start_new_session=True,
        )
        worker = _Worker(process)
        self._state.workers.append(worker)
        return worker

    def _hand_out(self) -> None:
        """Give queued tasks to idle workers, starting workers up to ``jobs`` (lock held)."""
        state = self._state
        while state.queue:
            idle = [w for w in state.workers if w.job is None]
            if not idle and len(state.workers) >= self._jobs:
                return
            job = state.queue.popleft()
            if not job.started and not job.future.set_running_or_notify_cancel():
                continue  # cancelled while queued
            job.started = True
            try:
                data = pickle.dumps(job.call)
            except Exception as exc:
                job.future.set_exception(exc)
                continue
            try:
                worker = idle[0] if idle else self._start_worker()
            except OSError as exc:  # cannot start a process (e.g. out of memory): the task fails
                job.future.set_exception(exc)
                continue
            try:
                worker.stdin.write(data)
                worker.stdin.flush()
            except OSError:  # the idle worker had died: drop it, the task goes back to the head of the queue
                self._forget(worker)
                state.queue.appendleft(job)
                continue
            worker.job = job

    def _forget(self, worker: _Worker) -> None:
        """Remove a worker that has ended, failing its task (unless the pool is stopping it)."""
        self._state.workers.remove(worker)
        returncode = worker.process.wait()
        for stream in (worker.stdin, worker.stdout):
            with contextlib.suppress(OSError):
                stream.close()
        if worker.job is not None:
            failure = CancelledError() if self._state.stopping else WorkerDiedError(death_message(returncode))
            worker.job.future.set_exception(failure)

    def _collect(self, worker: _Worker) -> None:
        """Read the answer of a worker whose stdout is readable (an end of file means it died)."""
        try:
            ok, value = pickle.load(worker.stdout)
        except (EOFError, OSError, pickle.UnpicklingError):
            self._forget(worker)
            return
        job, worker.job = worker.job, None
        if job is not None:
            if ok:
                job.future.set_result(value)
            else:
                job.future.set_exception(value)

    def _stop_workers(self) -> None:
        """End every worker: running ones are killed when stopping, idle ones see their stdin close."""
        state = self._state
        for job in state.queue:
            if not job.future.cancel():  # handed out once already (its worker had died): running
                job.future.set_exception(CancelledError())
        state.queue.clear()
        for worker in list(state.workers):
            if worker.job is not None or state.stopping:
                worker.process.kill()
            with contextlib.suppress(OSError):
                worker.stdin.close()
            self._forget(worker)

    def _run(self) -> None:
        """The dispatcher thread: hand out tasks, collect answers, notice dead workers, until shut down."""
        try:
            while True:
                with self._lock:
                    state = self._state
                    if not state.stopping:
                        self._hand_out()
                    busy = any(w.job is not None for w in state.workers)
                    if state.stopping or (state.closed and not state.queue and not busy):
                        break
                    watched: dict[int, _Worker] = {w.stdout.fileno(): w for w in state.workers}
                for ready in wait([self._wake_read, *watched]):
                    if ready == self._wake_read:
                        os.read(self._wake_read, 4096)
                    else:
                        with self._lock:
                            self._collect(watched[int(ready)])
        finally:
            with self._lock:
                self._state.closed = True
                self._stop_workers()
                self._finished = True
                os.close(self._wake_read)
                os.close(self._wake_write)
