"""The cells of a basin of a rigid walker in space (``Config.in_space``): each start walked by the step
map on its Poincare section (:mod:`biped_sim.rigid.space_cycle`).

A cell's start is its section point: the grid's two keys (section coordinates: bank, pitch, the angular velocity,
the hinge rate, and the heading on a slope), the others the configured start's or, with ``simulation.initial:
rigid_limit_cycle``, the gait's (the basin around the gait); the hinge angle is not a key: the trailing foot on the
ground fixes it. On level ground the heading is neutral (the map is the same in every heading) and left out.
"""

from __future__ import annotations

import numpy as np

from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.rigid.limit_cycle import LimitCycle, StepFailedError
from biped_sim.rigid.space_cycle import SpaceMap, SpaceSection, space_cycle_from, space_limit_cycle, space_walker_model
from biped_sim.rigid.space_model import STATE_NAMES


def basin_keys(config: Config) -> tuple[str, ...]:
    """The keys a basin's axes may take: a walker in space's section coordinates, else the initial-state keys."""
    if config.in_space:
        return SpaceSection(space_walker_model(config)).names
    return config.initial_keys()


def space_gait(config: Config) -> LimitCycle:
    """The gait a basin in space converges to: Newton from the configured start when ``simulation.initial`` gives
    one (:func:`~biped_sim.rigid.space_cycle.space_cycle_from`), else, or when that fails, the search without a
    guess (:func:`~biped_sim.rigid.space_cycle.space_limit_cycle`)."""
    initial = config.simulation.initial
    near = space_cycle_from(config, initial) if isinstance(initial, dict) else None
    return near or space_limit_cycle(config)


def space_cells(
    config: Config, starts: list[dict[str, float]], gait: dict[str, float] | None, steps: int
) -> list[tuple[int, dict[str, float] | None]]:
    """Each start (its keys over the configured start's, or the gait's) walked ``steps`` steps: (the steps taken,
    the last post-strike state's keys, on level ground heading 0; None when it fell first)."""
    step_map = SpaceMap(space_walker_model(config))
    section = step_map.section
    initial = config.simulation.initial
    base = initial if isinstance(initial, dict) else gait
    if base is None:
        raise ConfigError("simulation.initial", "rigid_limit_cycle: no gait found to map the basin around")
    return [_walk(step_map, section.of_keys({**base, **start}), steps) for start in starts]


def _walk(step_map: SpaceMap, z: np.ndarray, steps: int) -> tuple[int, dict[str, float] | None]:
    """(the steps taken from section point ``z``, up to ``steps``; the last post-strike state's keys, None when it
    fell first)."""
    for taken in range(steps):
        try:
            z = step_map(z)
        except StepFailedError:
            return taken, None
    return steps, {name: float(v) for name, v in zip(STATE_NAMES[:8], step_map.section.from_section(z), strict=False)}
