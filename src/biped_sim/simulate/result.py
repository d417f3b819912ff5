"""One result type for every run, compliant or rigid: status, summary, steps, channels, and ``write()``.

The two kinds of run differ in what they measure (contact and constraints against impacts), not in how
they are used: the CLI, the sweep runner and the storage layer see only :class:`RunResult`. Derived
channels (and a compliant run's summary) are computed the first time they are asked for and cached, so that
a study reading the steps computes no channel, and the summary, the trajectory file and the figures never
compute one twice.
"""

from __future__ import annotations

import math
import time
from abc import ABC, abstractmethod
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import Config
from biped_sim.io.run_files import TrajectoryFile, write_run_directory
from biped_sim.measure.steps import StepAccess, StepTable, steps_csv


def wall_deadline(config: Config) -> float:
    """``time.monotonic()`` past which a run ends with status 'timeout' (inf without simulation.max_wall_time)."""
    budget = config.simulation.max_wall_time
    return math.inf if budget is None else time.monotonic() + budget


def ordered_pushes(config: Config) -> list[tuple[float, np.ndarray]]:
    """``simulation.pushes`` as (time, impulse [px, py]) in time order (pushes at one time in config order)."""
    pushes = sorted(config.simulation.pushes, key=lambda push: push.time)
    return [(push.time, np.array(push.impulse, dtype=np.float64)) for push in pushes]


def push_summary(config: Config, applied: list[dict[str, float]]) -> dict[str, Any]:
    """The summary's ``pushes`` (only in a run that has any): each applied push's time, impulse and what the run
    measured of it (``applied``, in time order: its work, the kinetic energy jump, and so on). A run that fell or
    stopped before a push's time lists fewer pushes than its config."""
    if not config.simulation.pushes:
        return {}
    pushes = ordered_pushes(config)
    return {
        "pushes": [
            {"time": at, "impulse": impulse.tolist(), **{key: float(value) for key, value in measured.items()}}
            for (at, impulse), measured in zip(pushes, applied, strict=False)
        ]
    }


class RunResult(StepAccess, ABC):
    """A simulated run and what it measured (see :class:`~biped_sim.simulate.compliant.CompliantRunResult`
    and :class:`~biped_sim.simulate.rigid.RigidRunResult`)."""

    config: Config
    status: str  # 'walking', 'fell', 'diverged' or 'timeout'
    status_reason: str | None
    t_final: float  # the last simulated time
    steps: StepTable
    wall_time_s: float
    summary: dict[str, Any]

    def unit(self, si_unit: str) -> str:
        """This run's unit for an SI unit (compliant runs are SI throughout)."""
        return si_unit

    @abstractmethod
    def trajectory(self) -> TrajectoryFile:
        """The content of trajectory.h5."""

    @abstractmethod
    def energy_dissipated(self) -> dict[str, float]:
        """The summary's ``energy_dissipated``: the work dissipated over the run, by mechanism."""

    @abstractmethod
    def peak_normal_force(self) -> float | None:
        """The summary's ``peak_normal_force``: the largest normal contact force (None: none measured)."""

    @abstractmethod
    def integrity_text(self) -> str:
        """One clause on the model's own check: the constraint violation, or the impact losses."""

    def __repr__(self) -> str:
        """One line for a notebook: the status, the strikes, the gait (from the step table, so it computes no
        channel), e.g. ``<RunResult walking: 7 heel strikes in 3.000 s, mean period 0.4395 s, 0.624 m/s>``."""
        steps = self.step_summary()
        nondimensional = self.unit("s") != "s"  # the simplest walker's (g = l = 1)
        s, speed = ("", "") if nondimensional else (" s", " m/s")
        text = f"<RunResult {self.status}: {steps['n_steps']} heel strikes in {self.t_final:.3f}{s}"
        if steps["mean_step_period"] is not None:
            text += f", mean period {steps['mean_step_period']:.4f}{s}, {steps['mean_speed']:.3g}{speed}"
        if nondimensional:
            text += ", g = l = 1"
        return text + (f" ({self.status_reason})>" if self.status_reason else ">")

    def write(self, out_dir: str | Path) -> None:
        """Write trajectory.h5, steps.csv, config.yaml and summary.json into ``out_dir`` (each atomically,
        summary.json last)."""
        write_run_directory(
            Path(out_dir),
            self.trajectory(),
            config_yaml=self.config.to_yaml(),
            config_hash=self.config.hash(),
            status=self.status,
            steps_csv=steps_csv(self.steps, self.unit),
            summary=self.summary,
        )
