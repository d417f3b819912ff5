"""The rigid model of a config's walker: a bundled kind's own, or a described walker's tree."""

from __future__ import annotations

import numpy as np

from biped_sim.config import Config
from biped_sim.rigid.models import CompassChain, RigidWalker, RimlessWheel, SimplestWalker
from biped_sim.rigid.tree import TreeWalker

RIGID_MODELS = {"compass": CompassChain, "simplest": SimplestWalker, "rimless_wheel": RimlessWheel}


def rigid_walker(config: Config) -> RigidWalker:
    """The rigid model of ``config.walker``."""
    if config.walker.description is not None:
        return TreeWalker(config, config.walker.description)
    return RIGID_MODELS[config.walker.kind](config)


def initial_state(config: Config, walker: RigidWalker) -> np.ndarray:
    """The config's initial state as a rigid state vector (legs as configured)."""
    initial = config.simulation.initial
    if isinstance(initial, str):
        raise ValueError("initial_state: the config asks for the rigid limit cycle, resolve it first")
    return walker.state_from_legs(initial if isinstance(initial, dict) else initial.model_dump())
