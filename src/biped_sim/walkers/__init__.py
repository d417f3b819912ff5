"""Walker builders: a walker config becomes bodies, joints and feet (a :class:`BuiltModel`).

The engine knows nothing of walkers. Every walker is built from its description (a described walker's own, a
bundled kind's expansion by :func:`describe`): planar by :func:`build_described`, converted to minimal
coordinates, or lifted into the spatial formulation by :func:`spatial_described`; a walker in space
(``Config.in_space``: a described walker of the rigid model's form started on its gait in space) by its own
spatial builder.
"""

from __future__ import annotations

from biped_sim.config import Config, InitialState
from biped_sim.walkers.describe import describe
from biped_sim.walkers.described_start import build_described
from biped_sim.walkers.model import BuiltModel, minimal_model
from biped_sim.walkers.space_walker import build_space_walker
from biped_sim.walkers.spatial_described import spatial_described


def build_model(config: Config, initial: InitialState | dict[str, float] | None = None) -> BuiltModel:
    """Build the compliant multibody model of ``config.walker`` in ``config.formulation.kind``.

    ``initial`` is the start (leg angles and rates); by default the config's own. A config that starts on
    the rigid limit cycle is resolved by :func:`biped_sim.simulate.prepare_model`, not here. The schema has
    checked that the walker has a model in this formulation (the registry's).
    """
    if initial is None:
        if config.simulation.initial == "rigid_limit_cycle":
            raise ValueError("build_model: simulation.initial is rigid_limit_cycle; use simulate.prepare_model")
        initial = config.simulation.initial
    if config.in_space:
        return build_space_walker(config, initial)
    if config.formulation.kind == "spatial":
        return spatial_described(config, initial)
    planar = build_described(config, initial)
    return minimal_model(planar) if config.formulation.kind == "minimal" else planar


__all__ = ["BuiltModel", "build_model", "describe"]
