"""What is known of a config key: a distribution, parsed from ``KEY=DIST:...`` or a YAML section.

``uniform:LO:HI``, ``normal:MEAN:SD``, ``lognormal:MEDIAN:SIGMA`` (SIGMA the standard deviation of ln x),
``triangular:LO:MODE:HI`` and ``interval:LO:HI`` ("unknown but bounded": sampled uniformly over the bounds,
and reported with the range the samples reached besides the statistics). Each maps a unit sample u in (0, 1)
to a value by its inverse distribution function, so one quasi-Monte Carlo design in the unit cube serves
every distribution. Errors name the config key (or the argument ``parameters``), never a command-line flag.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats

from biped_sim.config import Config, derive
from biped_sim.config.loading import parse_yaml, read_text_file
from biped_sim.errors import ConfigError, quote
from biped_sim.studies.fit.parameters import check_distinct, numeric_value

# name: the numbers it takes, in order
KINDS = {
    "uniform": ("LO", "HI"),
    "normal": ("MEAN", "SD"),
    "lognormal": ("MEDIAN", "SIGMA"),
    "triangular": ("LO", "MODE", "HI"),
    "interval": ("LO", "HI"),
}
SPEC_KEYS = ("parameters", "samples", "seed", "method")  # an uncertainty file's section
UNIT_CLIP = 1e-12  # unit samples are kept inside (0, 1): a normal's inverse is infinite at the ends


@dataclass(frozen=True)
class Distribution:
    """A config key's distribution: ``kind`` (a name of :data:`KINDS`) and its numbers, checked."""

    key: str
    kind: str
    numbers: tuple[float, ...]

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigError(self.key, f"unknown distribution {quote(self.kind)}; expected one of {', '.join(KINDS)}")
        names = KINDS[self.kind]
        if len(self.numbers) != len(names):
            raise ConfigError(self.key, f"{self.kind} takes {len(names)} numbers ({self.kind}:{':'.join(names)})")
        if not all(math.isfinite(v) for v in self.numbers):
            raise ConfigError(self.key, f"{self.kind}: the numbers must be finite")
        self._check_shape()

    def _check_shape(self) -> None:
        n = self.numbers
        if self.kind in ("uniform", "interval") and not n[0] < n[1]:
            raise ConfigError(self.key, f"{self.kind}: bounds reversed or equal ({n[0]:g} is not below {n[1]:g})")
        if self.kind in ("normal", "lognormal") and not n[1] > 0:
            raise ConfigError(self.key, f"{self.kind}: the standard deviation must be positive, not {n[1]:g}")
        if self.kind == "lognormal" and not n[0] > 0:
            raise ConfigError(self.key, f"lognormal: the median must be positive, not {n[0]:g}")
        if self.kind == "triangular" and not (n[0] <= n[1] <= n[2] and n[0] < n[2]):
            raise ConfigError(self.key, f"triangular: need LO <= MODE <= HI and LO < HI, not {n}")

    @property
    def frozen(self) -> Any:
        """The scipy.stats distribution."""
        n = self.numbers
        if self.kind in ("uniform", "interval"):
            return stats.uniform(loc=n[0], scale=n[1] - n[0])
        if self.kind == "normal":
            return stats.norm(loc=n[0], scale=n[1])
        if self.kind == "lognormal":
            return stats.lognorm(s=n[1], scale=n[0])
        return stats.triang(c=(n[1] - n[0]) / (n[2] - n[0]), loc=n[0], scale=n[2] - n[0])

    def values(self, unit: np.ndarray) -> np.ndarray:
        """The values of unit samples ``unit`` (inverse distribution function)."""
        return np.asarray(self.frozen.ppf(np.clip(unit, UNIT_CLIP, 1.0 - UNIT_CLIP)), dtype=np.float64)

    def text(self) -> str:
        """``kind:n1:n2...`` as it would be given."""
        return ":".join([self.kind, *(f"{v:g}" for v in self.numbers)])


def parse_distribution(key: str, text: str) -> Distribution:
    """``DIST:N1:N2...`` for ``key``."""
    kind, *parts = text.strip().split(":")
    if kind.strip() not in KINDS:
        raise ConfigError(key, f"unknown distribution {quote(kind)}; expected one of {', '.join(KINDS)}")
    try:
        numbers = tuple(float(p) for p in parts)
    except ValueError:
        raise ConfigError(key, f"{quote(text)}: the distribution's numbers must be numbers") from None
    return Distribution(key, kind.strip(), numbers)


def parse_param(text: str) -> Distribution:
    """``KEY=DIST:N1:N2...`` (e.g. ``ground.slope=uniform:0.004:0.012``)."""
    key, sep, rest = text.partition("=")
    if not sep or not key.strip() or not rest.strip():
        raise ConfigError(
            "parameters", f"expected KEY=DIST:N1:N2 (e.g. ground.slope=normal:0.02:0.002), got {quote(text)}"
        )
    return parse_distribution(key.strip(), rest)


def _from_mapping(key: str, entry: Mapping[str, Any]) -> Distribution:
    """``{distribution: normal, mean: .., sd: ..}`` (the number names of :data:`KINDS`, any case)."""
    fields = {str(k).lower(): v for k, v in entry.items()}
    kind = str(fields.pop("distribution", ""))
    if kind not in KINDS:
        raise ConfigError(key, f"unknown distribution {quote(kind)}; expected one of {', '.join(KINDS)}")
    names = [n.lower() for n in KINDS[kind]]
    if sorted(fields) != sorted(names):
        raise ConfigError(key, f"{kind} takes {', '.join(names)}; got {', '.join(sorted(fields)) or 'none'}")
    values = [fields[n] for n in names]
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        raise ConfigError(key, f"{kind}: {', '.join(names)} must be numbers")
    return Distribution(key, kind, tuple(float(v) for v in values))


def read_spec(path: str) -> tuple[list[Distribution], dict[str, Any]]:
    """A YAML file whose ``uncertainty`` section (or top level) holds ``parameters``: KEY -> ``DIST:...`` or a
    mapping; other entries of the section (``samples``, ``seed``, ``method``) are returned as they are."""
    data = parse_yaml(read_text_file(path, "uncertainty file"), source=path)
    section = data.get("uncertainty", data) if isinstance(data, dict) else None
    if not isinstance(section, dict) or not isinstance(section.get("parameters"), dict):
        raise ConfigError(path, "expected an 'uncertainty' section with 'parameters': KEY -> DIST:N1:N2")
    found = []
    for key, entry in section["parameters"].items():
        if isinstance(entry, str):
            found.append(parse_distribution(str(key), entry))
        elif isinstance(entry, dict):
            found.append(_from_mapping(str(key), entry))
        else:
            raise ConfigError(str(key), "expected DIST:N1:N2 or a mapping with 'distribution'")
    if unknown := [str(k) for k in section if k not in SPEC_KEYS]:
        where = "uncertainty." if "uncertainty" in data else ""
        raise ConfigError(f"{path}: {where}{unknown[0]}", f"unknown key; expected {', '.join(SPEC_KEYS)}")
    return found, {k: v for k, v in section.items() if k != "parameters"}


def check_distributions(config: Config, distributions: Sequence[Distribution]) -> None:
    """At least one, no key twice, each key a real number of ``config``, and the distribution's central value
    a valid config (a key outside the schema's range fails here, before any run)."""
    if not distributions:
        raise ConfigError("parameters", "give at least one config key with a distribution (KEY=DIST:N1:N2)")
    check_distinct([d.key for d in distributions], "is given twice")
    for dist in distributions:
        numeric_value(config, dist.key)
        try:
            derive(config, {dist.key: float(dist.frozen.median())})
        except ConfigError as exc:
            raise ConfigError(dist.key, f"its median is not a valid config ({exc.reason})") from None
