"""Compass walker with round feet: two straight legs joined at the hip by a revolute joint.

Each leg is one body. The leg's own centre of mass lies c along the leg axis from the hip and w
(``walker.leg_com_offset``) across it; the foot arc centre l - R along the axis and d
(``walker.foot_offset``) across it (across = +x' of the body frame, downhill when the leg is vertical).
The hip point mass M_H is split half to each leg at the hip point (exact for a point mass), so leg
body i has mass m + M_H/2, its centre of mass at (d_w, -d_c) from the hip with d_c = m c / (m + M_H/2)
along the axis and d_w = m w / (m + M_H/2) across it, and inertia
J = I + m ((c - d_c)^2 + (w - d_w)^2) + (M_H/2) (d_c^2 + d_w^2) (parallel axes).
In the body frame the leg points along -y: the hip is at (-d_w, d_c) and the foot arc centre at
(d - d_w, -(l - R - d_c)). The body angle phi is the README's leg angle theta (from the slope normal,
positive with the foot downhill of the hip).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, InitialState
from biped_sim.contact.profile import profile_ground
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


def _leg_across(theta: float) -> np.ndarray:
    """Unit vector across the leg (the body's +x'), downhill when the leg is vertical: d/dtheta of the direction."""
    return np.array([math.cos(theta), math.sin(theta)])


def _rolling_velocity(omega: float, point: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """Velocity of ``point`` on a body rotating at ``omega`` about the instantaneous centre ``pivot``."""
    rel = point - pivot
    return omega * np.array([-rel[1], rel[0]])


def sagittal_initial_state(
    config: Config,
    init: InitialState,
    com_offsets: tuple[tuple[float, float], tuple[float, float]],
    static_penetration: float,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Initial planar state of a stance and a swing leg rolling on the stance foot (docs/guide/model.md), from ``init``.

    ``com_offsets`` place each leg body's centre of mass from the hip: (along the leg towards the foot, across
    it, downhill when vertical). The stance foot's arc centre (offset ``walker.foot_offset`` across the leg)
    is R above the contact point at x = 0, sunk by ``static_penetration``. Returns
    (coords, rates, hip speed): coords (2, 3) = (x, y, phi) of the stance and swing bodies, rates
    (2, 3) their velocities. Raises ConfigError when the walker would start fallen or with its swing
    foot in the ground while the scuffing guard is off.
    """
    l, R, d = config.walker.leg_length, config.walker.foot_radius, config.walker.foot_offset
    for name in ("stance_angle", "swing_angle"):
        if abs(getattr(init, name)) >= config.simulation.fall_leg_angle:
            raise ConfigError(
                f"simulation.initial.{name}", "beyond simulation.fall_leg_angle: the walker starts fallen"
            )
    contact_point = np.array([0.0, -static_penetration])
    arc_centre = contact_point + np.array([0.0, R])
    hip = arc_centre - (l - R) * _leg_direction(init.stance_angle) - d * _leg_across(init.stance_angle)
    if hip[1] <= config.simulation.fall_hip_height * l:
        raise ConfigError("simulation.initial.stance_angle", "the hip starts below simulation.fall_hip_height")
    (along_st, across_st), (along_sw, across_sw) = com_offsets
    com_stance = hip + along_st * _leg_direction(init.stance_angle) + across_st * _leg_across(init.stance_angle)
    com_swing = hip + along_sw * _leg_direction(init.swing_angle) + across_sw * _leg_across(init.swing_angle)
    v_hip = _rolling_velocity(init.stance_rate, hip, contact_point)
    v_stance = _rolling_velocity(init.stance_rate, com_stance, contact_point)
    v_swing = v_hip + _rolling_velocity(init.swing_rate, com_swing, hip)
    swing_centre = hip + (l - R) * _leg_direction(init.swing_angle) + d * _leg_across(init.swing_angle)
    swing_foot_bottom = swing_centre[1] - R
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
    d_w = m * w.leg_com_offset / body_mass
    inertia = I + m * ((c - d) ** 2 + (w.leg_com_offset - d_w) ** 2) + 0.5 * M_H * (d**2 + d_w**2)
    if inertia <= 0.0:
        raise ConfigError("walker.leg_inertia", "each leg needs a rotational inertia > 0 about its centre of mass")
    total_mass = 2.0 * m + M_H
    stiffness = contact_stiffness(config)
    normal, friction, switches = contact_arrays(config, stiffness, total_mass)

    foot_centre = np.array([w.foot_offset - d_w, -(l - R - d)])
    hip_x = 0.0 - d_w  # 0.0, not -0.0, without an offset
    system = PlanarSystem(
        body_mass=np.array([body_mass, body_mass]),
        body_inertia=np.array([inertia, inertia]),
        joint_bodies=np.array([[0, 1]], dtype=np.int64),
        joint_points=np.array([[hip_x, d, hip_x, d]]),
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
        ground=profile_ground(config.ground.profile, gamma),
    )

    static_penetration = static_contact_penetration(config, total_mass, stiffness)
    coords, rates, hip_speed = sagittal_initial_state(config, initial, ((d, d_w), (d, d_w)), static_penetration)
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
