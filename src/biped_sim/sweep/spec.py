"""Sweep files: their schema and their expansion into a list of resolved, validated run configs.

A sweep file names a base config and the axes to vary over any dotted config key::

    name: slopes_integrators
    base: ../round_foot_walker.yaml        # relative to this file
    set:                                   # fixed overrides for every run (optional)
      simulation.t_end: 10.0
    grid:                                  # Cartesian product of these axes
      ground.slope: {from: 0.015, to: 0.024, num: 4}
    zip:                                   # parallel lists: one more axis, moved together
      integrator.method: [dopri5, rk4]
      integrator.dt: [1.0e-4, 1.0e-4]
    output: results/sweeps/slopes_integrators   # relative to the current directory (optional)

The runs are the product of the grid axes (in file order) with the zip rows (varying fastest).
Precedence for a run: base file < ``set`` < ``--set`` on the command line < the run's axis values.
Every run's config is validated (and its walker built) before anything is written, so a sweep
never starts with a bad run in it; the error names the run and the field.
"""

from __future__ import annotations

import copy
import itertools
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from biped_sim.config import Config, apply_override, config_from_dict, parse_yaml, set_dotted
from biped_sim.errors import ArgumentError, ConfigError, quote
from biped_sim.simulate import prepare_model
from biped_sim.simulate.budget import MAX_RUNS

_DOTTED_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\.([A-Za-z_][A-Za-z0-9_]*|[0-9]+))*$")  # a list item: name or index
_NAME_SAFE = re.compile(r"[A-Za-z0-9.+-]+")
STEM_MAX_LENGTH = 96


class RangeSpec(BaseModel):
    """``{from, to, num}``: ``num`` evenly spaced values, ends included (``scale: log`` for geometric)."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    start: float = Field(..., alias="from", description="First value.")
    stop: float = Field(..., alias="to", description="Last value (included).")
    num: int = Field(..., ge=1, description="Number of values.")
    scale: Literal["linear", "log"] = Field("linear", description="'log' = geometric spacing (both ends > 0).")

    @model_validator(mode="after")
    def _log_needs_positive_ends(self) -> RangeSpec:
        if self.scale == "log" and (self.start <= 0 or self.stop <= 0):
            raise ValueError("scale: 'log' needs from > 0 and to > 0")
        return self

    def values(self) -> list[float]:
        """The range's values, rounded to 12 significant digits so that 0.015 + 0.003 is 0.018."""
        if self.num == 1:
            raw = np.array([self.start])
        elif self.scale == "log":
            raw = np.geomspace(self.start, self.stop, self.num)
        else:
            raw = np.linspace(self.start, self.stop, self.num)
        return [float(f"{v:.12g}") for v in raw]


AxisSpec = list[Any] | RangeSpec


class SweepSpec(BaseModel):
    """The content of a sweep file (unknown keys are errors)."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    name: str = Field(..., pattern=r"^[A-Za-z0-9][A-Za-z0-9_.-]*$", description="Sweep name (default output dir).")
    description: str = Field("", description="What the sweep compares (free text).")
    base: str = Field(..., min_length=1, description="Base config file, relative to the sweep file.")
    overrides: dict[str, Any] = Field(
        default_factory=dict, alias="set", description="Dotted key -> value for every run."
    )
    grid: dict[str, AxisSpec] = Field(default_factory=dict, description="Axes of the Cartesian product.")
    zipped: dict[str, AxisSpec] = Field(
        default_factory=dict, alias="zip", description="Parallel lists of equal length (one axis)."
    )
    output: str | None = Field(None, description="Sweep directory; default results/sweeps/<name>.")

    @field_validator("overrides", "grid", "zipped")
    @classmethod
    def _keys_are_dotted(cls, value: dict[str, Any]) -> dict[str, Any]:
        for key in value:
            if not _DOTTED_KEY.match(key):
                raise ValueError(f"{quote(key)} is not a dotted config key such as ground.slope")
        return value

    @field_validator("grid", "zipped", mode="before")
    @classmethod
    def _axes_are_lists_or_ranges(cls, value: Any) -> Any:
        if not isinstance(value, dict):
            return value  # pydantic reports the type error
        out: dict[str, Any] = {}
        for key, axis in value.items():
            if isinstance(axis, dict):
                try:
                    out[key] = RangeSpec.model_validate(axis)
                except ValidationError as exc:
                    err = exc.errors()[0]
                    where = ".".join(str(part) for part in (key, *err["loc"]))
                    reason = (
                        "unknown key (a range has from, to, num, scale)"
                        if err["type"] == "extra_forbidden"
                        else err["msg"]
                    )
                    raise ValueError(f"{where}: {reason.removeprefix('Value error, ')}") from None
            elif isinstance(axis, list):
                if not axis:
                    raise ValueError(f"{key}: an axis needs at least one value")
                out[key] = axis
            else:
                raise ValueError(f"{key}: expected a list of values or a range {{from, to, num}}")
        return out

    @model_validator(mode="after")
    def _axes_consistent(self) -> SweepSpec:
        if not self.grid and not self.zipped:
            raise ValueError("grid: a sweep needs at least one axis in grid or zip")
        lengths = {key: axis_length(axis) for key, axis in self.zipped.items()}
        if len(set(lengths.values())) > 1:
            detail = ", ".join(f"{key} has {n}" for key, n in lengths.items())
            raise ValueError(f"zip: lists must have equal lengths ({detail})")
        count = math.prod(axis_length(axis) for axis in self.grid.values()) * max(lengths.values(), default=1)
        if count > MAX_RUNS:
            where = "grid" if self.grid else "zip"
            raise ValueError(f"{where}: the sweep expands to {count:,} runs, more than the limit of {MAX_RUNS:,}")
        for key in self.overrides:
            if key in self.grid or key in self.zipped:
                raise ValueError(f"set: {key} is also a sweep axis")
        for key in self.grid:
            if key in self.zipped:
                raise ValueError(f"zip: {key} is also a grid axis")
        return self

    @property
    def axes(self) -> list[str]:
        """The swept keys, grid axes first then zip axes, in file order."""
        return [*self.grid, *self.zipped]


def axis_values(axis: AxisSpec) -> list[Any]:
    """The values of one axis (a list as written, or a range expanded)."""
    return axis.values() if isinstance(axis, RangeSpec) else list(axis)


def axis_length(axis: AxisSpec) -> int:
    """The number of values of one axis, without expanding a range."""
    return axis.num if isinstance(axis, RangeSpec) else len(axis)


def _format_value(value: Any) -> str:
    """A short, file-name-safe text for one axis value."""
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, float):
        text = f"{value:g}" if math.isfinite(value) else str(value)
    elif isinstance(value, list | dict):
        text = quote(value)  # short: a YAML alias bomb would not fit in memory as text
    else:
        text = str(value)
    # runs of other characters become one '-'; a value's own sign stays (slope -0.3 is 'slope=-0.3')
    return "-".join(_NAME_SAFE.findall(text)) or "x"


def short_keys(keys: list[str]) -> dict[str, str]:
    """Readable names for dotted keys: the last component, or more where two keys would clash."""
    out: dict[str, str] = {}
    for key in keys:
        parts = key.split(".")
        depth = 1
        while depth < len(parts):
            tail = ".".join(parts[-depth:])
            clashes = [k for k in keys if k != key and ".".join(k.split(".")[-depth:]) == tail]
            if not clashes:
                break
            depth += 1
        out[key] = ".".join(parts[-depth:])
    return out


def run_stem(params: dict[str, Any], names: dict[str, str]) -> str:
    """``slope=0.015_method=rk4``: the readable part of a run directory's name."""
    stem = "_".join(f"{names[key]}={_format_value(value)}" for key, value in params.items())
    return stem[:STEM_MAX_LENGTH].rstrip("_=")


@dataclass(frozen=True)
class RunSpec:
    """One run of a sweep: its axis values and its resolved config."""

    index: int
    params: dict[str, Any]
    stem: str
    config: Config

    @property
    def config_hash(self) -> str:
        return self.config.hash()

    @property
    def name(self) -> str:
        """Run directory name: readable stem plus config hash (unique, stable across restarts)."""
        return f"{self.stem}-{self.config_hash}"


@dataclass(frozen=True)
class Sweep:
    """A parsed sweep file and its expanded runs."""

    spec: SweepSpec
    source: Path
    base_path: Path
    overrides: tuple[str, ...]
    runs: list[RunSpec]

    @property
    def axes(self) -> list[str]:
        return self.spec.axes

    def default_output_dir(self) -> Path:
        """``output`` from the sweep file, else results/sweeps/<name> (relative to the current directory)."""
        return Path(self.spec.output) if self.spec.output else Path("results") / "sweeps" / self.spec.name


def parse_sweep(data: Any, source: str) -> SweepSpec:
    """Validate a raw sweep mapping; errors name the sweep file and the field."""
    if not isinstance(data, dict):
        raise ConfigError(source, "a sweep file must be a mapping (name, base, grid/zip, ...)")
    try:
        return SweepSpec.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(part) for part in err["loc"]) or "sweep"
        if err["type"] == "extra_forbidden":
            reason = "unknown key (a sweep file has name, description, base, set, grid, zip, output)"
        else:
            reason = err["msg"].removeprefix("Value error, ")
            if not err["loc"] and ": " in reason:  # whole-file checks name their own field
                where, reason = reason.split(": ", 1)
        raise ConfigError(f"{source}: {where}", reason) from None


def _axis_points(spec: SweepSpec) -> list[dict[str, Any]]:
    """Every run's axis values: grid product (file order) times zip rows (fastest)."""
    grid_keys = list(spec.grid)
    grid_values = [axis_values(spec.grid[key]) for key in grid_keys]
    zip_keys = list(spec.zipped)
    zip_columns = [axis_values(spec.zipped[key]) for key in zip_keys]
    zip_rows = [dict(zip(zip_keys, row, strict=True)) for row in zip(*zip_columns, strict=True)] or [{}]
    points = []
    for combo in itertools.product(*grid_values):
        for zip_row in zip_rows:
            points.append({**dict(zip(grid_keys, combo, strict=True)), **zip_row})
    return points


def expand(spec: SweepSpec, source: Path, overrides: list[str] | tuple[str, ...] = ()) -> Sweep:
    """Resolve every run of ``spec`` into a validated Config (ConfigError names the run and field)."""
    base_path = (source.parent / spec.base).resolve()
    if not base_path.is_file():
        raise ConfigError(f"{source}: base", f"no such config file {base_path}")
    base = parse_yaml(base_path.read_text(), source=str(base_path))
    if base is None:
        base = {}
    if not isinstance(base, dict):
        raise ConfigError(str(base_path), "top level must be a mapping of sections")
    for key, value in spec.overrides.items():
        set_dotted(base, key, value)
    for assignment in overrides:
        key = assignment.partition("=")[0].strip()
        if key in spec.axes:
            raise ArgumentError("overrides", f"{key} is a sweep axis of {source}; change the sweep file instead")
        apply_override(base, assignment)
    names = short_keys(spec.axes)
    runs: list[RunSpec] = []
    seen: dict[str, RunSpec] = {}
    for index, params in enumerate(_axis_points(spec)):
        stem = run_stem(params, names)
        data = copy.deepcopy(base)
        for key, value in params.items():
            set_dotted(data, key, value)
        try:
            config = config_from_dict(data)
        except ConfigError as exc:
            raise ConfigError(f"{source}: run {index + 1} ({stem}): {exc.field}", exc.reason) from None
        run = RunSpec(index=index, params=params, stem=stem, config=config)
        if run.config_hash in seen:
            raise ConfigError(
                f"{source}: run {index + 1} ({stem})",
                f"same resolved config as run {seen[run.config_hash].index + 1} ({seen[run.config_hash].stem})",
            )
        seen[run.config_hash] = run
        runs.append(run)
    return Sweep(spec=spec, source=source, base_path=base_path, overrides=tuple(overrides), runs=runs)


def check_buildable(sweep: Sweep) -> None:
    """Build every run's walker once (geometry, initial state; the rigid walker for ``dynamics: rigid``): a bad run
    stops the sweep before it starts."""
    for run in sweep.runs:
        try:
            prepare_model(run.config)
        except ConfigError as exc:
            raise ConfigError(f"{sweep.source}: run {run.index + 1} ({run.stem}): {exc.field}", exc.reason) from None


def load_sweep(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> Sweep:
    """Read, validate and expand a sweep file (ConfigError on any bad input)."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(str(path), "no such sweep file")
    spec = parse_sweep(parse_yaml(path.read_text(), source=str(path)), str(path))
    return expand(spec, path, overrides)
