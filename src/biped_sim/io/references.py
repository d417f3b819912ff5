"""Reference files: published or measured per-step numbers to compare a model against.

A reference file (YAML) says what was measured, where it was published and the values::

    experiment: liu_round_foot_walker        # identifies the physical experiment
    description: ...
    citation: {authors: [...], title: ..., year: 2009, doi: ..., journal: ...}
    source: {kind: table, label: "Table 3", page: 520, details: ...}
    quantity: {name: step_period, unit: s, statistic: mean, n_trials: 5}
    values: [0.61, 0.60, ...]                # step 1 first (or give `steps`)
    std: [0.01, ...]                         # optional, same length
    published_errors: [corral2020_liu_errors.yaml]   # optional, relative to this file
    notes: ...

Two quantities exist: ``step_period`` (seconds; what ``biped-sim compare`` needs) and
``step_period_relative_error`` (percent; another model's published errors against the same
experiment, shown beside ours). Every malformed field is a ConfigError naming the file and field.

A measured gait may give several quantities per step, each a per-step mean over trials with its standard
deviation and number of trials, instead of (or beside the periods in) ``quantity``/``values``::

    step_origin: release                     # or heel_strike (see below); default release
    measurements:
      - {quantity: step_period, unit: s, mean: [...], std: [...], n_trials: 5}
      - {quantity: step_length, unit: m, mean: [...], std: [...], n_trials: [5, 5, 4]}
      - {quantity: stance_angle, unit: rad, steps: [2, 3], mean: [...], std: [...], n_trials: 5}

Quantities per step (MEASURED_UNITS): the period, the length (advance of the contact point between the
strikes that begin and end the step), the speed (length / period) and the touchdown angles of the leg
that strikes at the end of the step (``stance_angle``) and of the other leg (``swing_angle``), from the
slope normal as the config's initial state. ``std`` is the spread of single trials: a fit weights the mean
of n trials by its standard error std / sqrt(n). ``step_origin`` says how steps are numbered: ``release``
(step 1 lasts from the release at t = 0, counted as strike 0, to the first heel strike: what ``compare`` and
``fit`` always did) or ``heel_strike`` (step 1 lasts from the first heel strike to the second: the rows of
a run's steps.csv and summary.json's ``step_periods``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from biped_sim.config import parse_yaml, read_text_file
from biped_sim.errors import ConfigError

QUANTITY_UNITS = {"step_period": "s", "step_period_relative_error": "percent"}
MEASURED_UNITS = {
    "step_period": "s",
    "step_length": "m",
    "step_speed": "m/s",
    "stance_angle": "rad",
    "swing_angle": "rad",
}
POSITIVE_QUANTITIES = ("step_period", "step_length", "step_speed")
StepOrigin = Literal["release", "heel_strike"]
ORIGIN_OFFSET = {"release": 0, "heel_strike": 1}  # reference step k is model step k + offset (release numbering)
MAX_STEPS = 10_000  # values of a quantity and the largest step number: a fit simulates as far as the last step


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Citation(_Strict):
    """Who published the numbers, and where."""

    authors: list[str] = Field(..., min_length=1, description="Author names, in the order published.")
    title: str = Field(..., min_length=1)
    year: int = Field(..., ge=1800, le=2100)
    journal: str | None = Field(None, description="Journal, volume, article or pages.")
    doi: str | None = Field(None, pattern=r"^10\.\d{4,9}/\S+$", description="DOI without the https://doi.org/ prefix.")


class Source(_Strict):
    """Where in the publication the numbers are."""

    kind: Literal["table", "figure", "text"]
    label: str | None = Field(None, description="'Table 3', 'Figure 12'; null when not known.")
    page: int | str | None = None
    details: str = Field("", description="How the numbers were read or transcribed.")


class Quantity(_Strict):
    """What the values are."""

    name: Literal["step_period", "step_period_relative_error"]
    unit: Literal["s", "percent"]
    statistic: Literal["mean", "median", "single"] | None = Field(
        None, description="How repeated trials were combined (null: not stated)."
    )
    n_trials: int | None = Field(None, ge=1, description="Number of trials averaged (null: not stated).")

    @model_validator(mode="after")
    def _unit_matches(self) -> Quantity:
        expected = QUANTITY_UNITS[self.name]
        if self.unit != expected:
            raise ValueError(f"unit: {self.name} is in {expected!r}, not {self.unit!r}")
        return self


def _check_steps(steps: list[int] | None, n: int, where: str = "steps") -> None:
    if steps is None:
        return
    if len(steps) != n:
        raise ValueError(f"{where}: {len(steps)} step numbers for {n} values")
    if any(s < 1 for s in steps) or any(b <= a for a, b in itertools.pairwise(steps)):
        raise ValueError(f"{where}: must be increasing step numbers starting at 1 or later")
    if steps and steps[-1] > MAX_STEPS:
        raise ValueError(f"{where}: step {steps[-1]:,} is past the last step a reference may number ({MAX_STEPS:,})")


def _check_std(std: list[float] | None, n: int, where: str = "std") -> None:
    if std is None:
        return
    if len(std) != n:
        raise ValueError(f"{where}: {len(std)} entries for {n} values")
    if any(not math.isfinite(s) or s < 0 for s in std):
        raise ValueError(f"{where}: entries must be finite and >= 0")


class Measurement(_Strict):
    """One measured quantity per step: the mean over trials, the trials' standard deviation and their number."""

    quantity: Literal[tuple(MEASURED_UNITS)]  # type: ignore[valid-type]
    unit: str
    statistic: Literal["mean", "median", "single"] = "mean"
    steps: list[int] | None = Field(None, description="Step numbers of the values (default 1, 2, ...).")
    mean: list[float] = Field(..., min_length=1, max_length=MAX_STEPS)
    std: list[float] | None = Field(None, description="Standard deviation of single trials, per step.")
    n_trials: int | list[int] | None = Field(None, description="Trials per step (one number for all, or a list).")

    @model_validator(mode="after")
    def _consistent(self) -> Measurement:
        n, name = len(self.mean), self.quantity
        if self.unit != MEASURED_UNITS[name]:
            raise ValueError(f"unit: {name} is in {MEASURED_UNITS[name]!r}, not {self.unit!r}")
        for i, value in enumerate(self.mean):
            if not math.isfinite(value):
                raise ValueError(f"mean: entry {i + 1} is not a finite number")
            if name in POSITIVE_QUANTITIES and value <= 0:
                raise ValueError(f"mean: entry {i + 1} is a {name} and must be > 0 (got {value})")
        _check_steps(self.steps, n)
        _check_std(self.std, n)
        if len(self.trials) != n or any(t < 1 for t in self.trials):
            raise ValueError(f"n_trials: one number >= 1, or {n} of them")
        return self

    @property
    def step_numbers(self) -> list[int]:
        return self.steps or list(range(1, len(self.mean) + 1))

    @property
    def trials(self) -> list[int]:
        if isinstance(self.n_trials, list):
            return self.n_trials
        return [1 if self.n_trials is None else self.n_trials] * len(self.mean)


class ReferenceSpec(_Strict):
    """The content of a reference file."""

    experiment: str = Field(..., pattern=r"^[A-Za-z0-9_.-]+$", description="Identifier of the measured experiment.")
    description: str = ""
    citation: Citation
    source: Source
    quantity: Quantity | None = None
    compared: str | None = Field(None, description="For errors: which model against which measurement.")
    step_origin: StepOrigin = Field("release", description="How steps are numbered (module docstring).")
    steps: list[int] | None = Field(None, description="Step numbers of the values (default 1, 2, ...).")
    values: list[float] | None = Field(None, min_length=1, max_length=MAX_STEPS)
    std: list[float] | None = None
    measurements: list[Measurement] | None = Field(None, min_length=1, description="Several quantities per step.")
    published_errors: list[str] = Field(default_factory=list, description="Error files to show beside ours.")
    notes: str = ""

    @model_validator(mode="after")
    def _one_form(self) -> ReferenceSpec:
        if (self.quantity is None) != (self.values is None):
            raise ValueError("values: give quantity and values together")
        if self.values is None and self.measurements is None:
            raise ValueError("values: give quantity and values, or measurements")
        names = [m.quantity for m in self.measurements or []]
        if len(set(names)) != len(names):
            raise ValueError("measurements: a quantity is listed twice")
        if self.quantity is not None and self.quantity.name == "step_period" and "step_period" in names:
            raise ValueError("measurements: step_period is also given as quantity/values")
        if self.measurements is not None and self.quantity is not None and self.quantity.name != "step_period":
            raise ValueError("measurements: only a measured reference (not published errors) has measurements")
        return self._values_consistent() if self.values is not None else self

    def _values_consistent(self) -> ReferenceSpec:
        assert self.quantity is not None and self.values is not None
        n = len(self.values)
        for i, value in enumerate(self.values):
            if not math.isfinite(value):
                raise ValueError(f"values: entry {i + 1} is not a finite number")
            if self.quantity.name == "step_period" and value <= 0:
                raise ValueError(f"values: entry {i + 1} is a step period and must be > 0 (got {value})")
            if self.quantity.name == "step_period_relative_error" and value < 0:
                raise ValueError(f"values: entry {i + 1} is a relative error and must be >= 0 (got {value})")
        _check_steps(self.steps, n)
        _check_std(self.std, n)
        if self.published_errors and self.quantity.name != "step_period":
            raise ValueError("published_errors: only a step_period reference can list published errors")
        return self


@dataclass
class Reference:
    """A loaded reference file (and, for periods, the published errors to show beside ours)."""

    path: Path
    spec: ReferenceSpec
    published_errors: list[Reference] = field(default_factory=list)

    def measured(self) -> list[Measurement]:
        """Every measured quantity per step, the legacy ``quantity``/``values`` periods as a Measurement first."""
        spec, out = self.spec, []
        if spec.quantity is not None and spec.values is not None and spec.quantity.name == "step_period":
            q = spec.quantity
            out.append(
                Measurement(
                    quantity="step_period", unit="s", statistic=q.statistic or "mean", steps=spec.steps,
                    mean=spec.values, std=spec.std, n_trials=q.n_trials,
                )
            )  # fmt: skip
        return out + list(spec.measurements or [])

    def _periods(self) -> Measurement | None:
        return next((m for m in self.measured() if m.quantity == "step_period"), None)

    @property
    def steps(self) -> list[int]:
        """Step numbers of the periods (or of the published errors), in the file's numbering."""
        if self.spec.values is not None:
            return self.spec.steps or list(range(1, len(self.spec.values) + 1))
        periods = self._periods()
        return periods.step_numbers if periods is not None else []

    @property
    def values(self) -> list[float]:
        if self.spec.values is not None:
            return list(self.spec.values)
        periods = self._periods()
        return list(periods.mean) if periods is not None else []

    @property
    def std(self) -> list[float] | None:
        """The periods' standard deviation per step, if given."""
        periods = self._periods()
        return list(periods.std) if periods is not None and periods.std is not None else None

    @property
    def is_periods(self) -> bool:
        return self._periods() is not None

    @property
    def origin_offset(self) -> int:
        """Model step (counted from the release) = reference step + this (``step_origin``)."""
        return ORIGIN_OFFSET[self.spec.step_origin]

    def numbering_text(self) -> str:
        """The reference's step numbering in one sentence (for file headers and table notes)."""
        if self.spec.step_origin == "heel_strike":
            return (
                "Step k lasts from heel strike k to heel strike k + 1 (as a run's steps.csv; step_origin: heel_strike)."
            )
        return "Step k lasts from heel strike k - 1 to heel strike k, the release (t = 0) counting as strike 0."

    def citation_text(self) -> str:
        """'Corral, ... (2020), Title. Journal. doi:...' in one line."""
        c = self.spec.citation
        authors = ", ".join(c.authors)
        parts = [f"{authors} ({c.year}). {c.title}."]
        if c.journal:
            parts.append(f"{c.journal}.")
        if c.doi:
            parts.append(f"https://doi.org/{c.doi}")
        return " ".join(parts)

    def source_text(self) -> str:
        """'Table 3, p. 520', or 'table/figure number not available'."""
        s = self.spec.source
        where = s.label or "table/figure number not available"
        return where + (f", p. {s.page}" if s.page is not None else "")

    @property
    def short_name(self) -> str:
        """Citation in short: 'Corral et al. 2020'."""
        c = self.spec.citation
        first = c.authors[0].split()[-1]
        return f"{first}{' et al.' if len(c.authors) > 1 else ''} {c.year}"


def _spec_error(path: Path, exc: ValidationError) -> ConfigError:
    err = exc.errors()[0]
    where = ".".join(str(part) for part in err["loc"])
    reason = err["msg"].removeprefix("Value error, ")
    if err["type"] == "extra_forbidden":
        reason = "unknown key (not in the reference-file schema)"
    elif err["type"] == "value_error" and ": " in reason:  # validators name their own field first
        field_name, reason = reason.split(": ", 1)
        where = f"{where}.{field_name}" if where else field_name
    return ConfigError(f"{path}: {where or 'reference'}", reason)


def load_reference(path: str | Path, *, linked_from: Path | None = None, _chain: tuple[Path, ...] = ()) -> Reference:
    """Read and validate a reference file (and the published-error files it links); ConfigError on any fault."""
    path = Path(path)
    where = f"{linked_from}: published_errors" if linked_from else str(path)
    if not path.is_file():
        raise ConfigError(where, f"no such reference file {path}")
    if path.resolve() in _chain:
        raise ConfigError(where, f"{path} links back to a file that lists it (a cycle)")
    data = parse_yaml(read_text_file(path, "reference file"), source=str(path))
    if not isinstance(data, dict):
        raise ConfigError(str(path), "a reference file must be a mapping (experiment, citation, source, ...)")
    try:
        spec = ReferenceSpec.model_validate(data)
    except ValidationError as exc:
        raise _spec_error(path, exc) from None
    reference = Reference(path=path, spec=spec)
    for entry in spec.published_errors:
        linked = load_reference(path.parent / entry, linked_from=path, _chain=(*_chain, path.resolve()))
        if linked.spec.quantity is None or linked.spec.quantity.name != "step_period_relative_error":
            raise ConfigError(f"{path}: published_errors", f"{entry} does not hold step_period_relative_error values")
        if linked.spec.experiment != spec.experiment:
            raise ConfigError(
                f"{path}: published_errors",
                f"{entry} is about experiment {linked.spec.experiment!r}, this file about {spec.experiment!r}",
            )
        reference.published_errors.append(linked)
    return reference
