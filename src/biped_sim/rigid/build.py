"""The rigid model of a config's walker: its description's tree (a bundled kind's, or the config's own)."""

from __future__ import annotations

import numpy as np

from biped_sim.config import Config
from biped_sim.config.walker_registry import capabilities
from biped_sim.errors import ConfigError
from biped_sim.rigid.tree import RigidWalker
from biped_sim.walkers.describe import describe


def rigid_walker(config: Config, checked: bool = True) -> RigidWalker:
    """The rigid model of ``config.walker``; ``checked``: its legs checked alike (a ConfigError if not), which
    compiles the flow's Python twin on a cold cache; unchecked only where the kernels' argument types alone are
    wanted (a second process compiling the step map's kernels: :mod:`biped_sim.simulate.aside`)."""
    kind = config.walker.kind
    if config.in_space:
        raise ConfigError("walker", "a walker in space has its own rigid model (rigid.space_model), not the planar one")
    gravity = 1.0 if capabilities(kind).nondimensional else config.gravity  # Garcia's g = l = hip mass = 1
    return RigidWalker(config, describe(config), kind, gravity, checked)


def initial_state(config: Config, walker: RigidWalker) -> np.ndarray:
    """The config's initial state as a rigid state vector (legs as configured)."""
    initial = config.simulation.initial
    if isinstance(initial, str):
        raise ValueError("initial_state: the config asks for the rigid limit cycle, resolve it first")
    return walker.state_from_legs(initial if isinstance(initial, dict) else initial.model_dump())
