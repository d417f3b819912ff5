"""The compass walker in the spatial formulation, and the pieces every spatial builder shares.

Body frames: x' forward, y' along the leg towards the hip, z' lateral (the hip axle), so that a
rotation phi about z' is the planar leg angle. A planar state (x, y, phi) maps to r = (x, y, 0),
p = (cos phi/2, 0, 0, sin phi/2) and omega = (0, 0, phidot) to pdot = (omega/2) (-sin phi/2, 0, 0, cos phi/2).

The spatial compass is the planar compass (its description's planar model, :mod:`biped_sim.walkers.described`:
same bodies, same initial state, converted) with a
disc foot in each leg's sagittal plane, a revolute hip (a SPHERICAL and two PERPENDICULAR
primitives) and a planar joint from leg 0 to the ground frame (IN_PLANE z = 0 and leg 0's axle
perpendicular to x and y): the motion stays in the sagittal plane by construction, not only by
symmetry, so that a lateral round-off never grows (a single disc foot is laterally unstable). The
legs' inertias about x' and y' do not act (the joints hold those rotations); they are taken equal
to the sagittal one so that the mass matrix is well conditioned.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.multibody.spatial import IN_PLANE, PERPENDICULAR, SPHERICAL, SpatialSystem
from biped_sim.walkers.model import BuiltModel

X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
DISC_AXIS = Z  # the feet are discs in the body's sagittal plane


def revolute(
    body_a: int, hip_a: tuple[float, float], body_b: int, hip_b: tuple[float, float]
) -> list[tuple[int, int, int, tuple[float, ...]]]:
    """Revolute joint about z' at the points (x', y') = hip_a of body a and hip_b of body b, both in z' = 0."""
    return [
        (SPHERICAL, body_a, body_b, (hip_a[0], hip_a[1], 0.0, hip_b[0], hip_b[1], 0.0, 0.0)),
        (PERPENDICULAR, body_a, body_b, (*X, *Z, 0.0)),
        (PERPENDICULAR, body_a, body_b, (*Y, *Z, 0.0)),
    ]


def planar_to_ground(body: int) -> list[tuple[int, int, int, tuple[float, ...]]]:
    """Planar joint of ``body`` to the ground frame: centre of mass in z = 0, axle z' along z."""
    return [
        (IN_PLANE, body, -1, (0.0, 0.0, 0.0, *Z, 0.0)),
        (PERPENDICULAR, body, -1, (*Z, *X, 0.0)),
        (PERPENDICULAR, body, -1, (*Z, *Y, 0.0)),
    ]


def constraint_arrays(
    primitives: list[tuple[int, int, int, tuple[float, ...]]],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(con_type, con_bodies, con_vecs, con_row) of a list of (type, body a, body b, 7 numbers)."""
    kinds = np.array([kind for kind, _, _, _ in primitives], dtype=np.int64)
    bodies = np.array([[a, b] for _, a, b, _ in primitives], dtype=np.int64)
    vecs = np.array([vec for _, _, _, vec in primitives], dtype=np.float64)
    rows = np.concatenate([[0], np.cumsum(np.where(kinds == SPHERICAL, 3, 1))[:-1]]).astype(np.int64)
    return kinds, bodies, vecs, rows


def sagittal_to_spatial(coords: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planar (x, y, phi) and rates per body, (nb, 3) each, as spatial (r, p) and (rdot, pdot), (nb, 7) each."""
    q = np.zeros((len(coords), 7))
    qd = np.zeros((len(coords), 7))
    for b, ((x, y, phi), (vx, vy, omega)) in enumerate(zip(coords, rates, strict=True)):
        c, s = math.cos(0.5 * phi), math.sin(0.5 * phi)
        q[b] = [x, y, 0.0, c, 0.0, 0.0, s]
        qd[b] = [vx, vy, 0.0, -0.5 * omega * s, 0.0, 0.0, 0.5 * omega * c]
    return q, qd


def spatial_gravity(config: Config) -> np.ndarray:
    """Gravity in the slope frame: g (sin gamma, -cos gamma, 0)."""
    g, gamma = config.gravity, config.ground.slope
    return np.array([g * math.sin(gamma), -g * math.cos(gamma), 0.0])


def spatial_compass(planar: BuiltModel, config: Config) -> BuiltModel:
    """The planar compass walker ``planar`` (two legs hinged at the hip) in Euler parameters, kept planar by a
    planar joint."""
    ps = planar.system
    nb, nf = 2, 2
    hip_a, hip_b = (
        (float(ps.joint_points[0, 0]), float(ps.joint_points[0, 1])),
        (
            float(ps.joint_points[0, 2]),
            float(ps.joint_points[0, 3]),
        ),
    )
    inertia = np.array([np.eye(3) * j for j in ps.body_inertia])
    kinds, bodies, vecs, rows = constraint_arrays(revolute(0, hip_a, 1, hip_b) + planar_to_ground(0))
    system = SpatialSystem(
        body_mass=ps.body_mass.copy(),
        body_inertia=inertia,
        body_inertia_inv=np.linalg.inv(inertia),
        con_type=kinds,
        con_bodies=bodies,
        con_vecs=vecs,
        con_row=rows,
        foot_body=ps.foot_body.copy(),
        foot_center=np.array([[c[0], c[1], 0.0] for c in ps.foot_center]),
        foot_axis=np.array([DISC_AXIS] * nf),
        foot_radius=ps.foot_radius.copy(),
        foot_partner=ps.foot_partner.copy(),
        gravity=spatial_gravity(config),
        baumgarte=ps.baumgarte.copy(),
        normal_params=ps.normal_params,
        friction_params=ps.friction_params,
        switches=ps.switches,
        limits=ps.limits.copy(),
    )
    planar_layout, layout = (formulation_of(s).layout_of(s) for s in (ps, system))
    q, qd = sagittal_to_spatial(
        np.array([planar.y0[planar_layout.position(b)] for b in range(nb)]),
        np.array([planar.y0[planar_layout.velocity(b)] for b in range(nb)]),
    )
    y0 = np.zeros(layout.size)
    for b in range(nb):
        y0[layout.position(b)] = q[b]
        y0[layout.velocity(b)] = qd[b]
    for foot in range(nf):  # the planar bristle runs along x
        y0[layout.bristle(foot).start] = planar.y0[planar_layout.bristle(foot).start]
    return BuiltModel(
        system=system,
        y0=y0,
        modes0=planar.modes0.copy(),
        body_names=planar.body_names,
        foot_names=planar.foot_names,
        leg_length=planar.leg_length,
        total_mass=planar.total_mass,
        stiffness=planar.stiffness,
        meta=planar.meta,
    )
