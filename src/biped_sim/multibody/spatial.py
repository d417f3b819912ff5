"""Spatial multibody dynamics with Euler parameters (MODEL.md 2, the paper's own formulation), compiled with numba.

Each body i has q_i = (r_i, p_i): the centre of mass r_i in the slope frame (x downhill along the
slope, y along its normal, z lateral: x, y, z right-handed) and the Euler parameters
p_i = (e0, e) with the normalisation constraint p_i.p_i - 1 = 0 (Nikravesh, Computer-Aided
Analysis of Mechanical Systems, ch. 6, whose notation :mod:`biped_sim.multibody.euler_parameters`
implements: A(p), E, G and the point Jacobian B(p, s')). The kinetic energy
T = m rdot^2 / 2 + 2 pdot^T G^T J' G pdot gives the Lagrange equations m rdd = f and
4 G^T J' G pdd = 8 Gdot^T J' Gdot p + B^T f_P (forces f_P at points), with J' the inertia about
the centre of mass in the body frame.

4 G^T J' G is singular (its null vector is p); the normalisation row of the constraint Jacobian
(2 p^T) fixes the component of pdd along p, so 4 j p p^T (j = trace(J')/3) is added to the mass
matrix, which only changes the normalisation multiplier, not pdd. The modified block has the
closed-form inverse (G^T J'^-1 G + p p^T / j) / (4 |p|^4) since [G; p^T] has orthogonal rows
of norm |p|. The augmented system is then solved through its Schur complement

    (Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - (gamma_c - 2 alpha Phidot - beta^2 Phi),
    qdd = M^-1 Q - (M^-1 Phi_q^T) lambda,

with the same in-place Cholesky factorisation as the planar engine. Baumgarte stabilisation
acts on every constraint row, the normalisation rows included.

Joints are built from three constraint primitives (Nikravesh's): SPHERICAL (3 rows: a point
of body a coincides with a point of body b or a fixed point), PERPENDICULAR (1 row: a body-a
vector is perpendicular to a body-b vector or a fixed vector) and IN_PLANE (1 row: a point of
body a lies in a fixed plane). A revolute joint is one SPHERICAL and two PERPENDICULAR rows; a
planar joint to the ground frame is one IN_PLANE and two PERPENDICULAR rows.

The ODE state is y = [q (7 nb) | qd (7 nb) | z (2 nf: x and z bristles per foot) | W_normal | W_friction].
This module holds the system description and the constrained equations of motion; the feet, the
right-hand side and the formulation record are :mod:`biped_sim.multibody.spatial_kernels`.
Everything compiled here is allocation-free: buffers live in :class:`Workspace`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.contact.ground import FLAT_GROUND, Ground
from biped_sim.contact.joint_element import NO_ELEMENTS, JointElements
from biped_sim.contact.stop import NO_STOPS, Stops
from biped_sim.kernel import kernel
from biped_sim.multibody.euler_parameters import (
    b_mul,
    b_tmul,
    dot3,
    g_col,
    inertia_mul,
    parameters,
    point_state,
    rotate,
    unit4,
    vec3,
)
from biped_sim.multibody.hinge import HingeElements, HingeStops
from biped_sim.multibody.linalg import cholesky_solve

# constraint primitives and their row counts
SPHERICAL, PERPENDICULAR, IN_PLANE = 0, 1, 2
PRIMITIVE_ROWS = np.array([3, 1, 1], dtype=np.int64)


class SpatialSystem(NamedTuple):
    """Numeric description of a spatial walker, as the compiled kernels read it."""

    body_mass: np.ndarray  # (nb,) [kg]
    body_inertia: np.ndarray  # (nb, 3, 3) J' about the centre of mass, body frame [kg m^2]
    body_inertia_inv: np.ndarray  # (nb, 3, 3)
    con_type: np.ndarray  # (nc,) int64: SPHERICAL, PERPENDICULAR, IN_PLANE
    con_bodies: np.ndarray  # (nc, 2) int64; second entry -1 = ground (fixed frame)
    con_vecs: np.ndarray  # (nc, 7): SPHERICAL s_a, s_b; PERPENDICULAR u_a, v_b; IN_PLANE s_a, n, offset
    con_row: np.ndarray  # (nc,) int64: first constraint row of each primitive
    foot_body: np.ndarray  # (nf,) int64
    foot_center: np.ndarray  # (nf, 3) disc or sphere centre, body frame
    foot_axis: np.ndarray  # (nf, 3) unit disc axis, body frame; zero = sphere
    foot_radius: np.ndarray  # (nf,)
    foot_tube: np.ndarray  # (nf,) a torus's tube radius about its disc's edge; 0 = none
    foot_quadric: np.ndarray  # (nf, 3, 3) an ellipsoid's Q, body frame (points centre + Q^(1/2) u); zero = none
    foot_partner: np.ndarray  # (nf,) int64: the foot this one must be ahead of to arm (-1: none)
    gravity: np.ndarray  # (3,) in the slope frame
    baumgarte: np.ndarray  # (2,) alpha, beta
    normal_params: np.ndarray
    friction_params: np.ndarray
    switches: np.ndarray  # (3,) int64: normal model, friction model, scuffing guard
    limits: np.ndarray  # (3,) impact velocity floor, fall hip height, fall leg angle
    # the joint stops (multibody.hinge: their modes follow the feet's in the mode table), springs and dampers
    stops: Stops | HingeStops = NO_STOPS
    elements: JointElements | HingeElements = NO_ELEMENTS
    ground: Ground = FLAT_GROUND  # contact.ground: FlatGround or ProfileGround (kernels specialise on its type)


class Workspace(NamedTuple):
    """Preallocated buffers for one right-hand-side evaluation."""

    phi_q: np.ndarray  # (m, n)
    minv_phi_t: np.ndarray  # (n, m) M^-1 Phi_q^T
    minv: np.ndarray  # (nb, 4, 4) inverse of each modified rotational mass block
    schur: np.ndarray  # (m, m)
    rhs: np.ndarray  # (m,)
    lam: np.ndarray  # (m,)
    force: np.ndarray  # (n,) generalized applied forces Q


def joint_rows(system: SpatialSystem) -> int:
    """Number of joint constraint rows (the normalisation rows come after them)."""
    return int(PRIMITIVE_ROWS[system.con_type].sum())


def make_workspace(system: SpatialSystem) -> Workspace:
    """Allocate the buffers of ``system`` (once per simulation, not per step)."""
    nb = system.body_mass.shape[0]
    n = 7 * nb
    m = joint_rows(system) + nb
    return Workspace(
        np.zeros((m, n)),
        np.zeros((n, m)),
        np.zeros((nb, 4, 4)),
        np.zeros((m, m)),
        np.zeros(m),
        np.zeros(m),
        np.zeros(n),
    )


# ---------------------------------------------------------------- constraints


@kernel(reference_counts=False)
def constraint_terms(
    y: np.ndarray, system: SpatialSystem, c: int, phi_q: np.ndarray, fill: bool
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Phi, Phidot and gamma_c = -(Phi_q qd)_q qd of primitive c (3 each, unused rows 0).

    With ``fill`` the primitive's rows of the Jacobian phi_q are written (the caller zeroes it).
    """
    nb = system.body_mass.shape[0]
    a, b = system.con_bodies[c, 0], system.con_bodies[c, 1]
    kind = system.con_type[c]
    row = system.con_row[c]
    p_a = parameters(y, a)
    pd_a = parameters(y, nb + a)
    if kind == SPHERICAL:
        s_a = vec3(system.con_vecs, c, 0)
        s_b = vec3(system.con_vecs, c, 3)
        x_a, v_a = point_state(y, nb, a, s_a)
        g_a = b_mul(pd_a, s_a, pd_a)
        x_b, v_b, g_b = s_b, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        if b >= 0:
            x_b, v_b = point_state(y, nb, b, s_b)
            pd_b = parameters(y, nb + b)
            g_b = b_mul(pd_b, s_b, pd_b)
        if fill:
            for j in range(4):
                col_a = b_mul(p_a, s_a, unit4(j))
                for k in range(3):
                    phi_q[row + k, 7 * a + 3 + j] = col_a[k]
                if b >= 0:
                    col_b = b_mul(parameters(y, b), s_b, unit4(j))
                    for k in range(3):
                        phi_q[row + k, 7 * b + 3 + j] = -col_b[k]
            for k in range(3):
                phi_q[row + k, 7 * a + k] = 1.0
                if b >= 0:
                    phi_q[row + k, 7 * b + k] = -1.0
        return (
            x_a[0] - x_b[0],
            x_a[1] - x_b[1],
            x_a[2] - x_b[2],
            v_a[0] - v_b[0],
            v_a[1] - v_b[1],
            v_a[2] - v_b[2],
            g_b[0] - g_a[0],
            g_b[1] - g_a[1],
            g_b[2] - g_a[2],
        )
    if kind == PERPENDICULAR:
        u_a = vec3(system.con_vecs, c, 0)
        w_b = vec3(system.con_vecs, c, 3)
        va = rotate(p_a, u_a)
        va_dot = b_mul(p_a, u_a, pd_a)
        gamma = -dot3(w_b, b_mul(pd_a, u_a, pd_a)) if b < 0 else 0.0
        vb, vb_dot = w_b, (0.0, 0.0, 0.0)
        if b >= 0:
            p_b = parameters(y, b)
            pd_b = parameters(y, nb + b)
            vb = rotate(p_b, w_b)
            vb_dot = b_mul(p_b, w_b, pd_b)
            gamma = -(dot3(vb, b_mul(pd_a, u_a, pd_a)) + 2.0 * dot3(va_dot, vb_dot) + dot3(va, b_mul(pd_b, w_b, pd_b)))
            if fill:
                jb = b_tmul(p_b, w_b, va)
                for j in range(4):
                    phi_q[row, 7 * b + 3 + j] = jb[j]
        if fill:
            ja = b_tmul(p_a, u_a, vb)
            for j in range(4):
                phi_q[row, 7 * a + 3 + j] = ja[j]
        return dot3(va, vb), 0.0, 0.0, dot3(va_dot, vb) + dot3(va, vb_dot), 0.0, 0.0, gamma, 0.0, 0.0
    # IN_PLANE: n.(r_a + A_a s_a) = offset, n fixed
    s_a = vec3(system.con_vecs, c, 0)
    n = vec3(system.con_vecs, c, 3)
    x_a, v_a = point_state(y, nb, a, s_a)
    if fill:
        ja = b_tmul(p_a, s_a, n)
        for k in range(3):
            phi_q[row, 7 * a + k] = n[k]
        for j in range(4):
            phi_q[row, 7 * a + 3 + j] = ja[j]
    gamma = -dot3(n, b_mul(pd_a, s_a, pd_a))
    return dot3(n, x_a) - system.con_vecs[c, 6], 0.0, 0.0, dot3(n, v_a), 0.0, 0.0, gamma, 0.0, 0.0


@kernel
def normalisation(y: np.ndarray, nb: int, b: int) -> tuple[float, float, float]:
    """Phi = p.p - 1, Phidot = 2 p.pdot, gamma_c = -2 pdot.pdot of body b."""
    p = parameters(y, b)
    pd = parameters(y, nb + b)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    ppd = p[0] * pd[0] + p[1] * pd[1] + p[2] * pd[2] + p[3] * pd[3]
    pdpd = pd[0] * pd[0] + pd[1] * pd[1] + pd[2] * pd[2] + pd[3] * pd[3]
    return pp - 1.0, 2.0 * ppd, -2.0 * pdpd


@kernel(reference_counts=False)
def mass_blocks(y: np.ndarray, system: SpatialSystem, minv: np.ndarray) -> None:
    """minv[b] = (G^T J'^-1 G + p p^T / j) / (4 |p|^4): inverse of 4 G^T J' G + 4 j p p^T."""
    jinv = system.body_inertia_inv
    for b in range(system.body_mass.shape[0]):
        p = parameters(y, b)
        pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
        j_ref = (system.body_inertia[b, 0, 0] + system.body_inertia[b, 1, 1] + system.body_inertia[b, 2, 2]) / 3.0
        scale = 1.0 / (4.0 * pp * pp)
        for i in range(4):
            t = inertia_mul(jinv, b, g_col(p, i))
            for k in range(i, 4):
                v = (dot3(g_col(p, k), t) + p[i] * p[k] / j_ref) * scale
                minv[b, i, k] = v
                minv[b, k, i] = v


@kernel(reference_counts=False)
def constrained_accelerations(y: np.ndarray, system: SpatialSystem, work: Workspace, qdd: np.ndarray) -> None:
    """Accelerations from the augmented system with Baumgarte stabilisation (forces in work.force)."""
    nb = system.body_mass.shape[0]
    n = 7 * nb
    nc = system.con_type.shape[0]
    alpha, beta = system.baumgarte[0], system.baumgarte[1]
    phi_q, rhs, x = work.phi_q, work.rhs, work.minv_phi_t
    m = rhs.shape[0]
    mj = m - nb
    phi_q[:, :] = 0.0
    for c in range(nc):
        terms = constraint_terms(y, system, c, phi_q, True)
        for k in range(PRIMITIVE_ROWS[system.con_type[c]]):
            rhs[system.con_row[c] + k] = terms[6 + k] - 2.0 * alpha * terms[3 + k] - beta * beta * terms[k]
    for b in range(nb):
        phi, phi_dot, gamma = normalisation(y, nb, b)
        for k in range(4):
            phi_q[mj + b, 7 * b + 3 + k] = 2.0 * y[7 * b + 3 + k]
        rhs[mj + b] = gamma - 2.0 * alpha * phi_dot - beta * beta * phi
    minv = work.minv
    mass_blocks(y, system, minv)
    force = work.force
    # x = M^-1 Phi_q^T and qdd = M^-1 Q (block by block)
    for b in range(nb):
        inv_m = 1.0 / system.body_mass[b]
        for k in range(3):
            qdd[7 * b + k] = force[7 * b + k] * inv_m
            for r in range(m):
                x[7 * b + k, r] = phi_q[r, 7 * b + k] * inv_m
        for i in range(4):
            v = 0.0
            for k in range(4):
                v += minv[b, i, k] * force[7 * b + 3 + k]
            qdd[7 * b + 3 + i] = v
            for r in range(m):
                s = 0.0
                for k in range(4):
                    s += minv[b, i, k] * phi_q[r, 7 * b + 3 + k]
                x[7 * b + 3 + i, r] = s
    schur, lam = work.schur, work.lam
    for r in range(m):
        v = -rhs[r]
        for c in range(n):
            v += phi_q[r, c] * qdd[c]
        lam[r] = v
        for s_ in range(r + 1):
            acc = 0.0
            for c in range(n):
                acc += phi_q[r, c] * x[c, s_]
            schur[r, s_] = acc
            schur[s_, r] = acc
    cholesky_solve(schur, lam, m)
    for c in range(n):
        v = qdd[c]
        for r in range(m):
            v -= x[c, r] * lam[r]
        qdd[c] = v


@kernel(by_symbol=True)  # a measure: per check or sample
def constraint_violation(y: np.ndarray, system: SpatialSystem, phi_q: np.ndarray) -> tuple[float, float, float]:
    """||Phi|| and ||Phidot|| over the joints, and ||p.p - 1|| over the bodies (Euler normalisation)."""
    pos = 0.0
    vel = 0.0
    for c in range(system.con_type.shape[0]):
        terms = constraint_terms(y, system, c, phi_q, False)
        for k in range(3):
            pos += terms[k] * terms[k]
            vel += terms[3 + k] * terms[3 + k]
    norm = 0.0
    nb = system.body_mass.shape[0]
    for b in range(nb):
        phi = normalisation(y, nb, b)[0]
        norm += phi * phi
    return math.sqrt(pos), math.sqrt(vel), math.sqrt(norm)
