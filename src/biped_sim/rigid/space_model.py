"""The rigid walker in space: its parts and feet in the walker frame, its attitude, and where its points are.

The walker frame is the stance leg's: origin at the hinge's midpoint, x forward, y along the hinge (to the
left), z up the leg. The stance leg is always the left leg (the description's): the step map mirrors the walker
(y -> -y) after each strike, so the right leg's step is the left leg's mirror image. The swing leg is the
stance leg's frame turned by the hinge angle ``beta`` about y (positive: the swing foot behind). A leg with a knee
is a thigh and a shank (frame 2 of the swing leg) turned from it by the knee angle about y through the knee point
(positive: the foot behind); the stance knee stays locked straight (Chen 2007, McGeer 1990), the swing knee is
locked but for the step's first phase, from the strike that unlocks it to the knee strike.

State ``x`` (the slope frame: x downhill, y left, z along the slope normal): heading psi, bank phi, pitch theta of
the stance leg, R = Rz(psi) Rx(phi) Ry(theta) (pitch positive with the leg's top downhill), the hinge angle
beta, the stance leg's angular velocity (slope frame), the hinge rate, and the stance contact point (x, y) on
the ground: ``STATE_NAMES``; with knees, then the swing knee's angle and rate (``KNEE_NAMES``); with a torso, then
its angle from the stance leg about y (+ with its top forward), its rate and the work its elements dissipated
(``TORSO_NAMES``: the dampers' work, integrated with the flow for the energy balance). A torso (frame 3) turns
about the hinge axis through the hinge's midpoint, on no leg's path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from biped_sim.config.space_description import SpaceDescription, SpaceTorso
from biped_sim.contact.joint_element import JOINT_ELEMENT_LAWS, element_parameters
from biped_sim.walkers.space_geometry import EZ, MIRROR, attitude, cross, rot_x, rot_y, rot_z

STATE_NAMES = ("heading", "bank", "pitch", "swing_angle", "omega_x", "omega_y", "omega_z", "swing_rate", "x", "y")
N_STATE = len(STATE_NAMES)
KNEE_NAMES = ("swing_knee", "swing_knee_rate")
KNEE_ANGLE, KNEE_RATE = N_STATE, N_STATE + 1
TORSO_NAMES = ("torso_angle", "torso_rate", "element_work")
TORSO_FRAME = 3
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
    """A rigid part: on the stance leg (frame 0), the swing leg (frame 1; with a knee its thigh), the swing shank
    (frame 2) or the torso (frame 3); mass, centre of mass and inertia about it, in the walker frame with the hinge,
    knee and torso at zero."""

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
class Knee:
    """The swing leg's knee: its point in the walker frame with the hinge at zero (the right leg's, the mirror of
    the description's) and its flexion's sign (+1: the knee bends with the foot behind, a positive angle)."""

    point: np.ndarray
    flexion: float


@dataclass(frozen=True)
class Torso:
    """The torso's elements: each one's law (its number in the joint-element registry) and parameter vector
    (:func:`~biped_sim.contact.joint_element.element_parameters`), acting alike against each leg."""

    laws: tuple[int, ...]
    params: tuple[np.ndarray, ...]


@dataclass(frozen=True)
class SpaceModel:
    """The walker in its frame: parts (the stance leg's, the swing leg's, a hip mass, a torso), the two feet,
    gravity and slope, the swing knee if the legs have knees, the torso's elements if it has a torso."""

    parts: tuple[Part, ...]
    feet: tuple[Foot, Foot]
    gravity: float
    slope: float
    leg_length: float
    knee: Knee | None = None
    torso: Torso | None = None

    @property
    def gravity_vector(self) -> np.ndarray:
        """Gravity in the slope frame (x downhill, z along the normal)."""
        return self.gravity * np.array([math.sin(self.slope), 0.0, -math.cos(self.slope)])

    @property
    def n_state(self) -> int:
        """The state's length (:attr:`state_names`)."""
        return len(self.state_names)

    @property
    def state_names(self) -> tuple[str, ...]:
        """The state's names: ``STATE_NAMES``, then ``KNEE_NAMES`` with knees, ``TORSO_NAMES`` with a torso."""
        return STATE_NAMES + (KNEE_NAMES if self.knee else ()) + (TORSO_NAMES if self.torso else ())

    @property
    def torso_angle(self) -> int:
        """The torso angle's index in the state (its rate and the elements' work follow)."""
        return N_STATE + (2 if self.knee else 0)

    @property
    def swapped(self) -> list[int]:
        """The parts' order after a strike: each leg's parts take the other's places (the hip's and torso's stay)."""
        per_leg = 2 if self.knee else 1
        legs = list(range(2 * per_leg))
        return legs[per_leg:] + legs[:per_leg] + list(range(2 * per_leg, len(self.parts)))

    @property
    def swing_foot_frame(self) -> int:
        """The frame the swing foot turns with: the shank's with a knee."""
        return 2 if self.knee else 1


def _leg(space: SpaceDescription, frame: int) -> tuple[list[Part], Foot]:
    """The left leg (frame 0) or its mirror image, the right leg (frame 1), in the walker frame: its parts (a
    knee's shank on frame 2 of the swing leg) and foot."""
    leg, foot = space.leg, space.leg.foot
    hip = np.array([0.0, 0.5 * space.hip_width, 0.0])
    mirror = MIRROR if frame == 1 else np.eye(3)
    bodies = [(frame, leg.mass, leg.com, leg.inertia)]
    if leg.knee:
        bodies.append((2 * frame, leg.knee.mass, leg.knee.com, leg.knee.inertia))
    parts = [
        Part(f, m, mirror @ (hip + np.array(com)), mirror @ inertia.matrix() @ mirror) for f, m, com, inertia in bodies
    ]
    normal = mirror @ (np.array(foot.normal) / np.linalg.norm(foot.normal))
    quadric = mirror @ foot.quadric() @ mirror
    centre = mirror @ (hip + np.array(foot.centre))
    return parts, Foot(SHAPES[foot.shape], centre, foot.radius, normal, foot.tube, quadric)


def space_model(space: SpaceDescription, gravity: float, slope: float) -> SpaceModel:
    """The model of a description in space on a slope of ``slope`` rad under ``gravity``."""
    stance, stance_foot = _leg(space, 0)
    swing, swing_foot = _leg(space, 1)
    hip = [Part(0, space.hip_mass, np.zeros(3), np.zeros((3, 3)))] if space.hip_mass else []
    knee, torso = space.leg.knee, space.torso
    at = MIRROR @ (np.array([0.0, 0.5 * space.hip_width, 0.0]) + np.array(knee.at)) if knee else None
    body = []
    if torso:
        body = [Part(TORSO_FRAME, torso.mass, np.array([torso.com[0], 0.0, torso.com[1]]), torso.inertia.matrix())]
    return SpaceModel(
        tuple(stance + swing + hip + body), (stance_foot, swing_foot), gravity, slope,
        space.leg_length(), Knee(at, float(knee.flexion)) if knee else None, _torso(torso) if torso else None,
    )  # fmt: skip


def _torso(torso: SpaceTorso) -> Torso:
    """The torso's elements as the model's (their laws' numbers and parameter vectors)."""
    elements = torso.elements
    return Torso(
        tuple(JOINT_ELEMENT_LAWS[e.law].index for e in elements),
        tuple(element_parameters(e.law, **{name: getattr(e, name) for name in JOINT_ELEMENT_LAWS[e.law].reads})
              for e in elements),
    )  # fmt: skip


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
    """Where the walker is, from its stance contact point (slope frame): the frames' rotations (stance leg, swing
    leg, swing shank, torso) and origins (where their walker-frame points are measured from: the hinge's midpoint, a
    shank's shifted so that it turns about the knee), the hinge axis, and the stance foot's d (:func:`foot_bottom`)."""

    rotations: tuple[np.ndarray, ...]
    origins: tuple[np.ndarray, ...]
    hinge: np.ndarray
    stance_d: np.ndarray

    @property
    def origin(self) -> np.ndarray:
        """The hinge's midpoint."""
        return self.origins[0]

    def point(self, frame: int, local: np.ndarray) -> np.ndarray:
        """A point of ``frame`` given in the walker frame, from the stance contact point."""
        return self.origins[frame] + self.rotations[frame] @ local


def pose(model: SpaceModel, x: np.ndarray) -> Pose:
    """The walker's pose in state ``x`` (a frame the walker lacks: the stance leg's)."""
    stance = attitude(x[0], x[1], x[2])
    swing = stance @ rot_y(x[3])
    bottom, d = foot_bottom(model.feet[0], stance)
    origin = -bottom
    shank, shank_origin = swing, origin
    if model.knee is not None:
        shank = swing @ rot_y(x[KNEE_ANGLE])
        shank_origin = origin + swing @ model.knee.point - shank @ model.knee.point
    torso = stance @ rot_y(x[model.torso_angle]) if model.torso else stance
    return Pose((stance, swing, shank, torso), (origin, origin, shank_origin, origin), stance[:, 1], d)


def swing_clearance(model: SpaceModel, x: np.ndarray) -> float:
    """The swing foot's lowest point above the slope (the stance foot's is on it)."""
    where, frame = pose(model, x), model.swing_foot_frame
    bottom, _ = foot_bottom(model.feet[1], where.rotations[frame])
    return float(where.origins[frame][2] + bottom[2])
