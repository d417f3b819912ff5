"""Liu's four-legged passive walker: an outer and an inner pair of legs, four disc feet; each pair's mass properties.

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
``foot_offset``); feet 0, 1 are the outer pair's (z' = +w/2, -w/2), 2, 3 the inner pair's, and each foot's
scuffing-guard partner is the other pair's foot on the same side. The machine is a walker description
(:func:`biped_sim.walkers.describe.describe`: the pairs' sagittal properties, J'_xx, J'_yy and J'_xy as each
body's ``spatial_inertia``, each foot's ``lateral`` place), built by the one builder like every walker: it starts
like the compass walker, the outer pair in stance on both feet (each carrying half the weight: static penetration
(M g cos gamma / 2 K)^(1/n)), the inner pair swinging, leg angles and rates from ``simulation.initial``. Nothing in
the machine or in this start breaks the lateral symmetry, so in the spatial formulation roll and yaw stay at
round-off unless the model is perturbed; its motion is then sagittal, which the minimal-coordinate formulation
integrates (``formulation.kind: minimal``: the planar star of the same description).
"""

from __future__ import annotations

import numpy as np

from biped_sim.config import Config
from biped_sim.errors import ConfigError

BODY_NAMES = ["outer", "inner"]
FOOT_NAMES = ["outer_left", "outer_right", "inner_left", "inner_right"]
FOOT_BODY = (0, 0, 1, 1)
FOOT_SIDE = (1.0, -1.0, 1.0, -1.0)  # z' = side w / 2


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
