"""Walker builders: a walker config becomes bodies, joints and feet (a :class:`BuiltModel`).

The engine knows nothing of walkers; another walker is another builder registered here.
"""

from __future__ import annotations

from collections.abc import Callable

from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.walkers.compass import build_compass
from biped_sim.walkers.model import BuiltModel

BUILDERS: dict[str, Callable[[Config], BuiltModel]] = {
    "compass": build_compass,
}


def build_model(config: Config) -> BuiltModel:
    """Build the compliant multibody model of ``config.walker``."""
    builder = BUILDERS.get(config.walker.kind)
    if builder is None:
        raise ConfigError("walker.kind", f"{config.walker.kind!r} has no compliant-contact builder")
    return builder(config)


__all__ = ["BUILDERS", "BuiltModel", "build_model"]
