"""Walker builders: a walker config becomes bodies, joints and feet (a :class:`BuiltModel`).

The engine knows nothing of walkers. Every planar walker is built from its description (a described walker's
own, a bundled kind's expansion by :func:`describe`) by :func:`build_described`, unless its kind registers a
builder of its own here (the four-legged machine, whose pairs stand on two feet each); the spatial builders lift
a planar model (the compass) or build a kind's own (the four-legged machine).
"""

from __future__ import annotations

from collections.abc import Callable

from biped_sim.config import Config, InitialState
from biped_sim.errors import ConfigError
from biped_sim.walkers.describe import describe
from biped_sim.walkers.described import build_described
from biped_sim.walkers.four_legged import build_four_legged, build_four_legged_sagittal
from biped_sim.walkers.model import BuiltModel, minimal_model
from biped_sim.walkers.space_walker import build_space_walker
from biped_sim.walkers.spatial_compass import spatial_compass


def _spatial_compass(config: Config, initial: InitialState) -> BuiltModel:
    return spatial_compass(build_described(config, initial), config)


BUILDERS: dict[str, Callable[[Config, InitialState], BuiltModel]] = {  # planar; minimal converts them
    "four_legged": build_four_legged_sagittal,  # the config allows it in minimal coordinates only
}
"""The planar builders of the kinds built otherwise than from their description (:func:`build_described`)."""
SPATIAL_BUILDERS: dict[str, Callable[[Config, InitialState], BuiltModel]] = {
    "compass": _spatial_compass,
    "four_legged": build_four_legged,
    "description3d": build_space_walker,
}


def build_model(config: Config, initial: InitialState | dict[str, float] | None = None) -> BuiltModel:
    """Build the compliant multibody model of ``config.walker`` in ``config.formulation.kind``.

    ``initial`` is the start (leg angles and rates); by default the config's own. A config that starts on
    the rigid limit cycle is resolved by :func:`biped_sim.simulate.prepare_model`, not here.
    """
    if initial is None:
        if config.simulation.initial == "rigid_limit_cycle":
            raise ValueError("build_model: simulation.initial is rigid_limit_cycle; use simulate.prepare_model")
        initial = config.simulation.initial
    spatial = config.formulation.kind == "spatial"
    builder = SPATIAL_BUILDERS.get(config.walker.kind) if spatial else BUILDERS.get(config.walker.kind, build_described)
    if builder is None:
        raise ConfigError(
            "walker.kind",
            f"{config.walker.kind!r} has no compliant-contact builder in the {config.formulation.kind} formulation",
        )
    if config.formulation.kind == "minimal":  # the planar builder's walker, in minimal coordinates
        return minimal_model(builder(config, initial))
    return builder(config, initial)


__all__ = ["BUILDERS", "SPATIAL_BUILDERS", "BuiltModel", "build_model", "describe"]
