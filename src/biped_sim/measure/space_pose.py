"""Where a walker in space (``Config.in_space``) is over a run, compliant or rigid: its legs' points in
3D, for drawing it (:mod:`biped_sim.picture`).

Each leg is drawn as the polyline from the hinge's midpoint to its hip point, out to its centre of mass and back,
and down to its foot's centre, and its foot as the shape the contact rolls on (:func:`foot_outline`), each curve
through the foot's lowest point: a ring as itself; a torus as its outer equator and its tube's section at the
bottom; a sphere or an ellipsoid as its three principal sections and its outline seen from the side (along the
slope's lateral axis, as the sagittal view sees it); a point foot as its centre. A ring or an equator too wide to
be drawn whole (:func:`~biped_sim.measure.pose.foot_arc_half_angle`; the 3D kneed walker's, 1.5 m round sideways)
is drawn as the arc of it that a foot is, about its bottom on the leg, which holds the contact point while the leg
has rolled less than its half-angle. The points come from the run's state (each leg's centre of mass and Euler
parameters, the spatial formulation's bodies) and the leg geometry of its description
(:func:`~biped_sim.walkers.space_geometry.leg_geometry`, the hip mass folded into the left leg as the compliant
builder does), in the slope frame (x downhill, y the slope's normal, z = x cross y: the walker's right).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.config.space_description import SpaceDescription
from biped_sim.io.trajectory import RunData
from biped_sim.measure.pose import foot_arc_half_angle
from biped_sim.rigid.space_cycle import space_walker_model
from biped_sim.rigid.space_model import KNEE_ANGLE, foot_bottom
from biped_sim.walkers.space_geometry import (
    EZ,
    TO_SPATIAL,
    LegGeometry,
    attitude,
    leg_geometry,
    rot_y,
    with_point_mass,
)

CIRCLE_POINTS = 33  # per closed curve of a foot, its first point where the curve is lowest
EY = np.array([0.0, 1.0, 0.0])  # the rigid slope frame's lateral axis: the sagittal view looks along it
ANGLES = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS)


@dataclass(frozen=True)
class SpacePoses:
    """A run's 3D poses in the slope frame [m]: per sample and leg, its polyline and its foot's outline."""

    time: np.ndarray  # (ns,)
    legs: np.ndarray  # (ns, 2, 5, 3): hinge midpoint, hip point, centre of mass, hip point, foot end (_walker_points)
    feet: np.ndarray  # (ns, 2, k, 3): the foot's closed curves of CIRCLE_POINTS, a row of NaN between two (k by shape)
    hip: np.ndarray  # (ns, 3): the hinge's midpoint
    torso: np.ndarray  # (ns, 2, 3): the hinge's midpoint and a torso's centre of mass (NaN without a torso)


def rotation_matrices(e: np.ndarray) -> np.ndarray:
    """(ns, 3, 3) rotations of Euler parameters ``e`` (ns, 4), normalised: A = (e0^2 - e.e) I + 2 e e^T + 2 e0 [e]x."""
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    e0, v = e[:, 0], e[:, 1:]
    cross = np.zeros((len(e), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    cross -= cross.transpose(0, 2, 1)
    identity = (e0**2 - np.sum(v * v, axis=1))[:, None, None] * np.eye(3)
    return identity + 2.0 * v[:, :, None] * v[:, None, :] + 2.0 * e0[:, None, None] * cross


def _unit(v: np.ndarray) -> np.ndarray:
    """(ns, 3) rows of ``v`` scaled to length 1."""
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _ellipse(centre: np.ndarray, a: np.ndarray, b: np.ndarray, angles: np.ndarray = ANGLES) -> np.ndarray:
    """(ns, CIRCLE_POINTS, 3): centre + cos(s) a + sin(s) b per sample (a, b: (ns, 3) or one (3,) for all), s over
    ``angles`` (by default the closed curve from s = 0, the point centre + a)."""
    c, s = np.cos(angles)[None, :, None], np.sin(angles)[None, :, None]
    return centre[:, None, :] + c * a[..., None, :] + s * b[..., None, :]


def _joined(curves: list[np.ndarray]) -> np.ndarray:
    """(ns, k, 3) closed curves one after the other, a row of NaN between two (matplotlib breaks the line there)."""
    gap = np.full((len(curves[0]), 1, 3), np.nan)
    return np.concatenate([part for curve in curves for part in (gap, curve)][1:], axis=1)


def foot_outline(leg: LegGeometry, rotation: np.ndarray, leg_length: float) -> np.ndarray:
    """(ns, k, 3) the foot drawn from the walker frame's origin, its leg turned by ``rotation`` (ns, 3, 3: walker
    frame -> rigid slope frame, z the slope's normal), from the ``LegGeometry`` the contact rolls on
    (:func:`~biped_sim.walkers.space_geometry.lowest_point`): every curve but a torus's equator starts at the foot's
    lowest point. A ring: itself; a torus: its outer equator (radius + tube, in its plane: its outline seen along its
    axis) and its tube's section at the bottom; either ring wider than a foot is drawn as :func:`ring_arc`'s arc; a
    sphere or an ellipsoid: :func:`_quadric_outline`; a point: its centre."""
    centre = rotation @ leg.foot_centre
    quadric = _quadric(leg)
    if quadric is not None:
        return _quadric_outline(quadric, rotation, centre)
    if leg.foot_normal is None:
        return np.repeat(centre[:, None, :], CIRCLE_POINTS, axis=1)
    n = rotation @ leg.foot_normal
    down = _unit(-(EZ - n[:, 2:] * n))  # in the plane, most against the normal: toward the lowest point
    along = np.cross(n, down)
    outer, arc = leg.foot_radius + leg.foot_tube, ring_arc(leg, leg_length)
    if arc is None:
        ring = _ellipse(centre, outer * down, outer * along)
    else:
        bottom = rotation @ arc[1]
        ring = _ellipse(
            centre, outer * bottom, outer * np.cross(n, bottom), np.linspace(-arc[0], arc[0], CIRCLE_POINTS)
        )
    if leg.foot_tube == 0.0:
        return ring
    section = _ellipse(centre + leg.foot_radius * down, -leg.foot_tube * EZ, leg.foot_tube * np.cross(along, -EZ))
    return _joined([ring, section])


def ring_arc(leg: LegGeometry, leg_length: float) -> tuple[float, np.ndarray] | None:
    """The arc drawn of a ring (a torus's outer equator) too wide to be drawn whole
    (:func:`~biped_sim.measure.pose.foot_arc_half_angle` below pi): its half-angle and its middle, the ring's bottom on
    the leg (a unit vector of the walker frame in the ring's plane, furthest down the leg, fixed in the leg as the
    foot is); None for a ring drawn whole and for the other shapes."""
    if leg.foot_normal is None:
        return None
    half = foot_arc_half_angle(leg.foot_radius + leg.foot_tube, leg_length)
    if half == math.pi:
        return None
    down_the_leg = -(EZ - (EZ @ leg.foot_normal) * leg.foot_normal)
    return half, down_the_leg / np.linalg.norm(down_the_leg)


def _quadric(leg: LegGeometry) -> np.ndarray | None:
    """The quadric Q of a foot whose points are centre + Q^(1/2) u, |u| = 1: an ellipsoid's (its ``foot_quadric``, as
    :func:`~biped_sim.walkers.space_geometry.lowest_point` tells it), a sphere's radius^2 I; None for the others."""
    if leg.foot_quadric[2, 2] > 0.0:
        return leg.foot_quadric
    return leg.foot_radius**2 * np.eye(3) if leg.foot_radius > 0.0 and leg.foot_normal is None else None


def _quadric_outline(quadric: np.ndarray, rotation: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """A sphere's or an ellipsoid's curves: its three principal sections (the ellipses through two of its semi-axes,
    turned with the leg) and its outline seen along the lateral axis EY, the ellipse of its points whose normal is
    across EY, starting at its lowest point. Its points are centre + A u, |u| = 1, A = Q^(1/2) (the quadric Q's
    semi-axes the square roots of its eigenvalues: :func:`_quadric`); the normal at A u is along A^-1 u, so
    the outline is A u for u across A^-1 EY, and the lowest point is A u at u = -A z / |A z| (there the normal is -z,
    across EY)."""
    eigenvalues, axes = np.linalg.eigh(quadric)
    semi = np.sqrt(eigenvalues)
    turned = rotation @ axes  # (ns, 3, 3): the principal axes, columns
    half = turned * semi @ turned.transpose(0, 2, 1)  # A, turned with the leg
    inverse = turned / semi @ turned.transpose(0, 2, 1)
    low = -_unit(half @ EZ)
    across = _unit(np.cross(inverse @ EY, low))
    pairs = ((0, 1), (1, 2), (2, 0))
    sections = [_ellipse(centre, semi[i] * turned[:, :, i], semi[j] * turned[:, :, j]) for i, j in pairs]
    outline = _ellipse(centre, np.einsum("sij,sj->si", half, low), np.einsum("sij,sj->si", half, across))
    return _joined([outline, *sections])


def space_poses(run: RunData) -> SpacePoses:
    """The 3D poses of a run of a walker in space, compliant or rigid (:func:`rigid_space_poses`)."""
    space = run.config.walker.space  # type: ignore[union-attr]
    legs = (with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1))
    if run.dynamics == "rigid":
        return rigid_space_poses(run, legs)
    names = run.state_names
    placed = []
    for leg, body in zip(legs, ("left", "right"), strict=True):
        columns = [names.index(f"{c}_{body}") for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
        rotation = TO_SPATIAL.T @ rotation_matrices(run.state[:, columns[3:]]) @ TO_SPATIAL  # walker -> rigid frame
        origin = run.state[:, columns[:3]] @ TO_SPATIAL - rotation @ leg.com
        placed.append((origin, rotation))
    return _poses(run.time, space, legs, placed)


def _walker_points(space: SpaceDescription, leg: LegGeometry, side: float) -> np.ndarray:
    """A leg's polyline in the walker frame: the hinge's midpoint, its hip point (the left leg's at +y), centre of
    mass (a kneed leg's: its knee, twice), hip point again, foot centre (a ring drawn as its arc: the arc's middle,
    its bottom on the leg, so that the leg reaches its foot, whose centre may be above the hip)."""
    hip_point = np.array([0.0, 0.5 * side * space.hip_width, 0.0])
    arc = ring_arc(leg, space.leg_length())
    end = leg.foot_centre if arc is None else leg.foot_centre + (leg.foot_radius + leg.foot_tube) * arc[1]
    if space.leg.knee is not None:
        knee = _knee_point(space, side)
        return np.vstack([np.zeros(3), hip_point, knee, knee, end])
    return np.vstack([np.zeros(3), hip_point, leg.com, hip_point, end])


def _knee_point(space: SpaceDescription, side: float) -> np.ndarray:
    """A kneed leg's knee in the walker frame: the left leg's (``side`` 1) or its mirror image's (-1)."""
    return np.array([1.0, side, 1.0]) * (np.array([0.0, 0.5 * space.hip_width, 0.0]) + space.leg.knee.at)


Placement = tuple[np.ndarray, np.ndarray]  # a frame's origin (ns, 3) and rotation (ns, 3, 3), rigid slope frame


def _poses(
    time: np.ndarray,
    space: SpaceDescription,
    legs: tuple[LegGeometry, LegGeometry],
    placed: list[Placement],
    shanks: list[Placement] | None = None,
    torso: np.ndarray | None = None,
) -> SpacePoses:
    """The poses of both legs, each ``placed`` at its walker frame's origin (ns, 3) and turned by its rotation
    (ns, 3, 3) in the rigid slope frame, in the spatial formulation's slope frame; the polyline's last point (the
    foot's end) and the foot placed by ``shanks`` (a kneed leg's shank; default ``placed``); a ``torso``'s line
    (ns, 2, 3), spatial slope frame, if any."""
    polylines, feet = [], []
    for k, (leg, (origin, rotation), (low_origin, low_rotation)) in enumerate(
        zip(legs, placed, shanks or placed, strict=True)
    ):
        body = _walker_points(space, leg, 1.0 - 2.0 * k)
        points = origin[:, None, :] + np.einsum("sij,kj->ski", rotation, body)
        points[:, -1] = low_origin + np.einsum("sij,j->si", low_rotation, body[-1])
        polylines.append(points @ TO_SPATIAL.T)
        feet.append((low_origin[:, None, :] + foot_outline(leg, low_rotation, space.leg_length())) @ TO_SPATIAL.T)
    legs_3d = np.stack(polylines, axis=1)
    torso = np.full((len(time), 2, 3), np.nan) if torso is None else torso
    return SpacePoses(time, legs_3d, np.stack(feet, axis=1), legs_3d[:, 0, 0], torso)


def rigid_space_poses(run: RunData, legs: tuple[LegGeometry, LegGeometry]) -> SpacePoses:
    """The 3D poses of a rigid run (:mod:`biped_sim.simulate.space_rigid`): its state holds the stance leg's
    attitude, the hinge angle and the stance contact point in the rigid model's slope frame (x downhill, y left,
    z the normal), a kneed walker's swing knee angle after them, a torso's angle from the stance leg; the stance leg
    is the left until the first strike, then the leg of the last strike (the step table's ``foot``). The hinge's
    midpoint sits above the contact point by the stance foot's bottom; a swing shank turns about its knee; a torso is
    drawn from the hinge's midpoint to its centre of mass."""
    space, model = run.config.walker.space, space_walker_model(run.config)  # type: ignore[union-attr]
    stance = np.zeros(len(run.time), dtype=int)
    for at, foot in zip(run.steps["strike_time"], run.steps["foot"], strict=True):
        stance[run.time >= at] = int(foot)
    hinge, turns = np.zeros((len(run.time), 3)), np.zeros((2, len(run.time), 3, 3))
    shank_origins, shank_turns = np.zeros((2, len(run.time), 3)), np.zeros((2, len(run.time), 3, 3))
    for i, (x, leg) in enumerate(zip(run.state, stance, strict=True)):
        rotation = attitude(x[0], x[1], x[2])
        turns[leg, i], turns[1 - leg, i] = rotation, rotation @ rot_y(x[3])
        hinge[i] = np.array([x[8], x[9], 0.0]) - foot_bottom(model.feet[leg], rotation)[0]
        shank_origins[:, i], shank_turns[:, i] = hinge[i], turns[:, i]
        if model.knee is not None:
            knee = _knee_point(space, 1.0 - 2.0 * (1 - leg))  # the swing leg's
            shank_turns[1 - leg, i] = turns[1 - leg, i] @ rot_y(x[KNEE_ANGLE])
            shank_origins[1 - leg, i] += (turns[1 - leg, i] - shank_turns[1 - leg, i]) @ knee
    placed = [(hinge, turns[0]), (hinge, turns[1])]
    torso = None
    if model.torso is not None:
        com = model.parts[-1].com  # the torso is the last part, its joint at the hinge's midpoint
        stance_turns = turns[stance, np.arange(len(run.time))]
        angles = run.state[:, model.torso_angle]
        tilted = np.array([turn @ rot_y(a) @ com for turn, a in zip(stance_turns, angles, strict=True)])
        torso = np.stack([hinge, hinge + tilted], axis=1) @ TO_SPATIAL.T
    return _poses(run.time, space, legs, placed, [(shank_origins[k], shank_turns[k]) for k in (0, 1)], torso)
