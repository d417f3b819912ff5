"""The rigid walker in space: its parts and feet in the walker frame, its attitude, and where its points are.

The walker frame is the stance leg's: origin at the hinge's midpoint, x forward, y along the hinge (to the
left), z up the leg. The stance leg is always the left leg (the description's): the step map mirrors the walker
(y -> -y) after each strike, so the right leg's step is the left leg's mirror image. The swing leg is the
stance leg's frame turned by the hinge angle ``beta`` about y (positive: the swing foot behind).

State ``x`` (the slope frame: x downhill, y left, z along the slope normal): heading psi, bank phi, pitch theta of
the stance leg, R = Rz(psi) Rx(phi) Ry(theta) (pitch positive with the leg's top downhill), the hinge angle
beta, the stance leg's angular velocity (slope frame), the hinge rate, and the stance contact point (x, y) on
the ground: ``STATE_NAMES``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from biped_sim.config.space_description import SpaceDescription
from biped_sim.walkers.space_geometry import EZ, MIRROR, attitude, cross, rot_x, rot_y, rot_z

STATE_NAMES = ("heading", "bank", "pitch", "swing_angle", "omega_x", "omega_y", "omega_z", "swing_rate", "x", "y")
N_STATE = len(STATE_NAMES)
POINT, SPHERE, RING, TORUS, ELLIPSOID = 0, 1, 2, 3, 4
SHAPES = {"point": POINT, "sphere": SPHERE, "ring": RING, "torus": TORUS, "ellipsoid": ELLIPSOID}


def attitude_angles(r: np.ndarray) -> tuple[float, float, float]:
    """(psi, phi, theta) of a rotation R = Rz(psi) Rx(phi) Ry(theta), |phi| < pi / 2."""
    return (
        math.atan2(-r[0, 1], r[1, 1]),
        math.asin(max(-1.0, min(1.0, r[2, 1]))),
        math.atan2(-r[2, 0], r[2, 2]),
    )


def rate_matrix(psi: float, phi: float) -> np.ndarray:
    """E with omega = E (psi', phi', theta'): the axes of the three rotations in the slope frame, as columns."""
    return np.column_stack((EZ, rot_z(psi)[:, 0], (rot_z(psi) @ rot_x(phi))[:, 1]))


@dataclass(frozen=True)
class Part:
    """A rigid part: on the stance leg (frame 0) or the swing leg (frame 1); mass, centre of mass and inertia
    about it, in the walker frame with the hinge at zero."""

    frame: int
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class Foot:
    """A foot in the walker frame with the hinge at zero: its shape code, centre, radius, a ring's or torus's unit
    normal, a torus's tube radius and an ellipsoid's quadric Q (its points centre + Q^(1/2) u, |u| = 1; zero for
    the other shapes)."""

    shape: int
    centre: np.ndarray
    radius: float
    normal: np.ndarray
    tube: float = 0.0
    quadric: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))


@dataclass(frozen=True)
class SpaceModel:
    """The walker in its frame: parts (stance leg, swing leg, a hip mass), the two feet, gravity and slope."""

    parts: tuple[Part, ...]
    feet: tuple[Foot, Foot]
    gravity: float
    slope: float
    leg_length: float

    @property
    def gravity_vector(self) -> np.ndarray:
        """Gravity in the slope frame (x downhill, z along the normal)."""
        return self.gravity * np.array([math.sin(self.slope), 0.0, -math.cos(self.slope)])


def _leg(space: SpaceDescription, frame: int) -> tuple[Part, Foot]:
    """The left leg (frame 0) or its mirror image, the right leg (frame 1), in the walker frame."""
    leg, foot = space.leg, space.leg.foot
    hip = np.array([0.0, 0.5 * space.hip_width, 0.0])
    mirror = MIRROR if frame == 1 else np.eye(3)
    com = mirror @ (hip + np.array(leg.com))
    inertia = mirror @ leg.inertia.matrix() @ mirror
    normal = mirror @ (np.array(foot.normal) / np.linalg.norm(foot.normal))
    quadric = mirror @ foot.quadric() @ mirror
    centre = mirror @ (hip + np.array(foot.centre))
    shape = SHAPES[foot.shape]
    return Part(frame, leg.mass, com, inertia), Foot(shape, centre, foot.radius, normal, foot.tube, quadric)


def space_model(space: SpaceDescription, gravity: float, slope: float) -> SpaceModel:
    """The model of a description in space on a slope of ``slope`` rad under ``gravity``."""
    stance, stance_foot = _leg(space, 0)
    swing, swing_foot = _leg(space, 1)
    parts = (stance, swing) + ((Part(0, space.hip_mass, np.zeros(3), np.zeros((3, 3))),) if space.hip_mass else ())
    return SpaceModel(parts, (stance_foot, swing_foot), gravity, slope, space.leg_length())


def foot_bottom(foot: Foot, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The foot's lowest point from its frame's origin (slope frame) and the unit vector d from its centre toward it
    (a ring: the direction in its plane most against the normal; a sphere: -z; a point: zero). A torus's lowest
    point is its tube's centre circle's (the ring's) lowered by the tube radius: the tube's section there is a
    circle in the vertical plane through d, its lowest point straight below its centre. An ellipsoid's d is not a
    unit vector but its whole offset -Q z / sqrt(z' Q z) (Q turned with the leg), where the normal is -z."""
    centre = rotation @ foot.centre
    if foot.shape == POINT:
        return centre, np.zeros(3)
    if foot.shape == ELLIPSOID:
        q = rotation @ foot.quadric @ rotation.T
        offset = -q[:, 2] / math.sqrt(q[2, 2])
        return centre + offset, offset
    if foot.shape == SPHERE:
        return centre - foot.radius * EZ, -EZ
    n = rotation @ foot.normal
    w = EZ - n[2] * n
    d = -w / np.linalg.norm(w)
    return centre + foot.radius * d - foot.tube * EZ, d


def bottom_direction_rate(foot: Foot, rotation: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Time derivative of :func:`foot_bottom`'s d for a foot turning at ``omega`` (zero but for a ring, torus or
    ellipsoid)."""
    if foot.shape == ELLIPSOID:
        q = rotation @ foot.quadric @ rotation.T
        spin = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]], [-omega[1], omega[0], 0.0]])
        q_dot = spin @ q - q @ spin
        s = math.sqrt(q[2, 2])
        return -q_dot[:, 2] / s + q[:, 2] * q_dot[2, 2] / (2.0 * s**3)
    if foot.shape not in (RING, TORUS):
        return np.zeros(3)
    n = rotation @ foot.normal
    n_dot = cross(omega, n)
    w = EZ - n[2] * n
    norm = np.linalg.norm(w)
    w_dot = -n_dot[2] * n - n[2] * n_dot
    unit = w / norm
    return -(w_dot - unit * (unit @ w_dot)) / norm


@dataclass(frozen=True)
class Pose:
    """Where the walker is, from its stance contact point (slope frame): the legs' rotations, the hinge axis, the
    hinge's midpoint, and the stance foot's d (:func:`foot_bottom`)."""

    rotations: tuple[np.ndarray, np.ndarray]
    hinge: np.ndarray
    origin: np.ndarray
    stance_d: np.ndarray

    def point(self, frame: int, local: np.ndarray) -> np.ndarray:
        """A point of leg ``frame`` given in the walker frame, from the stance contact point."""
        return self.origin + self.rotations[frame] @ local


def pose(model: SpaceModel, x: np.ndarray) -> Pose:
    """The walker's pose in state ``x``."""
    stance = attitude(x[0], x[1], x[2])
    swing = stance @ rot_y(x[3])
    bottom, d = foot_bottom(model.feet[0], stance)
    return Pose((stance, swing), stance[:, 1], -bottom, d)


def swing_clearance(model: SpaceModel, x: np.ndarray) -> float:
    """The swing foot's lowest point above the slope (the stance foot's is on it)."""
    where = pose(model, x)
    bottom, _ = foot_bottom(model.feet[1], where.rotations[1])
    return float(where.origin[2] + bottom[2])
