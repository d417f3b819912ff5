"""Basins of attraction: which starts on a grid over two initial-state keys walk, converge to the gait, or fall.

Every cell of the grid (two ``simulation.initial`` keys, the others as in the config) is walked for K steps:

* ``dynamics: rigid``: K strikes of the compiled rigid step map (:mod:`biped_sim.rigid.compiled`) from the
  cell's post-impact state; a fall or a stall (no strike: the walker rocked back) ends it;
* ``dynamics: compliant``: a compliant run that stops after K heel strikes (``simulation.max_steps``) or a fall.

A cell *walks* when it takes all K steps; it *converges* when, besides, its last state is within
a tolerance (``--tolerance``, default ``CONVERGED_TOLERANCE``; max over the four leg angles and rates) of the
period-1 gait: the rigid walker's
post-impact fixed point, the compliant walker's touchdown state. A cell that falls records after how many steps.

One axis may be a named parameter of the walker (``walker.parameters.NAME``, a preset's field or a described
walker's parameter) instead of an initial-state key: the grid is then the basin's slice along the other key for
each value of the parameter, every cell walked by the walker with that value, and a cell converges when it
ends near the gait of its own parameter value (each value's gait found from the config's start, as the
config's own; a value with none has no converged cells). Two parameters are a sweep, not a basin.

The slice: for the simplest walker over stance_angle and stance_rate, the swing leg starts as a heel strike
leaves it (Garcia's relations phi = 2 theta, phidot = thetadot (1 - cos 2 theta), i.e. swing_angle = -theta,
swing_rate = thetadot cos 2 theta), so the map is Schwab and Wisse's post-impact section. For every other
walker or pair of keys, the two keys vary and the other two stay as configured (a slice of the full
state space through the config's start, not a section). A walker in space walks its rigid step map on its
Poincare section, two section coordinates the axes (:mod:`biped_sim.studies.space_basin`).

Cells run in chunks of one grid row on an executor (the sweep's local pool or Dask); each finished row is
recorded atomically in ``DIR/cells/`` under a key of the resolved config, the grid and K, so a rerun of the
same basin skips the rows already done.
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import LEG_KEYS, Config, derive
from biped_sim.config.schema import MAX_STEPS
from biped_sim.config.space_description import SPACE_STATE_KEYS
from biped_sim.config.walker_registry import capabilities, require_study
from biped_sim.errors import ArgumentError, ConfigError, quote
from biped_sim.io.atomic import write_json_atomic
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import STRIKE, walk_starts
from biped_sim.rigid.limit_cycle import LimitCycle, StepFailedError
from biped_sim.simulate.budget import check_run_count
from biped_sim.studies.limit_cycle import limit_cycle
from biped_sim.studies.space_basin import basin_keys, space_cells, space_gait
from biped_sim.studies.tasks import results_as_done

KEY_PREFIX = "simulation.initial."
PARAMETER_PREFIX = "walker.parameters."
DEFAULT_STEPS = 30
CONVERGED_TOLERANCE = 1e-4  # rad and rad/s (the simplest walker: nondimensional)
FELL, WALKS, CONVERGED = 0, 1, 2
OUTCOMES = ("fell", "walks", "converged")
CELLS_DIR = "cells"
SPACE_NOTE = "eight post-strike keys, on level ground heading 0"
SPACE_SLICE = " (or the gait's), on the walker in space's Poincare section: the hinge angle from the trailing foot"
STEP_TIME_ALLOWANCE = 10.0  # a compliant cell's t_end: this many sqrt(l / g) per step (it stops at K strikes)


@dataclass(frozen=True)
class GridAxis:
    """One axis of the grid: an initial-state key (or ``walker.parameters.NAME``) and N evenly spaced values from LO
    to HI."""

    key: str
    lo: float
    hi: float
    n: int

    @property
    def values(self) -> np.ndarray:
        return np.linspace(self.lo, self.hi, self.n)

    @property
    def is_parameter(self) -> bool:
        """Whether the axis is a named parameter of the walker (not an initial-state key)."""
        return self.key.startswith(PARAMETER_PREFIX)

    @property
    def config_key(self) -> str:
        """The axis's full dotted config key."""
        return self.key if self.is_parameter else KEY_PREFIX + self.key


def parse_axis(name: str, text: str) -> GridAxis:
    """``KEY=LO:HI:N`` (KEY a simulation.initial key, with or without the prefix, or ``walker.parameters.NAME``);
    ArgumentError naming ``name`` (the axis: ``x`` or ``y``)."""
    key, sep, rest = text.partition("=")
    key = key.strip().removeprefix(KEY_PREFIX)
    parameter = key.startswith(PARAMETER_PREFIX) and len(key) > len(PARAMETER_PREFIX)
    if not sep or not (parameter or key.endswith(("_angle", "_rate")) or key in SPACE_STATE_KEYS):
        raise ArgumentError(
            name,
            f"expected KEY=LO:HI:N with KEY a key of {KEY_PREFIX[:-1]} ({', '.join(LEG_KEYS)}, ...) or "
            f"{PARAMETER_PREFIX}NAME",
        )
    parts = rest.split(":")
    try:
        lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
    except (IndexError, ValueError):
        raise ArgumentError(name, f"{quote(rest)}: expected LO:HI:N (two numbers and a count)") from None
    if len(parts) != 3 or not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo or n < 2:
        raise ArgumentError(name, f"{quote(rest)}: need finite LO < HI and N >= 2")
    return GridAxis(key, lo, hi, n)


@dataclass(frozen=True)
class BasinSpec:
    """What to map: the config, the two axes and K."""

    config: Config
    x: GridAxis
    y: GridAxis
    steps: int = DEFAULT_STEPS
    tolerance: float = CONVERGED_TOLERANCE

    def __post_init__(self) -> None:
        require_study(self.config.walker.kind, "basin", "a basin walks the planar rigid step map from a grid of starts")
        if self.x.key == self.y.key:
            raise ArgumentError("y", f"the same key as the x axis ({self.x.key})")
        if self.x.is_parameter and self.y.is_parameter:
            raise ArgumentError("y", "two parameters make a sweep (biped-sim sweep): one axis is an initial-state key")
        space = self.config.in_space
        if space and self.config.dynamics != "rigid":
            raise ConfigError("dynamics", "a basin of a walker in space walks its rigid step map (dynamics: rigid)")
        if isinstance(self.config.simulation.initial, str) and not space:
            raise ConfigError("simulation.initial", "a basin varies the configured initial state: give its keys")
        for axis, grid in (("x", self.x), ("y", self.y)):
            if grid.is_parameter:
                self._check_parameter(axis, grid)
            elif grid.key not in (keys := basin_keys(self.config)):
                raise ArgumentError(axis, f"{grid.key} is not a key of simulation.initial ({', '.join(keys)})")
        check_run_count(self.x.n * self.y.n, "y", "cells (x times y values)")
        if not 1 <= self.steps <= MAX_STEPS:
            raise ArgumentError("steps", f"must be from 1 to {MAX_STEPS:.0e}")
        if not (math.isfinite(self.tolerance) and self.tolerance > 0):
            raise ArgumentError("tolerance", "must be a positive number")

    def _check_parameter(self, axis: str, grid: GridAxis) -> None:
        """ArgumentError naming ``axis`` when the walker has no such parameter or refuses an end of its range."""
        for value in (grid.lo, grid.hi):
            try:
                derive(self.config, {grid.key: value})
            except ConfigError as exc:
                raise ArgumentError(axis, f"{grid.key}={value:g}: {exc}") from None

    @property
    def parameter_axis(self) -> GridAxis | None:
        """The axis that is a named parameter, if one is."""
        return next((grid for grid in (self.x, self.y) if grid.is_parameter), None)

    def cell_config(self, x_value: float, y_value: float) -> Config:
        """The config a cell's walker has: the config's own, or with the parameter axis's value."""
        if self.x.is_parameter:
            return derive(self.config, {self.x.key: float(x_value)})
        if self.y.is_parameter:
            return derive(self.config, {self.y.key: float(y_value)})
        return self.config

    @property
    def garcia_section(self) -> bool:
        """The simplest walker over stance angle and rate: the swing leg as a heel strike leaves it."""
        light_legs = capabilities(self.config.walker.kind).light_legs
        return light_legs and {self.x.key, self.y.key} == {"stance_angle", "stance_rate"}

    def key(self) -> str:
        """What a finished row was computed for (resume only reuses rows of the same basin)."""
        text = json.dumps(
            [self.config.hash(), self.x.__dict__, self.y.__dict__, self.steps, self.tolerance], sort_keys=True
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def cell_legs(self, x_value: float, y_value: float) -> dict[str, float]:
        """The initial-state keys of the cell at (x_value, y_value)."""
        initial = self.config.simulation.initial
        legs = {} if isinstance(initial, str) else dict(initial) if isinstance(initial, dict) else initial.model_dump()
        for grid, value in ((self.x, x_value), (self.y, y_value)):
            if not grid.is_parameter:
                legs[grid.key] = float(value)
        if self.garcia_section:
            theta, rate = legs["stance_angle"], legs["stance_rate"]
            legs["swing_angle"], legs["swing_rate"] = -theta, rate * math.cos(2.0 * theta)
        return legs


@dataclass(frozen=True)
class RowTask:
    """One grid row (fixed y value) to walk in a worker."""

    spec: BasinSpec
    row: int
    targets: list[dict[str, float] | None]  # per column, the gait state converged cells end near (None: no gait)


def _close(legs: dict[str, float], target: dict[str, float] | None, tolerance: float) -> bool:
    return target is not None and max(abs(legs[k] - target[k]) for k in target) <= tolerance


def _rigid_row(task: RowTask, cells: list[tuple[Config, dict[str, float]]]) -> tuple[list[int], list[int]]:
    """Each cell walked by the rigid step map: one batch per walker (the row's, or each cell's own parameter)."""
    outcome, taken = [], []
    for config, batch in _batches(cells):
        walker = rigid_walker(config)
        walked = walk_starts(walker, np.array([walker.state_from_legs(legs) for legs in batch]), task.spec.steps)
        for status, last in zip(walked.status, walked.last, strict=True):
            target = task.targets[len(outcome)]
            if status != STRIKE:
                outcome.append(FELL)
            else:
                outcome.append(CONVERGED if _close(walker.legs_state(last), target, task.spec.tolerance) else WALKS)
        taken += [int(s) for s in walked.steps]
    return outcome, taken


def _space_row(task: RowTask, cells: list[tuple[Config, dict[str, float]]]) -> tuple[list[int], list[int]]:
    """Each cell walked by the step map in space on its section (:mod:`biped_sim.studies.space_basin`)."""
    spec, target = task.spec, task.targets[0]  # a walker in space has no parameter axis: one gait
    walked = space_cells(spec.config, [legs for _, legs in cells], target, spec.steps)
    outcome = [
        FELL if last is None else CONVERGED if _close(last, target, spec.tolerance) else WALKS for _, last in walked
    ]
    return outcome, [taken for taken, _ in walked]


def _batches(cells: list[tuple[Config, dict[str, float]]]) -> list[tuple[Config, list[dict[str, float]]]]:
    """The cells in runs of one config, in order."""
    batches: list[tuple[Config, list[dict[str, float]]]] = []
    for config, legs in cells:
        if batches and batches[-1][0] is config:
            batches[-1][1].append(legs)
        else:
            batches.append((config, [legs]))
    return batches


def _compliant_row(task: RowTask, cells: list[tuple[Config, dict[str, float]]]) -> tuple[list[int], list[int]]:
    from biped_sim.simulate import simulate  # the compliant engine: imported only by workers that need it

    steps = task.spec.steps
    outcome, taken = [], []
    for config, legs in cells:
        t_end = STEP_TIME_ALLOWANCE * steps * math.sqrt(config.walker.leg_length / config.gravity)
        try:
            result = simulate(derive(config, {"simulation.initial": legs, "simulation.max_steps": steps,
                                              "simulation.t_end": t_end}))  # fmt: skip
        except ConfigError:  # the walker cannot start there (e.g. a foot below the ground): it falls at once
            outcome.append(FELL)
            taken.append(0)
            continue
        strikes = len(result.steps.strike_time)
        table = result.steps
        last = {k: float(getattr(table, k)[-1]) for k in LEG_KEYS} if strikes else {}
        if result.status != "walking" or strikes < steps:
            outcome.append(FELL)
        else:
            outcome.append(CONVERGED if _close(last, task.targets[len(outcome)], task.spec.tolerance) else WALKS)
        taken.append(min(strikes, steps))
    return outcome, taken


def basin_row(task: RowTask) -> dict[str, Any]:
    """Walk every cell of one row (runs in a worker): {'row', 'outcome', 'steps'}."""
    spec = task.spec
    y_value = spec.y.values[task.row]
    row_config = spec.cell_config(spec.x.lo, y_value) if not spec.x.is_parameter else None
    cells = [(row_config or spec.cell_config(x, y_value), spec.cell_legs(x, y_value)) for x in spec.x.values]
    row = _rigid_row if spec.config.dynamics == "rigid" else _compliant_row
    row = _space_row if spec.config.in_space else row  # rigid (BasinSpec)
    outcome, steps = row(task, cells)
    return {"row": task.row, "outcome": outcome, "steps": steps}


@dataclass
class Basin:
    """A mapped basin: outcome and steps per cell (rows: y values, columns: x values) and the gait."""

    spec: BasinSpec
    outcome: np.ndarray  # (ny, nx) FELL, WALKS or CONVERGED
    steps: np.ndarray  # (ny, nx) steps taken (K for cells that walk)
    cycle: LimitCycle | None
    wall_time_s: float = 0.0
    rows_reused: int = 0
    notes: list[str] = field(default_factory=list)
    parameter_gaits: list[dict[str, float] | None] = field(default_factory=list)  # per value of a parameter axis

    @property
    def fixed_point(self) -> dict[str, float] | None:
        return gait_target(self.spec, self.cycle)

    def to_json(self) -> dict[str, Any]:
        """The document of ``biped-sim basin --json``."""
        n_cells = int(self.outcome.size)
        return {
            "walker": self.spec.config.walker.kind,
            "dynamics": self.spec.config.dynamics,
            "x": self.spec.x.__dict__,
            "y": self.spec.y.__dict__,
            "steps": self.spec.steps,
            "n_cells": n_cells,
            "fraction_walking": float(np.count_nonzero(self.outcome != FELL)) / n_cells,
            "fraction_converged": float(np.count_nonzero(self.outcome == CONVERGED)) / n_cells,
            "converged_tolerance": self.spec.tolerance,
            "fixed_point": self.fixed_point,
            "parameter_gaits": self.parameter_gaits,
            "wall_time_s": self.wall_time_s,
            "rows_reused": self.rows_reused,
            "notes": self.notes,
        }


def gait_target(spec: BasinSpec, cycle: LimitCycle | None) -> dict[str, float] | None:
    """The gait state converged cells end near: rigid post-impact fixed point, compliant touchdown."""
    if cycle is None or not cycle.converged:
        return None
    return cycle.fixed_point if spec.config.dynamics == "rigid" else cycle.touchdown


def find_gait(config: Config) -> LimitCycle | None:
    """The period-1 gait from the config's start (None when there is none to find); a walker in space's near its
    start when one is given (:func:`~biped_sim.studies.space_basin.space_gait`)."""
    try:
        return space_gait(config) if config.in_space else limit_cycle(config)
    except (ConfigError, StepFailedError):
        return None


def _parameter_gait(task: tuple[BasinSpec, int]) -> tuple[int, dict[str, float] | None]:
    """(i, the gait state of the parameter axis's i-th value) (runs in a worker)."""
    spec, i = task
    grid = spec.parameter_axis
    assert grid is not None
    return i, gait_target(spec, find_gait(derive(spec.config, {grid.key: float(grid.values[i])})))


def parameter_gaits(spec: BasinSpec, executor: Executor | None) -> list[dict[str, float] | None]:
    """The gait state of each value of the parameter axis, on ``executor`` ([] without a parameter axis)."""
    grid = spec.parameter_axis
    if grid is None:
        return []
    gaits: list[dict[str, float] | None] = [None] * grid.n
    for i, gait in results_as_done(_parameter_gait, [(spec, i) for i in range(grid.n)], executor):
        gaits[i] = gait
    return gaits


def column_targets(spec: BasinSpec, row: int, target: dict[str, float] | None, gaits: list[Any]) -> list[Any]:
    """The gait each cell of ``row`` converges to: its parameter value's, or the config's."""
    if spec.x.is_parameter:
        return list(gaits)
    return [gaits[row] if spec.y.is_parameter else target] * spec.x.n


def _row_path(out_dir: Path, row: int) -> Path:
    return out_dir / CELLS_DIR / f"row_{row:04d}.json"


def finished_rows(spec: BasinSpec, out_dir: Path) -> dict[int, dict[str, Any]]:
    """Rows recorded by an earlier run of the same basin (other basins' or unreadable files are ignored)."""
    done = {}
    for row in range(spec.y.n):
        path = _row_path(out_dir, row)
        try:
            record = json.loads(path.read_text())
        except (OSError, ValueError):
            continue
        if record.get("key") == spec.key() and len(record.get("outcome", [])) == spec.x.n:
            done[row] = record
    return done


def _rows(
    spec: BasinSpec, pending: list[int], target: dict[str, float] | None, gaits: list[Any], executor: Executor | None
) -> Iterator[dict[str, Any]]:
    """The finished rows' records as they come: from ``executor``, or computed here when it is None."""
    tasks = [RowTask(spec, row, column_targets(spec, row, target, gaits)) for row in pending]
    return results_as_done(basin_row, tasks, executor)


def map_basin(
    spec: BasinSpec,
    out_dir: Path | None,
    executor: Executor | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Basin:
    """Walk every cell of the grid, one task per row on ``executor`` (None: in this process); with ``out_dir``,
    finished rows are recorded in ``out_dir/cells`` as they come and reused by a rerun.
    ``progress(done, total)`` after each row."""
    clock = time.perf_counter()
    cycle = find_gait(spec.config)
    target = gait_target(spec, cycle)
    done = finished_rows(spec, out_dir) if out_dir is not None else {}
    pending = [row for row in range(spec.y.n) if row not in done]
    gaits = parameter_gaits(spec, executor)
    reused = len(done)
    if out_dir is not None:
        (out_dir / CELLS_DIR).mkdir(parents=True, exist_ok=True)
    for result in _rows(spec, pending, target, gaits, executor):
        record = {"key": spec.key(), **result}
        if out_dir is not None:
            write_json_atomic(_row_path(out_dir, record["row"]), record)
        done[record["row"]] = record
        if progress is not None:
            progress(len(done), spec.y.n)
    outcome = np.array([done[row]["outcome"] for row in range(spec.y.n)], dtype=np.int64)
    steps = np.array([done[row]["steps"] for row in range(spec.y.n)], dtype=np.int64)
    space = spec.config.in_space
    notes = [
        f"each cell walked up to {spec.steps} steps; converged: walked them all and ended within "
        f"{spec.tolerance:g} of the gait (max over the {SPACE_NOTE if space else 'four leg angles and rates'})",
        "slice: swing leg as a heel strike leaves it (Garcia's relations): Schwab and Wisse's post-impact section"
        if spec.garcia_section
        else "slice: the two keys vary, the other initial keys as configured" + (SPACE_SLICE if space else ""),
    ]
    if (grid := spec.parameter_axis) is not None:
        notes.append(f"each value of {grid.key} converges to its own gait, found from the config's start")
    if target is None and grid is None:
        notes.append("no period-1 gait found from the config's start: no cell counts as converged")
    return Basin(spec, outcome, steps, cycle, time.perf_counter() - clock, reused, notes, gaits)
