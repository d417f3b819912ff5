"""Spatial multibody dynamics with Euler parameters (MODEL.md 2, the paper's own formulation), compiled with numba.

Each body i has q_i = (r_i, p_i): the centre of mass r_i in the slope frame (x downhill along the
slope, y along its normal, z lateral: x, y, z right-handed) and the Euler parameters
p_i = (e0, e) with the normalisation constraint p_i.p_i - 1 = 0 (Nikravesh, Computer-Aided
Analysis of Mechanical Systems, ch. 6, whose notation is used here):

* A(p) = E G^T = (e0^2 - e.e) I + 2 e e^T + 2 e0 e~ (exactly orthonormal when |p| = 1; the
  homogeneous quadratic form |p|^2 R is used everywhere, so that every Jacobian is exact);
* E = [-e, e~ + e0 I], G = [-e, -e~ + e0 I]: omega = 2 E pdot (global), omega' = 2 G pdot (body);
* the point r + A(p) s' of a body has velocity rdot + B(p, s') pdot with the exact 3 x 4 Jacobian
  B(p, s') = d(A s')/dp = 2 [e0 s' + e~ s', (e.s') I + e s'^T - s' e^T - e0 s'~], linear in p, so
  its acceleration is B(p, s') pdd + B(pdot, s') pdot;
* T = m rdot^2 / 2 + 2 pdot^T G^T J' G pdot, whose Lagrange equations are
  m rdd = f and 4 G^T J' G pdd = 8 Gdot^T J' Gdot p + B^T f_P (forces f_P at points), with J'
  the inertia about the centre of mass in the body frame.

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

Feet: a disc of radius R (a circle in the body's x'-y' plane, the sagittal plane, around its
local axis, normally z': the 3D form of the planar walker's arc) or a sphere (axis = 0). The
contact point is the lowest point of the circle (of the sphere) with respect to the ground
plane y = 0; penetration, approach velocity and the 2D slip velocity (x, z) are those of the
material point there. The scalar friction laws of :mod:`biped_sim.contact.friction` act along
the slip direction: F_T = F(|v|) v / |v|, exactly 0 at |v| = 0 (every law is odd in v and
vanishes at 0, so this is continuous). LuGre carries a 2-vector bristle state per foot,
zdot = v - sigma0 |v| z / g(|v|), written with the scalar law as
zdot_k = rate(|v|, z_k) - |v| + v_k, and F_k = lugre_friction(v_k, z_k, zdot_k, F_N).

The ODE state is y = [q (7 nb) | qd (7 nb) | z (2 nf: x and z bristles per foot) | W_normal | W_friction].
Everything compiled here is allocation-free: buffers live in :class:`Workspace`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.contact.friction import LUGRE, friction_force, lugre_bristle_rate, lugre_friction
from biped_sim.contact.normal import elastic_energy, elastic_force, normal_force
from biped_sim.multibody.planar import (
    ARMED,
    FALL_HIP_HEIGHT,
    FALL_LEG_ANGLE,
    FRICTION_MODEL,
    IMPACT_FLOOR,
    IMPACT_SPEED,
    NORMAL_MODEL,
    SCUFFING_GUARD,
    TOUCHING,
    cholesky_solve,
)

# constraint primitives and their row counts
SPHERICAL, PERPENDICULAR, IN_PLANE = 0, 1, 2
PRIMITIVE_ROWS = np.array([3, 1, 1], dtype=np.int64)

__all__ = [
    "ARMED",
    "IMPACT_SPEED",
    "IN_PLANE",
    "PERPENDICULAR",
    "SPHERICAL",
    "TOUCHING",
    "SpatialSystem",
    "Workspace",
]


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
    foot_partner: np.ndarray  # (nf,) int64: the foot this one must be ahead of to arm (-1: none)
    gravity: np.ndarray  # (3,) in the slope frame
    baumgarte: np.ndarray  # (2,) alpha, beta
    normal_params: np.ndarray
    friction_params: np.ndarray
    switches: np.ndarray  # (3,) int64: normal model, friction model, scuffing guard
    limits: np.ndarray  # (3,) impact velocity floor, fall hip height, fall leg angle


class Workspace(NamedTuple):
    """Preallocated buffers for one right-hand-side evaluation."""

    phi_q: np.ndarray  # (m, n)
    minv_phi_t: np.ndarray  # (n, m) M^-1 Phi_q^T
    minv: np.ndarray  # (nb, 4, 4) inverse of each modified rotational mass block
    schur: np.ndarray  # (m, m)
    rhs: np.ndarray  # (m,)
    lam: np.ndarray  # (m,)
    force: np.ndarray  # (n,) generalized applied forces Q
    onset: np.ndarray  # (nf,) int64: set by update_modes when a foot touches down


def joint_rows(system: SpatialSystem) -> int:
    """Number of joint constraint rows (the normalisation rows come after them)."""
    return int(PRIMITIVE_ROWS[system.con_type].sum())


def make_workspace(system: SpatialSystem) -> Workspace:
    """Allocate the buffers of ``system`` (once per simulation, not per step)."""
    nb = system.body_mass.shape[0]
    n = 7 * nb
    m = joint_rows(system) + nb
    nf = system.foot_body.shape[0]
    return Workspace(
        np.zeros((m, n)),
        np.zeros((n, m)),
        np.zeros((nb, 4, 4)),
        np.zeros((m, m)),
        np.zeros(m),
        np.zeros(m),
        np.zeros(n),
        np.zeros(nf, dtype=np.int64),
    )


def state_size(system: SpatialSystem) -> int:
    """Length of the ODE state vector."""
    return 14 * system.body_mass.shape[0] + 2 * system.foot_body.shape[0] + 2


# ---------------------------------------------------------------- Euler-parameter kinematics


@njit(cache=True)
def rotate(p: tuple, s: tuple) -> tuple[float, float, float]:
    """A(p) s."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    c = e0 * e0 - e1 * e1 - e2 * e2 - e3 * e3
    es = 2.0 * (e1 * s0 + e2 * s1 + e3 * s2)
    x0 = e2 * s2 - e3 * s1
    x1 = e3 * s0 - e1 * s2
    x2 = e1 * s1 - e2 * s0
    return c * s0 + es * e1 + 2.0 * e0 * x0, c * s1 + es * e2 + 2.0 * e0 * x1, c * s2 + es * e3 + 2.0 * e0 * x2


@njit(cache=True)
def rotate_t(p: tuple, f: tuple) -> tuple[float, float, float]:
    """A(p)^T f (A of the conjugate parameters)."""
    return rotate((p[0], -p[1], -p[2], -p[3]), f)


@njit(cache=True)
def b_mul(p: tuple, s: tuple, x: tuple) -> tuple[float, float, float]:
    """B(p, s) x = 2 [(e0 s + e x s) x0 + (e.s) xv + e (s.xv) - s (e.xv) - e0 (s x xv)]."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    x0, v0, v1, v2 = x
    es = e1 * s0 + e2 * s1 + e3 * s2
    sv = s0 * v0 + s1 * v1 + s2 * v2
    ev = e1 * v0 + e2 * v1 + e3 * v2
    c0 = e0 * s0 + e2 * s2 - e3 * s1
    c1 = e0 * s1 + e3 * s0 - e1 * s2
    c2 = e0 * s2 + e1 * s1 - e2 * s0
    w0 = s1 * v2 - s2 * v1
    w1 = s2 * v0 - s0 * v2
    w2 = s0 * v1 - s1 * v0
    return (
        2.0 * (c0 * x0 + es * v0 + e1 * sv - s0 * ev - e0 * w0),
        2.0 * (c1 * x0 + es * v1 + e2 * sv - s1 * ev - e0 * w1),
        2.0 * (c2 * x0 + es * v2 + e3 * sv - s2 * ev - e0 * w2),
    )


@njit(cache=True)
def b_tmul(p: tuple, s: tuple, f: tuple) -> tuple[float, float, float, float]:
    """B(p, s)^T f = 2 [(e0 s + e x s).f, (e.s) f + s (e.f) - e (s.f) + e0 (s x f)]."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    f0, f1, f2 = f
    es = e1 * s0 + e2 * s1 + e3 * s2
    ef = e1 * f0 + e2 * f1 + e3 * f2
    sf = s0 * f0 + s1 * f1 + s2 * f2
    c0 = e0 * s0 + e2 * s2 - e3 * s1
    c1 = e0 * s1 + e3 * s0 - e1 * s2
    c2 = e0 * s2 + e1 * s1 - e2 * s0
    return (
        2.0 * (c0 * f0 + c1 * f1 + c2 * f2),
        2.0 * (es * f0 + s0 * ef - e1 * sf + e0 * (s1 * f2 - s2 * f1)),
        2.0 * (es * f1 + s1 * ef - e2 * sf + e0 * (s2 * f0 - s0 * f2)),
        2.0 * (es * f2 + s2 * ef - e3 * sf + e0 * (s0 * f1 - s1 * f0)),
    )


@njit(cache=True)
def g_mul(p: tuple, x: tuple) -> tuple[float, float, float]:
    """G(p) x = -e x0 + e0 xv - e x xv (omega' = 2 G pdot)."""
    e0, e1, e2, e3 = p
    x0, v0, v1, v2 = x
    return (
        -e1 * x0 + e0 * v0 - (e2 * v2 - e3 * v1),
        -e2 * x0 + e0 * v1 - (e3 * v0 - e1 * v2),
        -e3 * x0 + e0 * v2 - (e1 * v1 - e2 * v0),
    )


@njit(cache=True)
def g_tmul(p: tuple, w: tuple) -> tuple[float, float, float, float]:
    """G(p)^T w = (-e.w, e0 w + e x w)."""
    e0, e1, e2, e3 = p
    w0, w1, w2 = w
    return (
        -(e1 * w0 + e2 * w1 + e3 * w2),
        e0 * w0 + e2 * w2 - e3 * w1,
        e0 * w1 + e3 * w0 - e1 * w2,
        e0 * w2 + e1 * w1 - e2 * w0,
    )


@njit(cache=True)
def e_mul(p: tuple, x: tuple) -> tuple[float, float, float]:
    """E(p) x = -e x0 + e0 xv + e x xv (omega = 2 E pdot)."""
    e0, e1, e2, e3 = p
    x0, v0, v1, v2 = x
    return (
        -e1 * x0 + e0 * v0 + (e2 * v2 - e3 * v1),
        -e2 * x0 + e0 * v1 + (e3 * v0 - e1 * v2),
        -e3 * x0 + e0 * v2 + (e1 * v1 - e2 * v0),
    )


@njit(cache=True)
def _pos(y: np.ndarray, b: int) -> tuple[float, float, float]:
    return y[7 * b], y[7 * b + 1], y[7 * b + 2]


@njit(cache=True)
def _par(y: np.ndarray, b: int) -> tuple[float, float, float, float]:
    return y[7 * b + 3], y[7 * b + 4], y[7 * b + 5], y[7 * b + 6]


@njit(cache=True)
def _vec(a: np.ndarray, row: int, k: int) -> tuple[float, float, float]:
    return a[row, k], a[row, k + 1], a[row, k + 2]


@njit(cache=True)
def _dot(a: tuple, b: tuple) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _inertia_mul(j: np.ndarray, b: int, w: tuple) -> tuple[float, float, float]:
    return (
        j[b, 0, 0] * w[0] + j[b, 0, 1] * w[1] + j[b, 0, 2] * w[2],
        j[b, 1, 0] * w[0] + j[b, 1, 1] * w[1] + j[b, 1, 2] * w[2],
        j[b, 2, 0] * w[0] + j[b, 2, 1] * w[1] + j[b, 2, 2] * w[2],
    )


@njit(cache=True)
def point_state(
    y: np.ndarray, nb: int, b: int, s: tuple
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(position, velocity) of the body-frame point s of body b: r + A s, rdot + B(p, s) pdot."""
    r = _pos(y, b)
    p = _par(y, b)
    a = rotate(p, s)
    v = _pos(y, nb + b)
    w = b_mul(p, s, _par(y, nb + b))
    return (r[0] + a[0], r[1] + a[1], r[2] + a[2]), (v[0] + w[0], v[1] + w[1], v[2] + w[2])


@njit(cache=True)
def _g_col(p: tuple, j: int) -> tuple[float, float, float]:
    """Column j of G(p) = [-e, e0 I - e~]."""
    e0, e1, e2, e3 = p
    if j == 0:
        return -e1, -e2, -e3
    if j == 1:
        return e0, -e3, e2
    if j == 2:
        return e3, e0, -e1
    return -e2, e1, e0


@njit(cache=True)
def _unit4(j: int) -> tuple[float, float, float, float]:
    return (1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0, 1.0 if j == 3 else 0.0)


@njit(cache=True)
def attitude(y: np.ndarray, nb: int, b: int) -> tuple[float, float, float, float]:
    """(pitch, roll, yaw, omega_z) of body b.

    pitch is the sagittal angle of the body's -y' axis (its legs) from the slope normal, positive
    with the feet downhill (the planar leg angle); roll the elevation of its lateral z' axis above
    the slope plane (lateral rocking); yaw the heading of z' about the normal (drift); omega_z the
    global angular rate about the lateral axis (the planar leg angle rate).
    """
    p = _par(y, b)
    norm = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    ay = rotate(p, (0.0, 1.0, 0.0))
    az = rotate(p, (0.0, 0.0, 1.0))
    sin_roll = min(1.0, max(-1.0, az[1] / norm))
    omega = e_mul(p, _par(y, nb + b))
    return math.atan2(-ay[0], ay[1]), math.asin(sin_roll), math.atan2(-az[0], az[2]), 2.0 * omega[2]


# ---------------------------------------------------------------- constraints


@njit(cache=True)
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
    p_a = _par(y, a)
    pd_a = _par(y, nb + a)
    if kind == SPHERICAL:
        s_a = _vec(system.con_vecs, c, 0)
        s_b = _vec(system.con_vecs, c, 3)
        x_a, v_a = point_state(y, nb, a, s_a)
        g_a = b_mul(pd_a, s_a, pd_a)
        x_b, v_b, g_b = s_b, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        if b >= 0:
            x_b, v_b = point_state(y, nb, b, s_b)
            pd_b = _par(y, nb + b)
            g_b = b_mul(pd_b, s_b, pd_b)
        if fill:
            for j in range(4):
                col_a = b_mul(p_a, s_a, _unit4(j))
                for k in range(3):
                    phi_q[row + k, 7 * a + 3 + j] = col_a[k]
                if b >= 0:
                    col_b = b_mul(_par(y, b), s_b, _unit4(j))
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
        u_a = _vec(system.con_vecs, c, 0)
        w_b = _vec(system.con_vecs, c, 3)
        va = rotate(p_a, u_a)
        va_dot = b_mul(p_a, u_a, pd_a)
        gamma = -_dot(w_b, b_mul(pd_a, u_a, pd_a)) if b < 0 else 0.0
        vb, vb_dot = w_b, (0.0, 0.0, 0.0)
        if b >= 0:
            p_b = _par(y, b)
            pd_b = _par(y, nb + b)
            vb = rotate(p_b, w_b)
            vb_dot = b_mul(p_b, w_b, pd_b)
            gamma = -(_dot(vb, b_mul(pd_a, u_a, pd_a)) + 2.0 * _dot(va_dot, vb_dot) + _dot(va, b_mul(pd_b, w_b, pd_b)))
            if fill:
                jb = b_tmul(p_b, w_b, va)
                for j in range(4):
                    phi_q[row, 7 * b + 3 + j] = jb[j]
        if fill:
            ja = b_tmul(p_a, u_a, vb)
            for j in range(4):
                phi_q[row, 7 * a + 3 + j] = ja[j]
        return _dot(va, vb), 0.0, 0.0, _dot(va_dot, vb) + _dot(va, vb_dot), 0.0, 0.0, gamma, 0.0, 0.0
    # IN_PLANE: n.(r_a + A_a s_a) = offset, n fixed
    s_a = _vec(system.con_vecs, c, 0)
    n = _vec(system.con_vecs, c, 3)
    x_a, v_a = point_state(y, nb, a, s_a)
    if fill:
        ja = b_tmul(p_a, s_a, n)
        for k in range(3):
            phi_q[row, 7 * a + k] = n[k]
        for j in range(4):
            phi_q[row, 7 * a + 3 + j] = ja[j]
    gamma = -_dot(n, b_mul(pd_a, s_a, pd_a))
    return _dot(n, x_a) - system.con_vecs[c, 6], 0.0, 0.0, _dot(n, v_a), 0.0, 0.0, gamma, 0.0, 0.0


@njit(cache=True)
def _normalisation(y: np.ndarray, nb: int, b: int) -> tuple[float, float, float]:
    """Phi = p.p - 1, Phidot = 2 p.pdot, gamma_c = -2 pdot.pdot of body b."""
    p = _par(y, b)
    pd = _par(y, nb + b)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    ppd = p[0] * pd[0] + p[1] * pd[1] + p[2] * pd[2] + p[3] * pd[3]
    pdpd = pd[0] * pd[0] + pd[1] * pd[1] + pd[2] * pd[2] + pd[3] * pd[3]
    return pp - 1.0, 2.0 * ppd, -2.0 * pdpd


@njit(cache=True)
def _mass_blocks(y: np.ndarray, system: SpatialSystem, minv: np.ndarray) -> None:
    """minv[b] = (G^T J'^-1 G + p p^T / j) / (4 |p|^4): inverse of 4 G^T J' G + 4 j p p^T."""
    jinv = system.body_inertia_inv
    for b in range(system.body_mass.shape[0]):
        p = _par(y, b)
        pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
        j_ref = (system.body_inertia[b, 0, 0] + system.body_inertia[b, 1, 1] + system.body_inertia[b, 2, 2]) / 3.0
        scale = 1.0 / (4.0 * pp * pp)
        for i in range(4):
            t = _inertia_mul(jinv, b, _g_col(p, i))
            for k in range(i, 4):
                v = (_dot(_g_col(p, k), t) + p[i] * p[k] / j_ref) * scale
                minv[b, i, k] = v
                minv[b, k, i] = v


@njit(cache=True)
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
        phi, phi_dot, gamma = _normalisation(y, nb, b)
        for k in range(4):
            phi_q[mj + b, 7 * b + 3 + k] = 2.0 * y[7 * b + 3 + k]
        rhs[mj + b] = gamma - 2.0 * alpha * phi_dot - beta * beta * phi
    minv = work.minv
    _mass_blocks(y, system, minv)
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


# ---------------------------------------------------------------- contact


@njit(cache=True)
def foot_kinematics(
    y: np.ndarray, system: SpatialSystem, i: int
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Foot i against the ground plane y = 0 with normal n = (0, 1, 0).

    Returns (delta, delta_dot, slip_x, slip_z, x_contact, z_contact, s0, s1, s2): penetration
    -P.n of the lowest point P of the disc (sphere), approach velocity -v_P.n and 2D slip
    velocity (v_P.x, v_P.z) of the material point at P, P's position in the ground plane, and
    s' = A^-1 (P - r), the body-frame lever of the contact force (its velocity is
    rdot + B(p, s') pdot, so the contact power and the generalized force B^T F agree exactly).
    """
    nb = system.body_mass.shape[0]
    b = system.foot_body[i]
    r = _pos(y, b)
    p = _par(y, b)
    radius = system.foot_radius[i]
    centre = rotate(p, _vec(system.foot_center, i, 0))
    axis = _vec(system.foot_axis, i, 0)
    d = (0.0, -1.0, 0.0)
    if _dot(axis, axis) > 0.0:
        a = rotate(p, axis)
        inv = 1.0 / math.sqrt(_dot(a, a))
        a0, a1, a2 = a[0] * inv, a[1] * inv, a[2] * inv
        norm = math.sqrt(max(1.0 - a1 * a1, 1e-300))
        d = (a1 * a0 / norm, -(1.0 - a1 * a1) / norm, a1 * a2 / norm)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    local_d = rotate_t(p, d)
    sc = _vec(system.foot_center, i, 0)
    scale = radius / (pp * pp)
    s = (sc[0] + scale * local_d[0], sc[1] + scale * local_d[1], sc[2] + scale * local_d[2])
    px = r[0] + centre[0] + radius * d[0]
    py = r[1] + centre[1] + radius * d[1]
    pz = r[2] + centre[2] + radius * d[2]
    v = _pos(y, nb + b)
    w = b_mul(p, s, _par(y, nb + b))
    return -py, -(v[1] + w[1]), v[0] + w[0], v[2] + w[2], px, pz, s[0], s[1], s[2]


@njit(cache=True)
def foot_forces(
    y: np.ndarray, system: SpatialSystem, modes: np.ndarray, i: int
) -> tuple[float, float, float, float, float, float, float, float, float, float, float, float, float, float]:
    """Contact forces on foot i and their dissipation rates.

    Returns (F_N, F_x, F_z, zdot_x, zdot_z, P_normal, P_friction, delta, delta_dot, slip_x,
    slip_z, s0, s1, s2): the normal force along the ground normal, the friction force in the
    ground plane, the LuGre bristle rates, the powers lost in the normal damping
    (F_N - K delta^n) deltadot and in friction -F_T.v_t, the kinematics and the body-frame lever.
    """
    delta, delta_dot, vx, vz, _, _, s0, s1, s2 = foot_kinematics(y, system, i)
    f_n = 0.0
    f_x = 0.0
    f_z = 0.0
    zdx = 0.0
    zdz = 0.0
    p_normal = 0.0
    p_friction = 0.0
    if modes[i, ARMED] > 0.5 and delta > 0.0:
        impact = modes[i, IMPACT_SPEED] if modes[i, TOUCHING] > 0.5 else delta_dot
        floor = system.limits[IMPACT_FLOOR]
        if impact < floor:
            impact = floor
        npar = system.normal_params
        f_n = normal_force(system.switches[NORMAL_MODEL], delta, delta_dot, impact, npar)
        p_normal = (f_n - elastic_force(delta, npar)) * delta_dot
        fpar = system.friction_params
        speed = math.sqrt(vx * vx + vz * vz)
        if system.switches[FRICTION_MODEL] == LUGRE:
            k = 14 * system.body_mass.shape[0] + 2 * i
            zx, zz = y[k], y[k + 1]
            zdx = lugre_bristle_rate(speed, zx, fpar) - speed + vx
            zdz = lugre_bristle_rate(speed, zz, fpar) - speed + vz
            f_x = lugre_friction(vx, zx, zdx, f_n, fpar)
            f_z = lugre_friction(vz, zz, zdz, f_n, fpar)
        elif speed > 0.0:
            f_t = friction_force(system.switches[FRICTION_MODEL], speed, f_n, fpar)
            f_x = f_t * (vx / speed)
            f_z = f_t * (vz / speed)
        p_friction = -(f_x * vx + f_z * vz)
    return f_n, f_x, f_z, zdx, zdz, p_normal, p_friction, delta, delta_dot, vx, vz, s0, s1, s2


@njit(cache=True)
def rhs(t: float, y: np.ndarray, system: SpatialSystem, modes: np.ndarray, work: Workspace, ydot: np.ndarray) -> None:
    """Right-hand side ydot = f(t, y) for the current contact modes (allocation-free)."""
    nb = system.body_mass.shape[0]
    n = 7 * nb
    nf = system.foot_body.shape[0]
    force = work.force
    g = system.gravity
    for b in range(nb):
        m = system.body_mass[b]
        force[7 * b] = m * g[0]
        force[7 * b + 1] = m * g[1]
        force[7 * b + 2] = m * g[2]
        # quadratic-velocity term 8 Gdot^T J' Gdot p
        pd = _par(y, nb + b)
        h = _inertia_mul(system.body_inertia, b, g_mul(pd, _par(y, b)))
        q = g_tmul(pd, h)
        for k in range(4):
            force[7 * b + 3 + k] = 8.0 * q[k]
    for c in range(n):
        ydot[c] = y[n + c]
    w_normal = 0.0
    w_friction = 0.0
    for i in range(nf):
        f_n, f_x, f_z, zdx, zdz, p_n, p_f, _, _, _, _, s0, s1, s2 = foot_forces(y, system, modes, i)
        b = system.foot_body[i]
        force[7 * b] += f_x
        force[7 * b + 1] += f_n
        force[7 * b + 2] += f_z
        q = b_tmul(_par(y, b), (s0, s1, s2), (f_x, f_n, f_z))
        for k in range(4):
            force[7 * b + 3 + k] += q[k]
        ydot[2 * n + 2 * i] = zdx
        ydot[2 * n + 2 * i + 1] = zdz
        w_normal += p_n
        w_friction += p_f
    ydot[2 * n + 2 * nf] = w_normal
    ydot[2 * n + 2 * nf + 1] = w_friction
    constrained_accelerations(y, system, work, ydot[n : 2 * n])


# ---------------------------------------------------------------- measurements and events


@njit(cache=True)
def mechanical_energy(y: np.ndarray, system: SpatialSystem, modes: np.ndarray) -> tuple[float, float, float]:
    """(kinetic, potential, elastic) energy; kinetic = m rdot^2/2 + omega'.J' omega'/2, omega' = 2 G pdot."""
    nb = system.body_mass.shape[0]
    kinetic = 0.0
    potential = 0.0
    g = system.gravity
    for b in range(nb):
        m = system.body_mass[b]
        v = _pos(y, nb + b)
        w = g_mul(_par(y, b), _par(y, nb + b))
        w = (2.0 * w[0], 2.0 * w[1], 2.0 * w[2])
        kinetic += 0.5 * m * _dot(v, v) + 0.5 * _dot(w, _inertia_mul(system.body_inertia, b, w))
        potential -= m * _dot(g, _pos(y, b))
    elastic = 0.0
    for i in range(system.foot_body.shape[0]):
        delta = foot_kinematics(y, system, i)[0]
        if modes[i, ARMED] > 0.5 and delta > 0.0:
            elastic += elastic_energy(delta, system.normal_params)
    return kinetic, potential, elastic


@njit(cache=True)
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
        phi = _normalisation(y, nb, b)[0]
        norm += phi * phi
    return math.sqrt(pos), math.sqrt(vel), math.sqrt(norm)


@njit(cache=True)
def event_functions(y: np.ndarray, system: SpatialSystem, g: np.ndarray) -> None:
    """Per foot: delta and (x_foot - x_partner), as in the planar engine."""
    nf = system.foot_body.shape[0]
    for i in range(nf):
        kin = foot_kinematics(y, system, i)
        g[2 * i] = kin[0]
        partner = system.foot_partner[i]
        g[2 * i + 1] = kin[4] - foot_kinematics(y, system, partner)[4] if partner >= 0 else 1.0


@njit(cache=True)
def update_modes(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, work: Workspace) -> bool:
    """Scuffing guard and contact onset/separation bookkeeping at an event (MODEL.md 3; as planar).

    A touchdown remembers deltadot^- and zeroes the foot's LuGre bristles. work.onset[i] marks a
    touchdown of foot i only when no other foot of the same body was touching or touched down in
    this update: the feet of one leg pair land together and make one heel strike.
    Returns True when any mode changed.
    """
    nb = system.body_mass.shape[0]
    nf = system.foot_body.shape[0]
    changed = False
    lugre = system.switches[FRICTION_MODEL] == LUGRE
    for i in range(nf):  # 2 marks a foot touching before this update, 1 a touchdown in it
        work.onset[i] = 2 if modes[i, TOUCHING] > 0.5 else 0
    for i in range(nf):
        kin = foot_kinematics(y, system, i)
        delta, delta_dot = kin[0], kin[1]
        partner = system.foot_partner[i]
        ahead = kin[4] - foot_kinematics(y, system, partner)[4] if partner >= 0 else 1.0
        armed = modes[i, ARMED] > 0.5
        if system.switches[SCUFFING_GUARD] == 0:
            new_armed = True
        elif armed:
            new_armed = not (delta <= 0.0 and ahead <= 0.0)
        else:
            new_armed = delta < 0.0 and ahead > 0.0
        touching = new_armed and delta > 0.0
        was_touching = modes[i, TOUCHING] > 0.5
        if touching and not was_touching:
            modes[i, IMPACT_SPEED] = delta_dot
            first = True
            for j in range(nf):
                if j != i and system.foot_body[j] == system.foot_body[i] and work.onset[j] > 0:
                    first = False
            if first:
                work.onset[i] = 1
        if touching != was_touching or new_armed != armed:
            changed = True
            if lugre and touching and not was_touching:
                y[14 * nb + 2 * i] = 0.0
                y[14 * nb + 2 * i + 1] = 0.0
        modes[i, ARMED] = 1.0 if new_armed else 0.0
        modes[i, TOUCHING] = 1.0 if touching else 0.0
    for i in range(nf):
        if work.onset[i] == 2:
            work.onset[i] = 0
    return changed


@njit(cache=True)
def has_fallen(y: np.ndarray, system: SpatialSystem) -> bool:
    """Fall: the hip (point s_a of primitive 0) below the height limit, or a body's legs tilted past the limit angle."""
    nb = system.body_mass.shape[0]
    if system.con_type.shape[0] > 0:
        hip = point_state(y, nb, system.con_bodies[0, 0], _vec(system.con_vecs, 0, 0))[0]
        if hip[1] < system.limits[FALL_HIP_HEIGHT]:
            return True
    for b in range(nb):
        p = _par(y, b)
        pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
        cos_tilt = rotate(p, (0.0, 1.0, 0.0))[1] / pp
        if math.acos(min(1.0, max(-1.0, cos_tilt))) > system.limits[FALL_LEG_ANGLE]:
            return True
    return False


@njit(cache=True)
def approach_velocity(y: np.ndarray, system: SpatialSystem, foot: int) -> float:
    """Normal approach velocity deltadot of a foot."""
    return foot_kinematics(y, system, foot)[1]


@njit(cache=True)
def is_leading(y: np.ndarray, system: SpatialSystem, foot: int) -> bool:
    """Whether a foot's contact point is downhill of its partner's."""
    partner = system.foot_partner[foot]
    if partner < 0:
        return True
    return foot_kinematics(y, system, foot)[4] > foot_kinematics(y, system, partner)[4]
