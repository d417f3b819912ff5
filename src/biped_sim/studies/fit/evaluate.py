"""Running a fit's simulations: cached by point, counted, in batches on an executor, checkpointed for resume.

An :class:`Evaluator` maps normalised points to :class:`~biped_sim.studies.fit.problem.Outcome` s, each run
as far as it is asked for (by default the last reference step; a stage that reads only the first targets asks
for fewer steps, and a run's first strikes do not depend on where it stops, so a longer run answers a shorter
request, and a run that ended before its last step, by a fall, answers any). The points of one batch that are
not yet known run together, on the executor when one is given (the sweep
layer's local pool or Dask: ``biped_sim.sweep.study_executor``), else here one by one. Every outcome is
kept, and with a ``checkpoint`` path written there atomically (at most every ``SAVE_INTERVAL_S`` and when
the evaluator closes, also on Ctrl-C): an interrupted fit or sampler run again with the same checkpoint
replays its finished evaluations from it instead of simulating them again. The optimizers and the sampler
are seeded, so the replay takes the same path. A checkpoint of another problem (config, reference,
parameters) is refused, naming the file.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.errors import ConfigError
from biped_sim.io.atomic import write_json_atomic
from biped_sim.studies.fit.problem import FitProblem, Outcome, simulate_outcome

SAVE_INTERVAL_S = 5.0
CHECKPOINT_FORMAT = "biped-sim fit evaluations 1"


def point_key(u: Sequence[float]) -> str:
    """The exact point as text (hex floats): a cache key that survives JSON."""
    return ",".join(float(x).hex() for x in np.asarray(u, dtype=float))


@dataclass
class Evaluator:
    """Runs evaluations of ``problem`` (cached by point, counted), serially or as batches on an executor."""

    problem: FitProblem
    executor: Executor | None = None
    checkpoint: Path | None = None
    progress: Callable[[Evaluator], None] | None = None
    cache: dict[str, Outcome] = field(default_factory=dict)
    reach: dict[str, int] = field(default_factory=dict)  # the model steps each cached outcome was run to
    evaluations: int = 0  # simulations run here
    replayed: int = 0  # outcomes read from the checkpoint when first asked for
    best_cost: float = float("inf")
    stage: str = ""
    _restored: set[str] = field(default_factory=set)
    _saved_at: float = 0.0

    def __post_init__(self) -> None:
        if self.checkpoint is not None and self.checkpoint.is_file():
            self._load(self.checkpoint)

    def _load(self, path: Path) -> None:
        try:
            data = json.loads(path.read_text())
            if data.get("format") != CHECKPOINT_FORMAT:
                raise ValueError("not a fit checkpoint")
            entries = {e["u"]: Outcome.from_json(e["outcome"]) for e in data["evaluations"]}
            reach = {e["u"]: int(e.get("steps", self.problem.model_steps)) for e in data["evaluations"]}
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ConfigError(
                str(path), f"unreadable checkpoint ({str(exc)[:80]}); remove it to start afresh"
            ) from None
        if data.get("problem") != self.problem.key():
            raise ConfigError(str(path), "checkpoint of another fit (config, reference or parameters differ)")
        self.cache.update(entries)
        self.reach.update(reach)
        self._restored = set(entries)

    def save(self) -> None:
        """Write the checkpoint (atomically), if there is one."""
        if self.checkpoint is None:
            return
        entries = [{"u": k, "outcome": outcome.to_json(), "steps": self.reach[k]} for k, outcome in self.cache.items()]
        doc = {"format": CHECKPOINT_FORMAT, "problem": self.problem.key(), "evaluations": entries}
        write_json_atomic(self.checkpoint, doc)
        self._saved_at = time.monotonic()

    def covers(self, key: str, steps: int) -> bool:
        """Whether the cached outcome at ``key`` answers a run to model step ``steps``: it went as far, or it ended
        before the step it was run to (a fall: a longer run ends the same way)."""
        outcome = self.cache.get(key)
        return outcome is not None and (self.reach[key] >= steps or outcome.strikes < self.reach[key])

    def outcomes(self, points: Sequence[Sequence[float]], steps: int | None = None) -> list[Outcome]:
        """The outcome at each point, run to model step ``steps`` (the last reference step by default); the points
        not yet known that far run together (in parallel on the executor)."""
        steps = self.problem.model_steps if steps is None else steps
        keys = [point_key(u) for u in points]
        todo = {k: np.asarray(u, dtype=float) for k, u in zip(keys, points, strict=True) if not self.covers(k, steps)}
        self.replayed += sum(1 for k in set(keys) if k in self._restored and k not in todo)
        self._restored.difference_update(keys)
        self._run(todo, steps)
        if todo and time.monotonic() - self._saved_at > SAVE_INTERVAL_S:
            self.save()
        out = [self.cache[k] for k in keys]
        for outcome in out:
            self.best_cost = min(self.best_cost, self.cost_of(outcome))
        if self.progress is not None and todo:
            self.progress(self)
        return out

    def _run(self, todo: dict[str, np.ndarray], steps: int) -> None:
        """Simulate the points ``todo`` (by key); those finished are cached even when the batch is interrupted
        (Ctrl-C, SIGTERM), so that the checkpoint written on the way out keeps them, in the batch's order."""
        done: dict[str, Outcome] = {}
        try:
            if self.executor is None or len(todo) < 2:
                for key, u in todo.items():
                    done[key] = simulate_outcome(self.problem.evaluation_data(u, steps))
            else:
                tasks = {
                    self.executor.submit(simulate_outcome, self.problem.evaluation_data(u, steps)): k
                    for k, u in todo.items()
                }
                for future in as_completed(tasks):
                    done[tasks[future]] = future.result()
        finally:
            self.cache.update((key, done[key]) for key in todo if key in done)
            self.reach.update((key, steps) for key in todo if key in done)
            self.evaluations += len(done)

    def cost_of(self, outcome: Outcome) -> float:
        r = self.problem.residuals(outcome)
        return 0.5 * float(r @ r)

    def residuals(self, u: np.ndarray, steps: int | None = None) -> np.ndarray:
        """The residuals at ``u`` (of a run to ``steps``: the targets beyond it are charged as missing)."""
        return self.problem.residuals(self.outcomes([u], steps)[0])

    def costs(self, points: Sequence[Sequence[float]]) -> list[float]:
        """Half the sum of squared residuals at each point (one batch)."""
        return [self.cost_of(o) for o in self.outcomes(points)]

    def cost_map(self, _func: Any, points: Any) -> list[float]:
        """A ``map(func, points)`` for scipy's differential_evolution ``workers``: the batch's costs."""
        return self.costs(list(points))

    def jacobian(self, u: np.ndarray, step: float, steps: int | None = None) -> np.ndarray:
        """Forward differences (backwards at the upper bound) of the residuals, the p shifted runs as one batch (runs
        to ``steps``, as :meth:`residuals`)."""
        u = np.asarray(u, dtype=float)
        deltas = np.where(u + step <= 1.0, step, -step)
        shifted = [u + deltas[j] * np.eye(len(u))[j] for j in range(len(u))]
        outcomes = self.outcomes([u, *shifted], steps)
        base = self.problem.residuals(outcomes[0])
        columns = [(self.problem.residuals(o) - base) / deltas[j] for j, o in enumerate(outcomes[1:])]
        return np.column_stack(columns)
