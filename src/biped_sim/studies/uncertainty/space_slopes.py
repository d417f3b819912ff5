"""Walks of a rigid walker in space on random slopes: the slope of every step drawn from N(slope, roughness^2) and
the step walked by the compiled step map in space on that slope (the ``slope`` ground of :mod:`.mfpt`).

Each step's ground is a plane through its stance contact point, as the rimless wheel's random slopes (Byl and
Tedrake 2009): where two steps' slopes differ, the ground has a kink at the new contact point. The step map's state
lives in its slope's frame (x downhill, y left, z the normal), so a post-strike state is re-expressed in the next
step's frame (:func:`tilted`): that frame is the last one turned about the lateral axis by the change of slope d,
so the stance leg's attitude R becomes Ry(-d) R and its angular velocity w becomes Ry(-d) w (the hinge angle and
rate, relative quantities, stay); gravity in the step's frame is g (sin gamma, 0, -cos gamma).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from biped_sim.config import Config
from biped_sim.rigid.space_integration import space_scratch
from biped_sim.rigid.space_model import SpaceModel, attitude_angles
from biped_sim.rigid.space_step import space_step
from biped_sim.simulate.space_rigid import space_start
from biped_sim.walkers.space_geometry import attitude, rot_y


def tilted(x: np.ndarray, change: float) -> np.ndarray:
    """Post-strike state ``x`` in the frame of a slope ``change`` rad steeper (module docstring); unchanged, to the
    bit, when the slope is (the walk on a smooth slope is the step map's)."""
    out = np.array(x, dtype=float)
    if change == 0.0:
        return out
    turn = rot_y(-change)
    out[:3] = attitude_angles(turn @ attitude(x[0], x[1], x[2]))
    out[4:7] = turn @ x[4:7]
    return out


def space_slope_walks(config: Config, roughness: float, seeds: range, cap: int) -> tuple[np.ndarray, np.ndarray]:
    """Walks of the walker in space from its start (``simulation.initial``: the gait's keys, or the gait found) on
    random slopes, one per seed: (strikes, fell), ``fell`` False for a walk that reached the cap."""
    start = space_start(config)
    strikes, fell = np.zeros(len(seeds), dtype=np.int64), np.zeros(len(seeds), dtype=bool)
    for i, seed in enumerate(seeds):
        strikes[i], fell[i] = _walk(start.model, start.state, config.ground.slope, roughness, seed, cap)
    return strikes, fell


def _walk(model: SpaceModel, x: np.ndarray, slope: float, roughness: float, seed: int, cap: int) -> tuple[int, bool]:
    """(strikes, fell) of one walk: each step on a slope drawn with ``seed``, up to ``cap`` strikes."""
    scratch, previous = space_scratch(), slope
    rng = np.random.default_rng(seed)
    for k in range(cap):
        gamma = float(rng.normal(slope, roughness)) if roughness > 0 else slope
        step = space_step(replace(model, slope=gamma), tilted(x, gamma - previous), scratch=scratch)
        if step.x_plus is None or not np.all(np.isfinite(step.x_plus)):
            return k, True
        x, previous = step.x_plus, gamma
    return cap, False
