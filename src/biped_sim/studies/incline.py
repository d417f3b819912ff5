"""A rigid body on an incline in the project's own engine: the bodies of the friction checks (:mod:`.friction_checks`).

A sphere (I = 2/5 m R^2), a disc (I = 1/2 m R^2) and a block (two small round feet at its bottom corners, so it
cannot roll), each one free body of :class:`~biped_sim.multibody.planar.PlanarSystem` in the slope frame (x
downhill, gravity (g sin(theta), -g cos(theta))), with the same compiled loop, contact response and laws as a
walker's feet; the sphere in space is one body of :class:`~biped_sim.multibody.spatial.SpatialSystem` with a
sphere foot. The contact is the project's default normal law, restitution and Hertz stiffness of the default
materials; the bodies start at rest (the sphere in space possibly rolling across the slope) at their static
penetration, so the normal force starts and stays at its static value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.config import BaumgarteConfig, ContactConfig, IntegratorConfig, MaterialsConfig
from biped_sim.contact.friction import FRICTION_LAWS
from biped_sim.contact.normal import NORMAL_LAWS, hertz_stiffness, normal_parameters
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.spatial import SpatialSystem
from biped_sim.walkers.model import standing_start

GRAVITY = 9.81  # [m/s^2]
MASS = 1.0  # [kg]
RADIUS = 0.1  # [m] sphere and disc
BLOCK_HALF_LENGTH, BLOCK_HALF_HEIGHT, BLOCK_FOOT_RADIUS = 0.1, 0.02, 0.005  # [m]
DURATION = 1.0  # [s] from rest
INTEGRATOR = IntegratorConfig(method="dopri5", rtol=1e-10, atol=1e-13, max_step=1e-3)


@dataclass(frozen=True)
class Body:
    """A test body: ``inertia_ratio`` k = I / (m R^2) about its centre (inf: the block, which cannot roll)."""

    name: str
    inertia_ratio: float

    @property
    def rolls(self) -> bool:
        return math.isfinite(self.inertia_ratio)

    @property
    def share(self) -> float:
        """k / (1 + k): the needed friction per unit tan(theta) when rolling, and the centre's part of a slip."""
        return self.inertia_ratio / (1.0 + self.inertia_ratio) if self.rolls else 1.0


def default_contact(radius: float, load: float) -> tuple[np.ndarray, float, float]:
    """(normal law parameters, static penetration under ``load`` [N], impact speed floor) of the default contact."""
    contact, m = ContactConfig(), MaterialsConfig()
    stiffness = hertz_stiffness(
        m.foot.youngs_modulus, m.foot.poisson_ratio, m.ground.youngs_modulus, m.ground.poisson_ratio, radius
    )
    normal = normal_parameters(contact.model, stiffness, contact.exponent, contact.restitution, None, MASS)
    exponent = 1.0 if contact.model == "kelvin_voigt" else contact.exponent
    return normal, (load / stiffness) ** (1.0 / exponent), contact.impact_velocity_floor


def _switches(law: str) -> np.ndarray:
    return np.array([NORMAL_LAWS[ContactConfig().model].index, FRICTION_LAWS[law].index, 0], dtype=np.int64)


def _limits(floor: float) -> np.ndarray:
    """Impact speed floor; no fall limits; every touchdown a new impact (the body never leaves the ground)."""
    return np.array([floor, -math.inf, math.inf, 0.0])


def planar_body(
    body: Body, law: str, p: np.ndarray, slope: float, bristles: float = 0.0
) -> tuple[PlanarSystem, np.ndarray, np.ndarray]:
    """(system, y0, modes0): ``body`` at rest on the slope at its static penetration, one planar free body, each
    foot's bristle deflection (LuGre) ``bristles``."""
    if body.rolls:
        centres, radius, inertia = np.zeros((1, 2)), RADIUS, body.inertia_ratio * MASS * RADIUS**2
        bottom = RADIUS
    else:
        a, b, radius = BLOCK_HALF_LENGTH, BLOCK_HALF_HEIGHT, BLOCK_FOOT_RADIUS
        centres, inertia, bottom = np.array([[-a, radius - b], [a, radius - b]]), MASS * (a * a + b * b) / 3.0, b
    feet = centres.shape[0]
    normal, penetration, floor = default_contact(radius, MASS * GRAVITY * math.cos(slope) / feet)
    system = PlanarSystem(
        body_mass=np.array([MASS]),
        body_inertia=np.array([inertia]),
        joint_bodies=np.zeros((0, 2), dtype=np.int64),
        joint_points=np.zeros((0, 4)),
        foot_body=np.zeros(feet, dtype=np.int64),
        foot_center=centres,
        foot_radius=np.full(feet, radius),
        foot_partner=np.full(feet, -1, dtype=np.int64),
        gravity=np.array([GRAVITY * math.sin(slope), -GRAVITY * math.cos(slope)]),
        baumgarte=np.zeros(2),
        normal_params=normal,
        friction_params=p,
        switches=_switches(law),
        limits=_limits(floor),
    )
    q = np.array([[0.0, bottom - penetration, 0.0]])
    y0, modes0 = standing_start(system, q, np.zeros((1, 3)), tuple(range(feet)), floor)
    y0[6 : 6 + feet] = bristles  # after x, y, phi and their rates
    return system, y0, modes0


def spatial_sphere(
    law: str,
    p: np.ndarray,
    slope: float,
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0),
    spin: tuple[float, float, float] = (0.0, 0.0, 0.0),
    bristles: float = 0.0,
) -> tuple[SpatialSystem, np.ndarray, np.ndarray]:
    """(system, y0, modes0): the sphere in space on the slope with the centre's ``velocity`` and the angular
    velocity ``spin`` (slope frame), its downhill bristle deflection ``bristles``."""
    inertia = SPHERE.inertia_ratio * MASS * RADIUS**2 * np.eye(3)
    normal, penetration, floor = default_contact(RADIUS, MASS * GRAVITY * math.cos(slope))
    baumgarte = BaumgarteConfig()
    system = SpatialSystem(
        body_mass=np.array([MASS]),
        body_inertia=inertia[None],
        body_inertia_inv=np.linalg.inv(inertia)[None],
        con_type=np.zeros(0, dtype=np.int64),
        con_bodies=np.zeros((0, 2), dtype=np.int64),
        con_vecs=np.zeros((0, 7)),
        con_row=np.zeros(0, dtype=np.int64),
        foot_body=np.zeros(1, dtype=np.int64),
        foot_center=np.zeros((1, 3)),
        foot_axis=np.zeros((1, 3)),  # a sphere
        foot_radius=np.array([RADIUS]),
        foot_tube=np.zeros(1),
        foot_quadric=np.zeros((1, 3, 3)),
        foot_partner=np.array([-1], dtype=np.int64),
        gravity=np.array([GRAVITY * math.sin(slope), -GRAVITY * math.cos(slope), 0.0]),
        baumgarte=np.array([baumgarte.alpha, baumgarte.beta]),
        normal_params=normal,
        friction_params=p,
        switches=_switches(law),
        limits=_limits(floor),
    )
    q = np.array([[0.0, RADIUS - penetration, 0.0, 1.0, 0.0, 0.0, 0.0]])
    # the Euler parameter rates of the angular velocity omega at p = (1, 0, 0, 0): pdot = (0, omega / 2)
    qd = np.array([[*velocity, 0.0, *(0.5 * w for w in spin)]])
    y0, modes0 = standing_start(system, q, qd, (0,), floor)
    y0[14] = bristles  # after r, p and their rates: the foot's x bristle
    return system, y0, modes0


def sampled_states(system: PlanarSystem | SpatialSystem, y0: np.ndarray, modes0: np.ndarray, rate: float) -> np.ndarray:
    """The states sampled at ``rate`` [1/s] up to DURATION; RuntimeError when the engine did not run to it."""
    run = integrate_model(system, y0, modes0, INTEGRATOR, t_end=DURATION, sample_rate=rate)
    if run.status != "walking" or not math.isclose(run.t[-1], DURATION):
        raise RuntimeError(f"incline: the run stopped ({run.status}: {run.stop_reason}) at {run.t[-1]:.4g} s")
    return run.y


def final_state(system: PlanarSystem | SpatialSystem, y0: np.ndarray, modes0: np.ndarray) -> np.ndarray:
    """The state at DURATION."""
    return sampled_states(system, y0, modes0, 10.0 / DURATION)[-1]


def slope_for(body: Body, ratio: float) -> float:
    """The slope on which ``body`` needs ``ratio`` of its normal force as friction to roll (the block: to stick)."""
    return math.atan(ratio / body.share)


def block_lean(ratio: float, slope: float) -> float:
    """How far [m] the block's centre moves as it leans on its compliant feet under the friction's moment.

    The friction ratio N at the feet, b below the centre, tilts the block by phi = ratio N b / (2 k a^2), k the
    linearised normal stiffness n N_i / delta_i of each foot (a apart from the centre), moving the centre by b phi.
    """
    load = MASS * GRAVITY * math.cos(slope)
    _, penetration, _ = default_contact(BLOCK_FOOT_RADIUS, load / 2.0)
    exponent = 1.0 if ContactConfig().model == "kelvin_voigt" else ContactConfig().exponent
    stiffness = exponent * (load / 2.0) / penetration
    a, b = BLOCK_HALF_LENGTH, BLOCK_HALF_HEIGHT
    return b * ratio * load * b / (2.0 * stiffness * a * a)


def angular_velocity(state: np.ndarray) -> np.ndarray:
    """The spatial sphere's angular velocity in the slope frame, omega = 2 E(p) pdot, E = [-e, e~ + e0 I]."""
    e0, e, e0_dot, e_dot = state[3], state[4:7], state[10], state[11:14]
    return 2.0 * (e0 * e_dot - e0_dot * e + np.cross(e, e_dot))


def contact_slip(state: np.ndarray) -> np.ndarray:
    """The slip velocity (x, z) of the spatial sphere's lowest material point: v + omega x (0, -R, 0)."""
    w = angular_velocity(state)
    return np.array([state[7] + RADIUS * w[2], state[9] - RADIUS * w[0]])


def rolling_angle(states: np.ndarray) -> float:
    """The final rotation about the lateral axis z, in the rolling sense (downhill), of a sphere turning about z
    only (Euler parameters (cos(phi/2), 0, 0, sin(phi/2))), unwrapped over the samples."""
    return -float(np.unwrap(2.0 * np.arctan2(states[:, 6], states[:, 3]))[-1])


SPHERE, DISC, BLOCK = Body("sphere", 0.4), Body("disc", 0.5), Body("block", math.inf)
BODIES = (SPHERE, DISC, BLOCK)
