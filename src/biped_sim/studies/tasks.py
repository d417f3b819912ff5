"""A study's tasks on an executor: results as they come, or computed in this process when there is none."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Executor, Future, as_completed
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")


def results_as_done(function: Callable[[T], R], tasks: Iterable[T], executor: Executor | None) -> Iterator[R]:
    """``function(task)`` of every task: from ``executor`` as each finishes, or in order here when it is None."""
    if executor is None:
        yield from map(function, tasks)
        return
    futures: list[Future[R]] = [executor.submit(function, task) for task in tasks]
    for future in as_completed(futures):
        yield future.result()
