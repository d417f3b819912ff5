"""The fitted config keys: bounds, the normalised variable the optimizers and the sampler move, and the checks.

Every key is fitted in a variable u in [0, 1] over its bounds, logarithmically when the bounds are positive
and span a decade or more (stiffness-like scales: ``LOG_SPAN``). Errors name the config key (or the
argument ``parameters``), never a command-line flag: the CLI maps them to its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from biped_sim.config import Config, derive, get_dotted
from biped_sim.errors import ConfigError

LOG_SPAN = 10.0  # bounds 0 < LO with HI / LO >= LOG_SPAN are fitted in log(value)


@dataclass(frozen=True)
class FitParameter:
    """A config key fitted within [low, high], from ``start`` (the config's own value)."""

    key: str
    low: float
    high: float
    start: float

    @property
    def log(self) -> bool:
        """Whether the key is fitted in log(value): positive bounds spanning a decade or more."""
        return self.low > 0 and self.high / self.low >= LOG_SPAN

    def to_unit(self, value: float) -> float:
        """The value as a normalised variable in [0, 1] over the bounds."""
        if self.log:
            return math.log(value / self.low) / math.log(self.high / self.low)
        return (value - self.low) / (self.high - self.low)

    def from_unit(self, u: float) -> float:
        """The value of normalised variable ``u`` (clipped to the bounds)."""
        u = min(max(u, 0.0), 1.0)
        if self.log:
            return self.low * (self.high / self.low) ** u
        return self.low + u * (self.high - self.low)

    def slope(self, u: float) -> float:
        """d value / d u at ``u`` (to carry a covariance from normalised to the parameter's units)."""
        if self.log:
            return self.from_unit(u) * math.log(self.high / self.low)
        return self.high - self.low


def numeric_value(config: Config, key: str) -> float:
    """The real-valued entry ``key`` (dotted) of ``config``; ConfigError naming the key if unknown or not a real."""
    node = get_dotted(config.model_dump(mode="json"), key)
    if node is None:
        raise ConfigError(key, "has no value in the config to start from: set one")
    if isinstance(node, str) and key.startswith("walker.description."):
        raise ConfigError(
            key, f"is the expression {node!r} of the walker's parameters: vary those instead (walker.parameters.NAME)"
        )
    if isinstance(node, bool) or not isinstance(node, float):
        raise ConfigError(key, f"is not a real-valued parameter (its value is {node!r})")
    return node


def fit_parameter(config: Config, key: str, low: float, high: float) -> FitParameter:
    """``key`` fitted within [low, high] from ``config``'s value; ConfigError naming the key for any fault."""
    if not (math.isfinite(low) and math.isfinite(high)):
        raise ConfigError(key, "bounds must be finite")
    if low >= high:
        raise ConfigError(key, f"lower bound {low:g} must be below the upper bound {high:g}")
    start = numeric_value(config, key)
    if not low <= start <= high:
        raise ConfigError(key, f"start {start:g} (the config's value) is outside [{low:g}, {high:g}]")
    for bound in (low, high):
        try:
            derive(config, {key: bound})
        except ConfigError as exc:
            raise ConfigError(key, f"bound {bound:g} is not a valid config ({exc.reason})") from None
    return FitParameter(key, low, high, start)


def parse_parameter(text: str, config: Config) -> FitParameter:
    """``KEY=LO:HI`` against the resolved ``config`` (start: its value of KEY)."""
    key, sep, bounds = text.partition("=")
    low_text, colon, high_text = bounds.partition(":")
    if not sep or not colon or not key.strip():
        raise ConfigError("parameters", f"expected KEY=LO:HI, got {text[:60]!r}")
    key = key.strip()
    try:
        low, high = float(low_text), float(high_text)
    except ValueError:
        raise ConfigError(key, f"bounds {bounds[:40]!r} are not two numbers LO:HI") from None
    return fit_parameter(config, key, low, high)


def check_parameters(parameters: tuple[FitParameter, ...]) -> None:
    """At least one parameter, no key twice (a preset's ``walker.parameters.NAME`` is its ``walker.NAME``)."""
    if not parameters:
        raise ConfigError("parameters", "give at least one config key to fit (KEY=LO:HI)")
    same = [same_key(p.key) for p in parameters]
    if twice := sorted(p.key for p, k in zip(parameters, same, strict=True) if same.count(k) > 1):
        raise ConfigError(twice[0], "is fitted twice")


def same_key(key: str) -> str:
    """The key as its field: a preset's parameter ``walker.parameters.NAME`` is its field ``walker.NAME``, so both
    spellings are one key (a described walker has no field ``walker.NAME``: its parameters keep their key)."""
    prefix = "walker.parameters."
    return "walker." + key[len(prefix) :] if key.startswith(prefix) and "." not in key[len(prefix) :] else key


def check_distinct(keys: list[str], reason: str) -> None:
    """ConfigError naming the first key (in sorted order) that ``keys`` holds twice, either spelling of a preset's
    parameter (:func:`same_key`) counting as one key."""
    same = [same_key(k) for k in keys]
    twice = sorted({k for k, s in zip(keys, same, strict=True) if same.count(s) > 1})
    if twice:
        raise ConfigError(twice[0], reason)
