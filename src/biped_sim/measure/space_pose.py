"""Where a walker in space (``Config.in_space``) is over a run, compliant or rigid: its legs' points in
3D, for drawing it (:mod:`biped_sim.picture`).

Each leg is drawn as the polyline from the hinge's midpoint to its hip point, out to its centre of mass and back,
and down to its foot's centre, and
its foot as a circle: a ring in its plane, a sphere's great circle in the leg's sagittal (x-z) plane, a point foot
none. The points come from the run's state (each leg's centre of mass and Euler parameters, the spatial
formulation's bodies) and the leg geometry of its description (:func:`~biped_sim.walkers.space_geometry.leg_geometry`,
the hip mass folded into the left leg as the compliant builder does), in the slope frame (x downhill, y the
slope's normal, z = x cross y: the walker's right).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from biped_sim.config.space_description import SpaceDescription
from biped_sim.io.trajectory import RunData
from biped_sim.rigid.space_cycle import space_walker_model
from biped_sim.rigid.space_model import foot_bottom
from biped_sim.walkers.space_geometry import (
    TO_SPATIAL,
    LegGeometry,
    attitude,
    leg_geometry,
    rot_y,
    with_point_mass,
)

CIRCLE_POINTS = 33


@dataclass(frozen=True)
class SpacePoses:
    """A run's 3D poses in the slope frame [m]: per sample and leg, its polyline and its foot's circle."""

    time: np.ndarray  # (ns,)
    legs: np.ndarray  # (ns, 2, 5, 3): hinge midpoint, hip point, centre of mass, hip point, foot centre
    feet: np.ndarray  # (ns, 2, CIRCLE_POINTS, 3): the foot's circle (all at its centre for a point foot)
    hip: np.ndarray  # (ns, 3): the hinge's midpoint


def rotation_matrices(e: np.ndarray) -> np.ndarray:
    """(ns, 3, 3) rotations of Euler parameters ``e`` (ns, 4), normalised: A = (e0^2 - e.e) I + 2 e e^T + 2 e0 [e]x."""
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    e0, v = e[:, 0], e[:, 1:]
    cross = np.zeros((len(e), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    cross -= cross.transpose(0, 2, 1)
    identity = (e0**2 - np.sum(v * v, axis=1))[:, None, None] * np.eye(3)
    return identity + 2.0 * v[:, :, None] * v[:, None, :] + 2.0 * e0[:, None, None] * cross


def foot_circle(leg: LegGeometry) -> np.ndarray:
    """(CIRCLE_POINTS, 3) the foot's circle in the walker frame: in a ring's plane, else in the leg's x-z plane."""
    normal = np.array([0.0, 1.0, 0.0]) if leg.foot_normal is None else leg.foot_normal
    u = np.cross(normal, [0.0, 0.0, 1.0])
    u = u / np.linalg.norm(u) if np.linalg.norm(u) > 1e-12 else np.array([1.0, 0.0, 0.0])
    w = np.cross(normal, u)
    angle = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS)
    return leg.foot_centre + leg.foot_radius * (np.outer(np.cos(angle), u) + np.outer(np.sin(angle), w))


def space_poses(run: RunData) -> SpacePoses:
    """The 3D poses of a run of a walker in space, compliant or rigid (:func:`rigid_space_poses`)."""
    space = run.config.walker.space  # type: ignore[union-attr]
    legs = (with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1))
    if run.dynamics == "rigid":
        return rigid_space_poses(run, legs)
    names = run.state_names
    polylines, circles = [], []
    for leg, body, side in zip(legs, ("left", "right"), (1.0, -1.0), strict=True):
        columns = [names.index(f"{c}_{body}") for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
        centre, rotation = run.state[:, columns[:3]], rotation_matrices(run.state[:, columns[3:]])
        body_points = (_walker_points(space, leg, side) - leg.com) @ TO_SPATIAL.T
        points = centre[:, None, :] + np.einsum("sij,kj->ski", rotation, body_points)
        polylines.append(points[:, :5])
        circles.append(points[:, 5:])
    return _poses(run.time, polylines, circles)


def _walker_points(space: SpaceDescription, leg: LegGeometry, side: float) -> np.ndarray:
    """A leg's drawn points in the walker frame: the hinge's midpoint, its hip point (the left leg's at +y), centre
    of mass, hip point again, foot centre, then its foot's circle."""
    hip_point = np.array([0.0, 0.5 * side * space.hip_width, 0.0])
    return np.vstack([np.zeros(3), hip_point, leg.com, hip_point, leg.foot_centre, foot_circle(leg)])


def _poses(time: np.ndarray, polylines: list[np.ndarray], circles: list[np.ndarray]) -> SpacePoses:
    legs_3d = np.stack(polylines, axis=1)
    return SpacePoses(time, legs_3d, np.stack(circles, axis=1), legs_3d[:, 0, 0])


def rigid_space_poses(run: RunData, legs: tuple[LegGeometry, LegGeometry]) -> SpacePoses:
    """The 3D poses of a rigid run (:mod:`biped_sim.simulate.space_rigid`): its state holds the stance leg's
    attitude, the hinge angle and the stance contact point in the rigid model's slope frame (x downhill, y left,
    z the normal); the stance leg is the left until the first strike, then the leg of the last strike (the step
    table's ``foot``). The hinge's midpoint sits above the contact point by the stance foot's bottom."""
    space, feet = run.config.walker.space, space_walker_model(run.config).feet  # type: ignore[union-attr]
    stance = np.zeros(len(run.time), dtype=int)
    for at, foot in zip(run.steps["strike_time"], run.steps["foot"], strict=True):
        stance[run.time >= at] = int(foot)
    points = {0: [], 1: []}
    for x, leg in zip(run.state, stance, strict=True):
        rotation = attitude(x[0], x[1], x[2])
        turns = {leg: rotation, 1 - leg: rotation @ rot_y(x[3])}
        hinge = np.array([x[8], x[9], 0.0]) - foot_bottom(feet[leg], rotation)[0]
        for k in (0, 1):
            points[k].append(hinge + _walker_points(space, legs[k], 1.0 - 2.0 * k) @ turns[k].T)
    world = [np.array(points[k]) @ TO_SPATIAL.T for k in (0, 1)]
    return _poses(run.time, [w[:, :5] for w in world], [w[:, 5:] for w in world])
