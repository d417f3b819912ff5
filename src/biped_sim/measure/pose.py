"""Where each body of a walker is over a run: its poses, for drawing it (:mod:`biped_sim.picture`).

A pose is the walker's sagittal view at one sample, in the slope frame (x downhill along the slope, y along its
normal): each body as its segment (from its origin, the joint to its parent, to its children's joints and its
feet's centres; a body with neither, a torso, to its centre of mass), each foot an arc or a point, the hip, and
each joint stop with whether it is engaged. Everything comes from the run's resolved walker description
(:func:`biped_sim.walkers.describe.describe`: a described walker's own, a bundled kind's expansion) and from two
things every run file holds: the hip's path and each body's angle. A compliant run names its bodies in its state
(planar and minimal ``phi_<body>``, spatial the pitch of ``x_<body>``); a rigid run's state holds the angles in
role order (the stance leg's bodies from the hip down, then the swing leg's), relabelled at each heel strike, so
step k's stance leg is the description's leg k mod 2 (a wheel's stance spoke its foot k mod N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.config import WalkerDescription
from biped_sim.io.trajectory import RunData
from biped_sim.walkers.describe import describe

STOP_TOLERANCE = 1e-3  # rad: a joint within this of its stop (or past it) is drawn at its stop
FOOT_ARC_HALF_ANGLE = 0.8  # rad: the most of a planar foot's arc drawn on each side of its body's axis (a rocker)
FOOT_HALF_WIDTH = 0.4  # leg lengths: the widest a round foot is drawn on each side of its bottom


def foot_arc_half_angle(radius: float, leg_length: float) -> float:
    """The half-angle [rad] of the arc of a round foot of ``radius`` drawn about its bottom, the foot that exists (a
    description gives no span of a foot's arc): the whole circle (pi) of a foot no wider than FOOT_HALF_WIDTH leg
    lengths on each side of its bottom, else the arc of that half-width, R sin(theta) = FOOT_HALF_WIDTH l, so that a
    foot of large radius (the 3D kneed walker's, 1.5 m sideways on a 1 m leg) is drawn as a foot, not as a circle
    around the walker. The arc holds the contact point while the foot has rolled less than theta from its bottom
    (0.41 rad for a foot as round as the leg is long: a leg's swing, some 0.3 rad, stays on it)."""
    reach = FOOT_HALF_WIDTH * leg_length
    return math.pi if radius <= reach else math.asin(reach / radius)


@dataclass(frozen=True)
class Skeleton:
    """A description's geometry for drawing, bodies in the description's order (body frames: origin at the joint
    to the parent, -y along the body)."""

    names: list[str]
    parent: np.ndarray  # (nb,) int, -1 for the root (whose origin is the hip)
    leg_of: np.ndarray  # (nb,) int: the leg holding the body, -1 for a body off the legs (a torso)
    joint_at: np.ndarray  # (nb, 2) the body's origin in its parent's frame
    ends: list[np.ndarray]  # per body (k, 2): the points its segment reaches, in its frame
    foot_body: np.ndarray  # (nf,) int
    foot_centre: np.ndarray  # (nf, 2) in the body frame: the centre of the arc the foot rolls on in the sagittal plane
    foot_radius: np.ndarray  # (nf,) that arc's radius
    foot_half_angle: np.ndarray  # (nf,) the arc drawn on each side of the body's axis [rad] (foot_arc_half_angle)
    stops: list[tuple[int, int, str, float]]  # (parent, child, side, limit) of every joint stop
    total_mass: float  # kg (the bodies and point masses)


def skeleton(description: WalkerDescription) -> Skeleton:
    """The :class:`Skeleton` of a walker description."""
    names = [b.name for b in description.bodies]
    index = {name: k for k, name in enumerate(names)}
    parent = np.full(len(names), -1, dtype=np.int64)
    joint_at = np.zeros((len(names), 2))
    ends: list[list[tuple[float, float]]] = [[] for _ in names]
    stops = []
    for joint in description.joints:
        c, p = index[joint.child], index[joint.parent]
        parent[c], joint_at[c] = p, joint.at
        if any(joint.at):  # a joint at the parent's origin (the hip) adds nothing to its segment
            ends[p].append(joint.at)
        stops += [(p, c, stop.side, stop.angle) for stop in joint.stops]
    arcs = [foot.sagittal_arc() for foot in description.feet]  # a ring off the sagittal plane: its sagittal section
    for foot, (centre, _) in zip(description.feet, arcs, strict=True):
        ends[index[foot.body]].append(centre)
    for k, body in enumerate(description.bodies):
        if not ends[k]:  # a body off the legs (a torso): up to its centre of mass, its point masses folded in
            parts = [(body.mass, body.com)] + [(p.mass, p.at) for p in description.point_masses if p.body == body.name]
            mass = sum(m for m, _ in parts)
            ends[k].append(tuple(sum(m * np.array(at) for m, at in parts) / mass) if mass > 0 else body.com)
    masses = [b.mass for b in description.bodies] + [p.mass for p in description.point_masses]
    leg_length = description.leg_length()
    return Skeleton(
        names=names,
        parent=parent,
        leg_of=np.array([next((k for k, leg in enumerate(description.legs) if n in leg), -1) for n in names]),
        joint_at=joint_at,
        ends=[np.array(points, dtype=float).reshape(-1, 2) for points in ends],
        foot_body=np.array([index[f.body] for f in description.feet], dtype=np.int64),
        foot_centre=np.array([centre for centre, _ in arcs], dtype=float).reshape(-1, 2),
        foot_radius=np.array([radius for _, radius in arcs], dtype=float),
        foot_half_angle=np.array([min(FOOT_ARC_HALF_ANGLE, foot_arc_half_angle(r, leg_length)) for _, r in arcs]),
        stops=stops,
        total_mass=float(sum(masses)),
    )


@dataclass(frozen=True)
class Pose:
    """The walker at one sample, in the slope frame [m]."""

    time: float
    hip: np.ndarray  # (2,)
    segments: list[np.ndarray]  # per body (2 k, 2): its origin and each point it reaches in turn
    angles: np.ndarray  # (nb,) each body's angle [rad] (its -y axis from the slope normal)
    foot_centres: np.ndarray  # (nf, 2)
    joints: np.ndarray  # (n_stops, 2) where each stopped joint is (the child's origin)
    engaged: np.ndarray  # (n_stops,) bool: the joint at or past its stop


def _rotate(angles: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(ns, 2): v (2,) in a frame turned by each angle."""
    c, s = np.cos(angles), np.sin(angles)
    return np.column_stack([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _turn(angle: float, points: np.ndarray) -> np.ndarray:
    """(k, 2): points (k, 2) of a body frame turned by the body's angle."""
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


@dataclass(frozen=True)
class Poses:
    """A run's poses: its skeleton, each body's angle and origin at every sample."""

    skeleton: Skeleton
    time: np.ndarray  # (ns,)
    hip: np.ndarray  # (ns, 2)
    angles: np.ndarray  # (ns, nb)
    origins: np.ndarray  # (ns, nb, 2)

    @classmethod
    def from_angles(cls, sk: Skeleton, time: np.ndarray, hip: np.ndarray, angles: np.ndarray) -> Poses:
        """Each body's origin from the root's (the hip), down the tree."""
        origins = np.zeros((len(time), len(sk.names), 2))
        origins[:, 0] = hip
        placed = {0}  # a description lists its bodies in any order (the root first): parents before children
        while len(placed) < len(sk.names):
            for b in range(len(sk.names)):
                p = int(sk.parent[b])
                if b not in placed and p in placed:
                    origins[:, b] = origins[:, p] + _rotate(angles[:, p], sk.joint_at[b])
                    placed.add(b)
        return cls(sk, time, hip, angles, origins)

    def at(self, i: int) -> Pose:
        """The pose at sample ``i``."""
        sk, angles, origins = self.skeleton, self.angles[i], self.origins[i]
        segments = [  # from the origin out to each end (a star: a wheel's spokes)
            np.vstack([np.vstack([origins[b], end]) for end in origins[b] + _turn(angles[b], ends)])
            for b, ends in enumerate(sk.ends)
        ]
        feet = origins[sk.foot_body] + np.array(
            [_turn(angles[b], c[None])[0] for b, c in zip(sk.foot_body, sk.foot_centre, strict=True)]
        ).reshape(-1, 2)
        relative = np.array([angles[c] - angles[p] for p, c, _, _ in sk.stops])
        limits = np.array([limit for *_, limit in sk.stops])
        upper = np.array([side == "upper" for _, _, side, _ in sk.stops], dtype=bool)
        engaged = np.where(upper, relative >= limits - STOP_TOLERANCE, relative <= limits + STOP_TOLERANCE)
        joints = np.array([origins[c] for _, c, _, _ in sk.stops]).reshape(-1, 2)
        return Pose(float(self.time[i]), self.hip[i], segments, angles, feet, joints, engaged.astype(bool))


def run_poses(run: RunData) -> Poses:
    """The poses of a finished run, compliant or rigid, from its resolved description."""
    description = describe(run.config)
    sk = skeleton(description)
    angles = _rigid_angles(run, description) if run.dynamics == "rigid" else _compliant_angles(run, sk)
    return Poses.from_angles(sk, run.time, run.hip[:, :2], angles)


def _compliant_angles(run: RunData, sk: Skeleton) -> np.ndarray:
    """(ns, nb) in the description's order, from the run's bodies by name."""
    by_name = dict(zip(run.body_names, run.leg_angles().T, strict=True))
    return np.column_stack([by_name[name] for name in sk.names])


def _rigid_angles(run: RunData, description: WalkerDescription) -> np.ndarray:
    """(ns, nb) in the description's order from a rigid run's role-ordered angles: step k (the samples from strike
    k on; a sample at a strike's time holds the state after it) has the description's leg k mod 2 in stance, a
    wheel its foot k mod N (the body's angle being the stance spoke's less the spoke's angle in the body)."""
    names = [b.name for b in description.bodies]
    step = np.searchsorted(run.steps["strike_time"], run.time, side="right")
    roles = [column for column, name in enumerate(run.state_names) if name.endswith("_angle")]
    angles = np.zeros((len(run.time), len(names)))
    if len(description.legs) == 1:
        spokes = np.array([math.atan2(f.centre[0], -f.centre[1]) for f in description.feet])
        angles[:, names.index(description.legs[0][0])] = run.state[:, roles[0]] - spokes[step % len(spokes)]
        return angles
    for parity in (0, 1):
        order = [b for leg in (description.legs[parity], description.legs[1 - parity]) for b in leg]
        rows = step % 2 == parity
        for column, name in zip(roles, order, strict=True):
            angles[rows, names.index(name)] = run.state[rows, column]
    return angles
