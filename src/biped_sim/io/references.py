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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from biped_sim.config import parse_yaml, read_text_file
from biped_sim.errors import ConfigError

QUANTITY_UNITS = {"step_period": "s", "step_period_relative_error": "percent"}


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


class ReferenceSpec(_Strict):
    """The content of a reference file."""

    experiment: str = Field(..., pattern=r"^[A-Za-z0-9_.-]+$", description="Identifier of the measured experiment.")
    description: str = ""
    citation: Citation
    source: Source
    quantity: Quantity
    compared: str | None = Field(None, description="For errors: which model against which measurement.")
    steps: list[int] | None = Field(None, description="Step numbers of the values (default 1, 2, ...).")
    values: list[float] = Field(..., min_length=1)
    std: list[float] | None = None
    published_errors: list[str] = Field(default_factory=list, description="Error files to show beside ours.")
    notes: str = ""

    @model_validator(mode="after")
    def _values_consistent(self) -> ReferenceSpec:
        n = len(self.values)
        for i, value in enumerate(self.values):
            if not math.isfinite(value):
                raise ValueError(f"values: entry {i + 1} is not a finite number")
            if self.quantity.name == "step_period" and value <= 0:
                raise ValueError(f"values: entry {i + 1} is a step period and must be > 0 (got {value})")
            if self.quantity.name == "step_period_relative_error" and value < 0:
                raise ValueError(f"values: entry {i + 1} is a relative error and must be >= 0 (got {value})")
        if self.steps is not None:
            if len(self.steps) != n:
                raise ValueError(f"steps: {len(self.steps)} step numbers for {n} values")
            if any(s < 1 for s in self.steps) or any(b <= a for a, b in zip(self.steps, self.steps[1:], strict=False)):
                raise ValueError("steps: must be increasing step numbers starting at 1 or later")
        if self.std is not None:
            if len(self.std) != n:
                raise ValueError(f"std: {len(self.std)} entries for {n} values")
            if any(not math.isfinite(s) or s < 0 for s in self.std):
                raise ValueError("std: entries must be finite and >= 0")
        if self.published_errors and self.quantity.name != "step_period":
            raise ValueError("published_errors: only a step_period reference can list published errors")
        return self


@dataclass
class Reference:
    """A loaded reference file (and, for periods, the published errors to show beside ours)."""

    path: Path
    spec: ReferenceSpec
    published_errors: list[Reference] = field(default_factory=list)

    @property
    def steps(self) -> list[int]:
        return self.spec.steps or list(range(1, len(self.spec.values) + 1))

    @property
    def values(self) -> list[float]:
        return list(self.spec.values)

    @property
    def is_periods(self) -> bool:
        return self.spec.quantity.name == "step_period"

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
        if linked.spec.quantity.name != "step_period_relative_error":
            raise ConfigError(f"{path}: published_errors", f"{entry} does not hold step_period_relative_error values")
        if linked.spec.experiment != spec.experiment:
            raise ConfigError(
                f"{path}: published_errors",
                f"{entry} is about experiment {linked.spec.experiment!r}, this file about {spec.experiment!r}",
            )
        reference.published_errors.append(linked)
    return reference
