"""Compass walker with round feet: two straight legs joined at the hip by a revolute joint.

Each leg is one body. The hip point mass M_H is split half to each leg at the hip point (exact
for a point mass), so leg body i has mass m + M_H/2, its centre of mass at
d = m c / (m + M_H/2) from the hip, and inertia J = I + m (c - d)^2 + (M_H/2) d^2.
In the body frame the leg points along -y: the hip is at (0, d) and the foot arc centre at
(0, -(l - R - d)). The body angle phi is the README's leg angle theta (from the slope normal,
positive with the foot downhill of the hip).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, InitialState
from biped_sim.contact.profile import profile_arrays
from biped_sim.errors import ConfigError
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.walkers.model import (
    BuiltModel,
    contact_arrays,
    contact_limits,
    contact_stiffness,
    standing_start,
    static_contact_penetration,
)


def _leg_direction(theta: float) -> np.ndarray:
    """Unit vector from hip to foot for leg angle theta."""
    return np.array([math.sin(theta), -math.cos(theta)])


def _rolling_velocity(omega: float, point: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Velocity of ``point`` on a body rotating at ``omega`` about the instantaneous centre ``pivot``."""
    rel = point - pivot
    return omega * np.array([-rel[1], rel[0]])


def sagittal_initial_state(
    config: Config, init: InitialState, com_offsets: tuple[float, float], static_penetration: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """Initial planar state of a stance and a swing leg rolling on the stance foot (README conventions), from ``init``.

    ``com_offsets`` are the distances from the hip down to each leg body's centre of mass. Returns
    (coords, rates, hip speed): coords (2, 3) = (x, y, phi) of the stance and swing bodies, rates
    (2, 3) their velocities. Raises ConfigError when the walker would start fallen or with its swing
    foot in the ground while the scuffing guard is off.
    """
    l, R = config.walker.leg_length, config.walker.foot_radius
    for name in ("stance_angle", "swing_angle"):
        if abs(getattr(init, name)) >= config.simulation.fall_leg_angle:
            raise ConfigError(
                f"simulation.initial.{name}", "beyond simulation.fall_leg_angle: the walker starts fallen"
            )
    contact_point = np.array([0.0, -static_penetration])
    arc_centre = contact_point + np.array([0.0, R])
    hip = arc_centre - (l - R) * _leg_direction(init.stance_angle)
    if hip[1] <= config.simulation.fall_hip_height * l:
        raise ConfigError("simulation.initial.stance_angle", "the hip starts below simulation.fall_hip_height")
    com_stance = hip + com_offsets[0] * _leg_direction(init.stance_angle)
    com_swing = hip + com_offsets[1] * _leg_direction(init.swing_angle)
    v_hip = _rolling_velocity(init.stance_rate, hip, contact_point)
    v_stance = _rolling_velocity(init.stance_rate, com_stance, contact_point)
    v_swing = v_hip + _rolling_velocity(init.swing_rate, com_swing, hip)
    swing_foot_bottom = hip[1] + (l - R) * _leg_direction(init.swing_angle)[1] - R
    if not config.contact.scuffing_guard and swing_foot_bottom < 0.0:
        raise ConfigError(
            "simulation.initial.swing_angle",
            "the swing foot starts below the ground (and contact.scuffing_guard is off)",
        )
    coords = np.array([[*com_stance, init.stance_angle], [*com_swing, init.swing_angle]])
    rates = np.array([[*v_stance, init.stance_rate], [*v_swing, init.swing_rate]])
    return coords, rates, float(np.hypot(*v_hip))


def build_compass(config: Config, initial: InitialState) -> BuiltModel:
    """Bodies, joint and feet of the compass walker, and its initial state rolling on its stance foot."""
    w = config.walker
    l, R, m, c, I, M_H = w.leg_length, w.foot_radius, w.leg_mass, w.leg_com_from_hip, w.leg_inertia, w.hip_mass
    g, gamma = config.gravity, config.ground.slope
    body_mass = m + 0.5 * M_H
    d = m * c / body_mass
    inertia = I + m * (c - d) ** 2 + 0.5 * M_H * d**2
    if inertia <= 0.0:
        raise ConfigError("walker.leg_inertia", "each leg needs a rotational inertia > 0 about its centre of mass")
    total_mass = 2.0 * m + M_H
    stiffness = contact_stiffness(config)
    normal, friction, switches = contact_arrays(config, stiffness, total_mass)

    foot_centre = np.array([0.0, -(l - R - d)])
    ground_vertices, ground_ends = profile_arrays(config.ground.profile, gamma)
    system = PlanarSystem(
        body_mass=np.array([body_mass, body_mass]),
        body_inertia=np.array([inertia, inertia]),
        joint_bodies=np.array([[0, 1]], dtype=np.int64),
        joint_points=np.array([[0.0, d, 0.0, d]]),
        foot_body=np.array([0, 1], dtype=np.int64),
        foot_center=np.array([foot_centre, foot_centre]),
        foot_radius=np.array([R, R]),
        foot_partner=np.array([1, 0], dtype=np.int64),
        gravity=np.array([g * math.sin(gamma), -g * math.cos(gamma)]),
        baumgarte=np.array([config.formulation.baumgarte.alpha, config.formulation.baumgarte.beta]),
        normal_params=normal,
        friction_params=friction,
        switches=switches,
        limits=contact_limits(config),
        ground_vertices=ground_vertices,
        ground_ends=ground_ends,
    )

    static_penetration = static_contact_penetration(config, total_mass, stiffness)
    coords, rates, hip_speed = sagittal_initial_state(config, initial, (d, d), static_penetration)
    # the stance foot "just struck": it remembers an approach velocity of the scale of the hip speed
    y0, modes0 = standing_start(system, coords, rates, (0,), max(hip_speed, config.contact.impact_velocity_floor))
    return BuiltModel(
        system=system,
        y0=y0,
        modes0=modes0,
        body_names=["leg0", "leg1"],
        foot_names=["foot0", "foot1"],
        leg_length=l,
        total_mass=total_mass,
        stiffness=stiffness,
        meta={"static_penetration": static_penetration, "leg_body_mass": body_mass, "leg_body_inertia": inertia},
    )
