"""Step periods against a contact parameter under both impact-velocity memories (``contact.impact_memory``).

The study behind the choice of the default (docs/guide/contact.md, "Modelling choices to know"): for each value of a
numeric config key (restitution by default) and each memory, the first ``steps`` step periods (step 1
from the release to the first heel strike) and the number of rebounds (a touchdown of a foot less than
``contact.recontact_time`` after its own lift-off). Under ``touchdown`` every rebound resets the
remembered impact velocity to its own few mm/s, so the periods jump where a rebound appears; under
``impact`` they do not. :func:`largest_jump` is the figure of merit: the largest change of any step
period between neighbouring values.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import Any

import numpy as np

from biped_sim.config import Config, derive
from biped_sim.simulate import simulate

MEMORIES = ("touchdown", "impact")


@dataclass(frozen=True)
class MemoryScan:
    """``periods[memory]``: (values x steps) [s], NaN where the walker stopped; ``rebounds[memory]``: per value."""

    key: str
    values: np.ndarray
    steps: int
    periods: dict[str, np.ndarray]
    rebounds: dict[str, np.ndarray]

    def largest_jump(self, memory: str) -> float:
        """The largest |change| of a step period between neighbouring values [s] (NaN-free steps only)."""
        change = np.abs(np.diff(self.periods[memory], axis=0))
        return float(np.nanmax(change)) if np.isfinite(change).any() else float("nan")


def count_rebounds(contact_log: np.ndarray, within: float) -> int:
    """Touchdowns less than ``within`` seconds after the same foot's lift-off (contact-log rows)."""
    count = 0
    for foot in np.unique(contact_log[:, 1]):
        rows = contact_log[contact_log[:, 1] == foot]
        for before, after in itertools.pairwise(rows):
            count += int(before[2] < 0 < after[2] and after[0] - before[0] < within)
    return count


def _periods_and_rebounds(config: Config, steps: int) -> tuple[list[float], int]:
    result = simulate(config)
    times = np.concatenate([[0.0], result.summary["step_times"][:steps]])
    periods = np.full(steps, np.nan)
    periods[: len(times) - 1] = np.diff(times)
    return periods.tolist(), count_rebounds(result.run.contact_log, config.contact.recontact_time)


def scan_config(config: Config, key: str, value: float, memory: str, steps: int) -> Config:
    """The config one scan point runs: ``key`` = value, the memory, stopping after ``steps`` heel strikes."""
    return derive(
        config,
        {key: value, "contact.impact_memory": memory, "simulation.max_steps": steps, "output.sample_rate": 10.0},
    )


def memory_scan(
    config: Config,
    values: Sequence[float],
    key: str = "contact.restitution",
    steps: int = 7,
    executor: Executor | None = None,
) -> MemoryScan:
    """Scan ``key`` over ``values`` under both memories (runs on ``executor`` when given, else here)."""
    tasks = [(scan_config(config, key, float(v), memory, steps), steps) for memory in MEMORIES for v in values]
    outcomes: list[Any]
    if executor is None:
        outcomes = [_periods_and_rebounds(*task) for task in tasks]
    else:
        outcomes = [f.result() for f in [executor.submit(_periods_and_rebounds, *task) for task in tasks]]
    n = len(values)
    periods = {m: np.array([o[0] for o in outcomes[i * n : (i + 1) * n]]) for i, m in enumerate(MEMORIES)}
    rebounds = {m: np.array([o[1] for o in outcomes[i * n : (i + 1) * n]]) for i, m in enumerate(MEMORIES)}
    return MemoryScan(key, np.asarray(values, dtype=float), steps, periods, rebounds)
