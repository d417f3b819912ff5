"""A described walker's planar model started (:func:`build_described`): its bodies' angles from the start's keys, the
tree rolling on its stance leg's foot (:func:`tree_start`), the start's modes (:func:`settle_start_modes`: the mode
update, then the stance leg's latches held, as the rigid model's stance knee is locked).

:func:`described_start` stops short of the modes, so that a walker in space (:mod:`biped_sim.walkers.spatial_described`)
settles them once, on its own system at its lifted start: the planar update would compile the planar event machinery
for a run that never calls it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from biped_sim.config import Config, InitialState
from biped_sim.contact.response import IMPACT_SPEED, TOUCHING
from biped_sim.contact.stop import FOOT, HELD, LATCHED
from biped_sim.errors import ConfigError
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.spatial import SpatialSystem
from biped_sim.walkers.describe import describe
from biped_sim.walkers.described import (
    Tree,
    fall_angles,
    leg_feet,
    planar_tree_system,
    resolve_tree,
    rotate,
    stance_feet,
)
from biped_sim.walkers.model import (
    BuiltModel,
    contact_stiffness,
    standing_start,
    static_contact_penetration,
    update_start_modes,
)


def latch_stance(system: PlanarSystem, tree: Tree, modes0: np.ndarray, rate: float) -> None:
    """Hold the stance leg's latches in ``modes0`` (the rigid model's straight stance knee at the start),
    remembering ``rate`` [rad/s] as their approach rate."""
    nf = system.foot_body.shape[0]
    stance_feet = leg_feet(tree)[0]
    for s, foot in enumerate(system.stops.latch[:, FOOT]):
        if foot in stance_feet:
            modes0[nf + s, LATCHED], modes0[nf + s, TOUCHING] = HELD, 1.0
            modes0[nf + s, IMPACT_SPEED] = rate


def body_angles(tree: Tree, initial: InitialState | Mapping[str, float], keys: list[str]) -> np.ndarray:
    """(nb, 2): each body's angle and rate from the initial-state ``keys`` (stance leg, then swing leg, hip down,
    then the bodies off the legs, ``<name>_angle`` and ``<name>_rate``, 0 when not given)."""
    values = initial.model_dump() if isinstance(initial, InitialState) else dict(initial)
    state = np.zeros((len(tree.names), 2))
    per_leg = 2 * len(tree.legs[0])
    for leg, bodies in enumerate(tree.legs[:2]):
        for k, b in enumerate(bodies):
            offset = leg * per_leg + 2 * k
            state[b] = values[keys[offset]], values[keys[offset + 1]]
    on_legs = {b for leg in tree.legs for b in leg}
    for b in (b for b in range(len(tree.names)) if b not in on_legs):
        state[b] = values.get(f"{tree.names[b]}_angle", 0.0), values.get(f"{tree.names[b]}_rate", 0.0)
    return state


def angle_key(tree: Tree, keys: list[str], b: int) -> tuple[str, str]:
    """(body b's initial angle key, the limit it is held to): a leg's body in ``keys``' order (stance leg, then swing
    leg, hip down) against simulation.fall_leg_angle, a body off the legs its ``<name>_angle`` against its own."""
    per_leg = 2 * len(tree.legs[0])
    for leg, bodies in enumerate(tree.legs[:2]):
        if b in bodies:
            return keys[leg * per_leg + 2 * list(bodies).index(b)], "simulation.fall_leg_angle"
    return f"{tree.names[b]}_angle", f"the fall_angle of the body {tree.names[b]!r}"


def tree_start(
    tree: Tree, angles: np.ndarray, static_penetration: float, config: Config, length: float, keys: list[str]
) -> tuple[np.ndarray, np.ndarray, float]:
    """(coords (nb, 3), rates (nb, 3), hip speed) of the walker rolling on its stance foot.

    The stance foot (the first of :func:`stance_feet`) touches the ground at x = 0, sunk by
    ``static_penetration``; its body rolls about the contact point, and each body's origin follows up the
    stance leg to the hip (the joints shared) and down the other bodies from their parents. ConfigError naming
    the initial-state key (of ``keys``) of a body that would start fallen.
    """
    limits = fall_angles(tree, config)
    for b in range(len(tree.names)):
        if abs(angles[b, 0]) >= limits[b]:
            key, limit = angle_key(tree, keys, b)
            raise ConfigError(f"simulation.initial.{key}", f"beyond {limit}: the walker starts fallen")
    foot = stance_feet(tree)[0]
    contact = np.array([0.0, -static_penetration])
    nb = len(tree.names)
    origin, velocity = np.zeros((nb, 2)), np.zeros((nb, 2))
    b = int(tree.foot_body[foot])
    origin[b] = contact + np.array([0.0, tree.foot_radius[foot]]) - rotate(angles[b, 0], tree.foot_centre[foot])
    velocity[b] = angles[b, 1] * _perp(origin[b] - contact)
    chain = [b]
    while tree.parent[chain[-1]] >= 0:  # up the stance leg: the child's origin is the parent's joint point
        child, p = chain[-1], int(tree.parent[chain[-1]])
        origin[p] = origin[child] - rotate(angles[p, 0], tree.joint_at[child])
        velocity[p] = velocity[child] - angles[p, 1] * _perp(origin[child] - origin[p])
        chain.append(p)
    for c in range(nb):  # down the other bodies (parents first)
        if c not in chain:
            p = int(tree.parent[c])
            arm = rotate(angles[p, 0], tree.joint_at[c])
            origin[c], velocity[c] = origin[p] + arm, velocity[p] + angles[p, 1] * _perp(arm)
    if origin[0, 1] <= config.simulation.fall_hip_height * length:
        raise ConfigError("simulation.initial", "the hip starts below simulation.fall_hip_height")
    if not config.contact.scuffing_guard:
        _check_swing_feet(tree, angles, origin)
    arms = np.array([rotate(angles[c, 0], tree.com[c]) for c in range(nb)])
    coms = origin + arms
    com_velocity = velocity + angles[:, 1:2] * np.array([_perp(a) for a in arms])
    com_velocity[b] = angles[b, 1] * _perp(coms[b] - contact)  # the rolling body: about the contact point
    coords = np.column_stack([coms, angles[:, 0]])
    rates = np.column_stack([com_velocity, angles[:, 1]])
    return coords, rates, float(np.hypot(*velocity[0]))


def _check_swing_feet(tree: Tree, angles: np.ndarray, origin: np.ndarray) -> None:
    """ConfigError when a foot off the stance leg starts below the ground (which no scuffing guard lifts)."""
    for foot in (f for leg in leg_feet(tree)[1:] for f in leg):
        b = int(tree.foot_body[foot])
        if origin[b, 1] + rotate(angles[b, 0], tree.foot_centre[foot])[1] - tree.foot_radius[foot] < 0.0:
            raise ConfigError(
                "simulation.initial", "the swing foot starts below the ground (and contact.scuffing_guard is off)"
            )


def _perp(v: np.ndarray) -> np.ndarray:
    """The vector v turned by +90 degrees: omega x v is omega perp(v)."""
    return np.array([-v[1], v[0]])


class DescribedStart(NamedTuple):
    """A described walker's planar model before the start's mode update and latches (:func:`settle_start_modes`)."""

    model: BuiltModel
    tree: Tree
    latch_rate: float  # [rad/s] the stance leg's latches' approach rate


def build_described(config: Config, initial: InitialState | Mapping[str, float]) -> BuiltModel:
    """Bodies, joints, stops and feet of the walker's description, started rolling on its stance foot, the stance
    leg's latches engaged (their approach rate the stance foot's remembered impact speed over the leg length)."""
    start = described_start(config, initial)
    settle_start_modes(start, start.model.system, start.model.y0)
    return start.model


def settle_start_modes(start: DescribedStart, system: PlanarSystem | SpatialSystem, y0: np.ndarray) -> None:
    """The start's modes (``start.model.modes0``, in place): the mode update of ``system`` at ``y0`` (the planar
    model's own, or the same walker's in space: the feet's and stops' rows are the same), then the stance leg's
    latches held."""
    update_start_modes(system, y0, start.model.modes0)
    latch_stance(start.model.system, start.tree, start.model.modes0, start.latch_rate)


def described_start(config: Config, initial: InitialState | Mapping[str, float]) -> DescribedStart:
    """:func:`build_described` but the start's mode update and latches."""
    description = describe(config)
    tree = resolve_tree(description)
    length = description.leg_length()
    radius = float(np.max(tree.foot_hertz))
    stiffness = contact_stiffness(config, radius)
    total_mass = float(np.sum(tree.mass))
    system = planar_tree_system(tree, config, stiffness, length)
    feet = stance_feet(tree)  # each carries its share of the weight
    static_penetration = static_contact_penetration(config, total_mass / len(feet), stiffness, length)
    keys = description.state_keys()
    angles = body_angles(tree, initial, keys)
    coords, rates, hip_speed = tree_start(tree, angles, static_penetration, config, length, keys)
    impact = max(hip_speed, config.contact.impact_velocity_floor)
    y0, modes0 = standing_start(system, coords, rates, feet, impact, update_modes=False)
    model = BuiltModel(
        system=system,
        y0=y0,
        modes0=modes0,
        body_names=tree.names,
        foot_names=tree.foot_names,
        leg_length=length,
        total_mass=total_mass,
        stiffness=stiffness,
        meta={"static_penetration": static_penetration},
    )
    return DescribedStart(model, tree, impact / length)
