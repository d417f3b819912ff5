"""Where a walker in space (``Config.in_space``) has its parts, and where its rigid gait puts them.

Frames: the walker frame is the stance (left) leg's with the hinge at zero (origin at the hinge's midpoint, x
forward, y along the hinge to the left, z up the leg); the rigid model's slope frame is x downhill, y left, z
along the slope normal (:mod:`biped_sim.rigid.space_model`). The spatial formulation's slope frame is x downhill,
y along the normal, z to the right (:mod:`biped_sim.multibody.spatial`): the proper rotation ``TO_SPATIAL``
(x, y, z) -> (x, z, -y) takes the one to the other, and each leg's body frame is its walker frame turned so
(x' forward, y' up the leg, z' along the hinge to the right, as the other spatial walkers' frames).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from biped_sim.config.space_description import SpaceDescription

TO_SPATIAL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
MIRROR = np.diag([1.0, -1.0, 1.0])  # y -> -y: the right leg is the left's image
EZ = np.array([0.0, 0.0, 1.0])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b of two 3-vectors: np.cross's arithmetic (the same bits) without its axis handling, which costs ten times
    the product on vectors this small."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def rot_x(a: float) -> np.ndarray:
    """Rotation by ``a`` about x."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> np.ndarray:
    """Rotation by ``a`` about y."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> np.ndarray:
    """Rotation by ``a`` about z."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def attitude(psi: float, phi: float, theta: float) -> np.ndarray:
    """The stance leg's rotation Rz(psi) Rx(phi) Ry(theta) (walker frame -> rigid slope frame)."""
    return rot_z(psi) @ rot_x(phi) @ rot_y(theta)


@dataclass(frozen=True)
class LegGeometry:
    """One leg in the walker frame with the hinge at zero: centre of mass, inertia about it, the foot's centre,
    radius, unit plane normal (a ring's or torus's; a sphere, an ellipsoid or a point has none), tube radius (a
    torus's, else 0) and quadric (an ellipsoid's Q, its points centre + Q^(1/2) u; zero for the other shapes)."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    foot_centre: np.ndarray
    foot_radius: float
    foot_normal: np.ndarray | None
    foot_tube: float = 0.0
    foot_quadric: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))


def leg_geometry(space: SpaceDescription, frame: int) -> LegGeometry:
    """The left leg (frame 0) or its mirror image, the right leg (frame 1): hip points ``hip_width`` apart on the
    hinge."""
    leg, foot = space.leg, space.leg.foot
    hip = np.array([0.0, 0.5 * space.hip_width, 0.0])
    mirror = MIRROR if frame == 1 else np.eye(3)
    normal = None
    if foot.shape in ("ring", "torus"):
        normal = mirror @ (np.array(foot.normal) / np.linalg.norm(foot.normal))
    return LegGeometry(
        mass=leg.mass,
        com=mirror @ (hip + np.array(leg.com)),
        inertia=mirror @ leg.inertia.matrix() @ mirror,
        foot_centre=mirror @ (hip + np.array(foot.centre)),
        foot_radius=foot.radius,
        foot_normal=normal,
        foot_tube=foot.tube,
        foot_quadric=mirror @ foot.quadric() @ mirror,
    )


def with_point_mass(leg: LegGeometry, mass: float) -> LegGeometry:
    """``leg`` carrying a point ``mass`` at the walker frame's origin, the hinge's midpoint (on the hinge axis, it
    moves alike on either leg): centre of mass and inertia by parallel axes."""
    total = leg.mass + mass
    com = leg.com * (leg.mass / total)
    inertia = leg.inertia.copy()
    for m, at in ((leg.mass, leg.com - com), (mass, -com)):
        inertia += m * (at @ at * np.eye(3) - np.outer(at, at))
    return replace(leg, mass=total, com=com, inertia=inertia)


def lowest_point(leg: LegGeometry, rotation: np.ndarray) -> np.ndarray:
    """The foot's lowest point from the walker frame's origin (rigid slope frame), its leg turned by ``rotation``:
    a ring's point in its plane most against the normal (a torus's: lowered by its tube), a sphere's below its
    centre, an ellipsoid's at -Q z / sqrt(z.Q z) from its centre (Q turned with the leg), a point itself."""
    centre = rotation @ leg.foot_centre
    if leg.foot_quadric[2, 2] > 0.0:
        q = rotation @ leg.foot_quadric @ rotation.T
        return centre - q[:, 2] / math.sqrt(q[2, 2])
    if leg.foot_normal is None:
        return centre - leg.foot_radius * EZ
    n = rotation @ leg.foot_normal
    w = EZ - n[2] * n
    return centre - leg.foot_radius * w / np.linalg.norm(w) - leg.foot_tube * EZ


@dataclass(frozen=True)
class BodyStates:
    """Both legs' centres of mass, rotations (walker frame -> rigid slope frame), velocities and angular velocities
    (rigid slope frame), from the stance foot's contact point."""

    com: tuple[np.ndarray, np.ndarray]
    rotation: tuple[np.ndarray, np.ndarray]
    velocity: tuple[np.ndarray, np.ndarray]
    omega: tuple[np.ndarray, np.ndarray]


def rolling_states(legs: tuple[LegGeometry, LegGeometry], x: dict[str, float]) -> BodyStates:
    """The legs' states in the rigid gait's state ``x`` (heading, bank, pitch, swing_angle, omega_x, omega_y,
    omega_z, swing_rate: the stance leg rolls without slip on its contact point at the origin, the swing leg turns
    about the hinge at the swing rate)."""
    stance = attitude(x["heading"], x["bank"], x["pitch"])
    swing = stance @ rot_y(x["swing_angle"])
    omega = np.array([x["omega_x"], x["omega_y"], x["omega_z"]])
    omega_swing = omega + x["swing_rate"] * stance[:, 1]
    origin = -lowest_point(legs[0], stance)
    com = (origin + stance @ legs[0].com, origin + swing @ legs[1].com)
    hinge_velocity = cross(omega, origin)
    velocity = (cross(omega, com[0]), hinge_velocity + cross(omega_swing, com[1] - origin))
    return BodyStates(com, (stance, swing), velocity, (omega, omega_swing))


def euler_parameters(rotation: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p, pdot) of a rotation matrix and its angular velocity (global frame): pdot = E(p)^T omega / 2, with
    E = [-e, e~ + e0 I] (Nikravesh), e0 >= 0."""
    from scipy.spatial.transform import Rotation  # here: scipy.spatial adds 0.15 s to every command's start-up

    x, y, z, w = Rotation.from_matrix(rotation).as_quat()
    p = np.array([w, x, y, z]) * (1.0 if w >= 0.0 else -1.0)
    e0, e = p[0], p[1:]
    tilde = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
    big_e = np.column_stack((-e, tilde + e0 * np.eye(3)))
    return p, 0.5 * big_e.T @ omega
