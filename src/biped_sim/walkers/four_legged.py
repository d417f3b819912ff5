"""Liu's four-legged passive walker: an outer and an inner pair of legs, four disc feet (spatial, or sagittal).

Each pair is one rigid body: two straight legs (mass m, centre of mass c below the hip along the leg
and u = ``leg_com_offset`` across it, forward; inertia I about their centre of mass for any axis
across the leg, none about the leg's own axis: slender legs) at z' = +-w/2, a cross bar (a uniform
rod of mass ``crossbar_mass`` and length w along the hip axle) and half the hip mass M_H on the
axle. Body 0 is the outer pair (w = foot_spacing_outer), body 1 the inner pair (w =
foot_spacing_inner); a revolute hip axle along z' joins them. The body's centre of mass lies
d = 2 m c / M_b below the hip and e = 2 m u / M_b forward of it (M_b = 2 m + M_H/2 + crossbar_mass),
and its inertia about it, in the body frame (x' forward, y' up the legs, z' along the axle), is
(parallel axes, with a = u - e and M_a = M_H/2 + m_bar on the axle)

    J'_xx = 2 [I + m ((c - d)^2 + w^2/4)] + M_a d^2 + m_bar w^2/12
    J'_yy = m w^2/2 + m_bar w^2/12 + 2 m a^2 + M_a e^2
    J'_zz = 2 [I + m ((c - d)^2 + a^2)] + M_a (d^2 + e^2)
    J'_xy = 2 m a (c - d) + M_a e d.

Feet: discs of radius R in the legs' sagittal planes (centres at (f - e, -(l - R - d), +-w/2), f =
``foot_offset``); feet
0, 1 are the outer pair's (z' = +w/2, -w/2), 2, 3 the inner pair's, and each foot's scuffing-guard
partner is the other pair's foot on the same side. The walker starts like the compass walker: the
outer pair in stance on both feet (each carrying half the weight: static penetration
(M g cos gamma / 2 K)^(1/n)), the inner pair swinging, leg angles and rates from
``simulation.initial``. Nothing in the machine or in this start breaks the lateral symmetry, so
roll and yaw stay at round-off unless the model is perturbed.

Its motion is then sagittal: :func:`build_four_legged_sagittal` is the same machine as a planar star
(two bodies, J'_zz each, joined at the hip, two feet per body at one sagittal place), which the
minimal-coordinate formulation integrates (``formulation.kind: minimal``).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, InitialState
from biped_sim.contact.profile import profile_ground
from biped_sim.errors import ConfigError
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.spatial import SpatialSystem
from biped_sim.walkers.model import (
    BuiltModel,
    contact_arrays,
    contact_limits,
    contact_stiffness,
    standing_start,
    static_contact_penetration,
)
from biped_sim.walkers.spatial_compass import (
    DISC_AXIS,
    constraint_arrays,
    revolute,
    sagittal_to_spatial,
    spatial_gravity,
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


def pair_properties(config: Config, spacing: float) -> tuple[float, tuple[float, float], np.ndarray]:
    """(mass, centre of mass from the hip (d below along the legs, e forward across them), inertia J' about the
    centre of mass) of one leg pair."""
    w = config.walker
    m, c, u, inertia, bar = w.leg_mass, w.leg_com_from_hip, w.leg_com_offset, w.leg_inertia, w.crossbar_mass
    on_axle = 0.5 * w.hip_mass + bar
    mass = 2.0 * m + on_axle
    d = 2.0 * m * c / mass
    e = 2.0 * m * u / mass
    a = u - e
    j_xx = 2.0 * (inertia + m * ((c - d) ** 2 + spacing**2 / 4.0)) + on_axle * d**2 + bar * spacing**2 / 12.0
    j_yy = 0.5 * m * spacing**2 + bar * spacing**2 / 12.0 + (2.0 * m * a**2 + on_axle * e**2)
    j_zz = 2.0 * (inertia + m * ((c - d) ** 2 + a**2)) + on_axle * (d**2 + e**2)
    j_xy = 2.0 * m * a * (c - d) + on_axle * e * d
    return mass, (d, e), np.array([[j_xx, j_xy, 0.0], [j_xy, j_yy, 0.0], [0.0, 0.0, j_zz]])


def leg_pairs(config: Config) -> tuple[np.ndarray, list[float], np.ndarray]:
    """(masses, hip-to-centre-of-mass distances, inertias J') of the outer and inner pair."""
    props = [pair_properties(config, s) for s in (config.walker.foot_spacing_outer, config.walker.foot_spacing_inner)]
    if min(np.linalg.eigvalsh(j).min() for _, _, j in props) <= 0.0:
        raise ConfigError("walker.leg_inertia", "each leg pair needs a positive-definite inertia")
    return np.array([mass for mass, _, _ in props]), [d for _, d, _ in props], np.array([j for _, _, j in props])


def _meta(static_penetration: float, masses: np.ndarray) -> dict[str, float]:
    return {"static_penetration": static_penetration, "outer_mass": float(masses[0]), "inner_mass": float(masses[1])}


BODY_NAMES = ["outer", "inner"]
FOOT_NAMES = ["outer_left", "outer_right", "inner_left", "inner_right"]
FOOT_BODY = np.array([0, 0, 1, 1], dtype=np.int64)
FOOT_PARTNER = np.array([2, 3, 0, 1], dtype=np.int64)  # the other pair's foot on the same side


def build_four_legged_sagittal(config: Config, initial: InitialState) -> BuiltModel:
    """The four-legged walker's sagittal motion as a planar star: the two pairs (sagittal inertia J'_zz) hinged
    at the hip, each pair's two feet at one place of its sagittal plane, standing on the outer pair."""
    w = config.walker
    l, R = w.leg_length, w.foot_radius
    masses, offsets, inertia = leg_pairs(config)
    total_mass = float(masses.sum())
    stiffness = contact_stiffness(config)
    normal, friction, switches = contact_arrays(config, stiffness, total_mass)
    gravity = spatial_gravity(config)[:2]
    system = PlanarSystem(
        body_mass=masses,
        body_inertia=inertia[:, 2, 2].copy(),
        joint_bodies=np.array([[0, 1]], dtype=np.int64),
        joint_points=np.array([[0.0 - offsets[0][1], offsets[0][0], 0.0 - offsets[1][1], offsets[1][0]]]),
        foot_body=FOOT_BODY.copy(),
        foot_center=np.array([[w.foot_offset - offsets[b][1], -(l - R - offsets[b][0])] for b in FOOT_BODY]),
        foot_radius=np.full(4, R),
        foot_partner=FOOT_PARTNER.copy(),
        gravity=gravity,
        baumgarte=np.array([config.formulation.baumgarte.alpha, config.formulation.baumgarte.beta]),
        normal_params=normal,
        friction_params=friction,
        switches=switches,
        limits=contact_limits(config),
        ground=profile_ground(config.ground.profile, config.ground.slope),
    )
    static_penetration = static_contact_penetration(config, 0.5 * total_mass, stiffness)
    coords, rates, hip_speed = sagittal_initial_state(config, initial, (offsets[0], offsets[1]), static_penetration)
    y0, modes0 = standing_start(system, coords, rates, (0, 1), max(hip_speed, config.contact.impact_velocity_floor))
    meta = _meta(static_penetration, masses)
    return BuiltModel(system, y0, modes0, BODY_NAMES, FOOT_NAMES, l, total_mass, stiffness, meta)


def build_four_legged(config: Config, initial: InitialState) -> BuiltModel:
    """Bodies, hip axle and four feet of the four-legged walker, standing on its outer pair."""
    if config.formulation.kind != "spatial":
        raise ConfigError("formulation.kind", "walker.kind 'four_legged' needs the spatial formulation")
    w = config.walker
    l, R = w.leg_length, w.foot_radius
    spacings = (w.foot_spacing_outer, w.foot_spacing_inner)
    masses, offsets, inertia = leg_pairs(config)
    total_mass = float(masses.sum())
    stiffness = contact_stiffness(config)
    normal, friction, switches = contact_arrays(config, stiffness, total_mass)
    hips = [(0.0 - e, d) for d, e in offsets]  # the hip in each pair's body frame (0.0, not -0.0, without offset)
    kinds, bodies, vecs, rows = constraint_arrays(revolute(0, hips[0], 1, hips[1]))

    foot_center = np.array(
        [
            [w.foot_offset - offsets[b][1], -(l - R - offsets[b][0]), side * 0.5 * spacings[b]]
            for b in (0, 1)
            for side in (1.0, -1.0)
        ]
    )
    system = SpatialSystem(
        body_mass=masses,
        body_inertia=inertia,
        body_inertia_inv=np.linalg.inv(inertia),
        con_type=kinds,
        con_bodies=bodies,
        con_vecs=vecs,
        con_row=rows,
        foot_body=FOOT_BODY.copy(),
        foot_center=foot_center,
        foot_axis=np.array([DISC_AXIS] * 4),
        foot_radius=np.full(4, R),
        foot_partner=FOOT_PARTNER.copy(),
        gravity=spatial_gravity(config),
        baumgarte=np.array([config.formulation.baumgarte.alpha, config.formulation.baumgarte.beta]),
        normal_params=normal,
        friction_params=friction,
        switches=switches,
        limits=contact_limits(config),
    )

    static_penetration = static_contact_penetration(config, 0.5 * total_mass, stiffness)
    coords, rates, hip_speed = sagittal_initial_state(config, initial, (offsets[0], offsets[1]), static_penetration)
    q, qd = sagittal_to_spatial(coords, rates)
    # the outer pair "just struck"
    y0, modes0 = standing_start(system, q, qd, (0, 1), max(hip_speed, config.contact.impact_velocity_floor))
    return BuiltModel(
        system, y0, modes0, BODY_NAMES, FOOT_NAMES, l, total_mass, stiffness, _meta(static_penetration, masses)
    )
