"""Planar multibody dynamics in absolute coordinates (MODEL.md 2), compiled with numba.

Each body i has q_i = (x_i, y_i, phi_i) at its centre of mass and M_i = diag(m_i, m_i, J_i).
Joints are revolute constraints Phi = r_a + A_a s_a - (r_b + A_b s_b) = 0 (body b may be the
ground, index -1, with s_b a fixed point). Forward dynamics solves the augmented system

    [ M      Phi_q^T ] [ qdd    ]   [ Q                                    ]
    [ Phi_q  0       ] [ lambda ] = [ gamma_c - 2 alpha Phidot - beta^2 Phi ]

by its Schur complement (M is diagonal): (Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - rhs,
solved with an in-place Cholesky factorisation, then qdd = M^-1 (Q - Phi_q^T lambda).

The ODE state is y = [q (3 nb) | qd (3 nb) | z (nf, LuGre bristles) | W_normal | W_friction]:
the dissipated work is integrated with the motion, so that the energy balance
E(t) - E(0) + W(t) = 0 is an independent check of the integration.

Everything here is allocation-free: buffers live in :class:`Workspace`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from biped_sim.contact.friction import LUGRE, friction_force, lugre_bristle_rate, lugre_friction
from biped_sim.contact.normal import elastic_energy, elastic_force, normal_force

# columns of the per-foot discrete mode table
ARMED, TOUCHING, IMPACT_SPEED = 0, 1, 2
N_MODE_COLUMNS = 3
# switches
NORMAL_MODEL, FRICTION_MODEL, SCUFFING_GUARD = 0, 1, 2
# limits
IMPACT_FLOOR, FALL_HIP_HEIGHT, FALL_LEG_ANGLE = 0, 1, 2


class PlanarSystem(NamedTuple):
    """Numeric description of a planar walker, as the compiled kernels read it."""

    body_mass: np.ndarray  # (nb,) [kg]
    body_inertia: np.ndarray  # (nb,) about the centre of mass [kg m^2]
    joint_bodies: np.ndarray  # (nj, 2) int64; second entry -1 = ground
    joint_points: np.ndarray  # (nj, 4) s_a (body a frame), s_b (body b frame, or global if ground)
    foot_body: np.ndarray  # (nf,) int64
    foot_center: np.ndarray  # (nf, 2) arc centre in the body frame
    foot_radius: np.ndarray  # (nf,)
    foot_partner: np.ndarray  # (nf,) int64: the foot this one must be ahead of to arm (-1: none)
    gravity: np.ndarray  # (2,) in the slope frame
    baumgarte: np.ndarray  # (2,) alpha, beta
    normal_params: np.ndarray
    friction_params: np.ndarray
    switches: np.ndarray  # (3,) int64: normal model, friction model, scuffing guard
    limits: np.ndarray  # (3,) impact velocity floor, fall hip height, fall leg angle


class Workspace(NamedTuple):
    """Preallocated buffers for one right-hand-side evaluation."""

    phi_q: np.ndarray  # (m, n)
    schur: np.ndarray  # (m, m)
    rhs: np.ndarray  # (m,)
    lam: np.ndarray  # (m,)
    force: np.ndarray  # (n,) generalized applied forces Q
    onset: np.ndarray  # (nf,) int64: set by update_modes when a foot touches down


def make_workspace(system: PlanarSystem) -> Workspace:
    """Allocate the buffers of ``system`` (once per simulation, not per step)."""
    n = 3 * system.body_mass.shape[0]
    m = 2 * system.joint_bodies.shape[0]
    nf = system.foot_body.shape[0]
    return Workspace(
        np.zeros((m, n)), np.zeros((m, m)), np.zeros(m), np.zeros(m), np.zeros(n), np.zeros(nf, dtype=np.int64)
    )


def state_size(system: PlanarSystem) -> int:
    """Length of the ODE state vector."""
    return 6 * system.body_mass.shape[0] + system.foot_body.shape[0] + 2


@njit(cache=True)
def foot_kinematics(y: np.ndarray, system: PlanarSystem, i: int) -> tuple[float, float, float, float, float, float]:
    """Foot arc against the ground line y = 0 with normal (0, 1) (MODEL.md 3).

    Returns (delta, delta_dot, slip, x_contact, dx, dy): penetration R - C_y, approach velocity
    -v_P.n, slip velocity v_P.t of the material point at P = C - R n, the contact point's
    position along the slope, and P - r_body (the lever arm of the contact force).
    """
    nb = system.body_mass.shape[0]
    b = system.foot_body[i]
    x, yb, phi = y[3 * b], y[3 * b + 1], y[3 * b + 2]
    vx, vy, om = y[3 * nb + 3 * b], y[3 * nb + 3 * b + 1], y[3 * nb + 3 * b + 2]
    c, s = math.cos(phi), math.sin(phi)
    sx, sy = system.foot_center[i, 0], system.foot_center[i, 1]
    radius = system.foot_radius[i]
    px = x + c * sx - s * sy
    py = yb + s * sx + c * sy - radius
    dx, dy = px - x, py - yb
    vpx = vx - om * dy
    vpy = vy + om * dx
    return -py, -vpy, vpx, px, dx, dy


@njit(cache=True)
def foot_forces(
    y: np.ndarray, system: PlanarSystem, modes: np.ndarray, i: int
) -> tuple[float, float, float, float, float, float, float, float, float, float]:
    """Contact forces on foot i and their dissipation rates.

    Returns (F_N, F_T, zdot, P_normal, P_friction, delta, delta_dot, slip, dx, dy) with
    P_normal = (F_N - K delta^n) deltadot the power lost in the normal damping and P_friction =
    -F_T v_t the power taken by friction (for LuGre this includes the small, load-dependent
    bristle energy, which is not a potential). The force acts when the foot is armed and penetrates.
    """
    delta, delta_dot, slip, _, dx, dy = foot_kinematics(y, system, i)
    f_n = 0.0
    f_t = 0.0
    z_dot = 0.0
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
        if system.switches[FRICTION_MODEL] == LUGRE:
            z = y[6 * system.body_mass.shape[0] + i]
            z_dot = lugre_bristle_rate(slip, z, fpar)
            f_t = lugre_friction(slip, z, z_dot, f_n, fpar)
            p_friction = -f_t * slip
        else:
            f_t = friction_force(system.switches[FRICTION_MODEL], slip, f_n, fpar)
            p_friction = -f_t * slip
    return f_n, f_t, z_dot, p_normal, p_friction, delta, delta_dot, slip, dx, dy


@njit(cache=True)
def _body_point(y: np.ndarray, b: int, sx: float, sy: float) -> tuple[float, float, float, float]:
    """(A s)_x, (A s)_y and the global point r + A s of body b."""
    c, s = math.cos(y[3 * b + 2]), math.sin(y[3 * b + 2])
    ax = c * sx - s * sy
    ay = s * sx + c * sy
    return ax, ay, y[3 * b] + ax, y[3 * b + 1] + ay


@njit(cache=True)
def constraint_residuals(y: np.ndarray, system: PlanarSystem, j: int) -> tuple[float, float, float, float]:
    """Phi and Phidot of revolute joint j: (Phi_x, Phi_y, Phidot_x, Phidot_y)."""
    nb = system.body_mass.shape[0]
    a, b = system.joint_bodies[j, 0], system.joint_bodies[j, 1]
    jp = system.joint_points[j]
    ax, ay, pax, pay = _body_point(y, a, jp[0], jp[1])
    om_a = y[3 * nb + 3 * a + 2]
    vax = y[3 * nb + 3 * a] - om_a * ay
    vay = y[3 * nb + 3 * a + 1] + om_a * ax
    if b >= 0:
        bx, by, pbx, pby = _body_point(y, b, jp[2], jp[3])
        om_b = y[3 * nb + 3 * b + 2]
        vbx = y[3 * nb + 3 * b] - om_b * by
        vby = y[3 * nb + 3 * b + 1] + om_b * bx
    else:
        pbx, pby, vbx, vby = jp[2], jp[3], 0.0, 0.0
    return pax - pbx, pay - pby, vax - vbx, vay - vby


@njit(cache=True)
def cholesky_solve(a: np.ndarray, b: np.ndarray, m: int) -> None:
    """Solve a x = b in place for a symmetric positive definite m x m matrix (x overwrites b)."""
    for j in range(m):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        d = math.sqrt(d)
        a[j, j] = d
        for i in range(j + 1, m):
            v = a[i, j]
            for k in range(j):
                v -= a[i, k] * a[j, k]
            a[i, j] = v / d
    for i in range(m):
        v = b[i]
        for k in range(i):
            v -= a[i, k] * b[k]
        b[i] = v / a[i, i]
    for i in range(m - 1, -1, -1):
        v = b[i]
        for k in range(i + 1, m):
            v -= a[k, i] * b[k]
        b[i] = v / a[i, i]


@njit(cache=True)
def _inverse_mass(system: PlanarSystem, c: int) -> float:
    body = c // 3
    return 1.0 / system.body_inertia[body] if c % 3 == 2 else 1.0 / system.body_mass[body]


@njit(cache=True)
def constrained_accelerations(y: np.ndarray, system: PlanarSystem, work: Workspace, qdd: np.ndarray) -> None:
    """Accelerations from the augmented system with Baumgarte stabilisation (forces in work.force)."""
    nb = system.body_mass.shape[0]
    n = 3 * nb
    nj = system.joint_bodies.shape[0]
    m = 2 * nj
    alpha, beta = system.baumgarte[0], system.baumgarte[1]
    phi_q, rhs = work.phi_q, work.rhs
    phi_q[:, :] = 0.0
    for j in range(nj):
        a, b = system.joint_bodies[j, 0], system.joint_bodies[j, 1]
        jp = system.joint_points[j]
        ax, ay, _, _ = _body_point(y, a, jp[0], jp[1])
        om_a = y[n + 3 * a + 2]
        r0, r1 = 2 * j, 2 * j + 1
        phi_q[r0, 3 * a] = 1.0
        phi_q[r1, 3 * a + 1] = 1.0
        phi_q[r0, 3 * a + 2] = -ay
        phi_q[r1, 3 * a + 2] = ax
        gx = om_a * om_a * ax
        gy = om_a * om_a * ay
        if b >= 0:
            bx, by, _, _ = _body_point(y, b, jp[2], jp[3])
            om_b = y[n + 3 * b + 2]
            phi_q[r0, 3 * b] = -1.0
            phi_q[r1, 3 * b + 1] = -1.0
            phi_q[r0, 3 * b + 2] = by
            phi_q[r1, 3 * b + 2] = -bx
            gx -= om_b * om_b * bx
            gy -= om_b * om_b * by
        px, py, vx, vy = constraint_residuals(y, system, j)
        rhs[r0] = gx - 2.0 * alpha * vx - beta * beta * px
        rhs[r1] = gy - 2.0 * alpha * vy - beta * beta * py
    force, schur, lam = work.force, work.schur, work.lam
    for k in range(m):
        v = -rhs[k]
        for c in range(n):
            v += phi_q[k, c] * _inverse_mass(system, c) * force[c]
        lam[k] = v
        for l in range(k + 1):
            s = 0.0
            for c in range(n):
                s += phi_q[k, c] * phi_q[l, c] * _inverse_mass(system, c)
            schur[k, l] = s
            schur[l, k] = s
    cholesky_solve(schur, lam, m)
    for c in range(n):
        v = force[c]
        for k in range(m):
            v -= phi_q[k, c] * lam[k]
        qdd[c] = v * _inverse_mass(system, c)


@njit(cache=True)
def rhs(t: float, y: np.ndarray, system: PlanarSystem, modes: np.ndarray, work: Workspace, ydot: np.ndarray) -> None:
    """Right-hand side ydot = f(t, y) for the current contact modes (allocation-free)."""
    nb = system.body_mass.shape[0]
    n = 3 * nb
    nf = system.foot_body.shape[0]
    force = work.force
    for b in range(nb):
        force[3 * b] = system.body_mass[b] * system.gravity[0]
        force[3 * b + 1] = system.body_mass[b] * system.gravity[1]
        force[3 * b + 2] = 0.0
    for c in range(n):
        ydot[c] = y[n + c]
    w_normal = 0.0
    w_friction = 0.0
    for i in range(nf):
        f_n, f_t, z_dot, p_n, p_f, _, _, _, dx, dy = foot_forces(y, system, modes, i)
        b = system.foot_body[i]
        force[3 * b] += f_t
        force[3 * b + 1] += f_n
        force[3 * b + 2] += dx * f_n - dy * f_t
        ydot[2 * n + i] = z_dot
        w_normal += p_n
        w_friction += p_f
    ydot[2 * n + nf] = w_normal
    ydot[2 * n + nf + 1] = w_friction
    constrained_accelerations(y, system, work, ydot[n : 2 * n])


@njit(cache=True)
def mechanical_energy(y: np.ndarray, system: PlanarSystem, modes: np.ndarray) -> tuple[float, float, float]:
    """(kinetic, potential, elastic) energy; elastic = the springs of the touching feet."""
    nb = system.body_mass.shape[0]
    n = 3 * nb
    kinetic = 0.0
    potential = 0.0
    for b in range(nb):
        m = system.body_mass[b]
        vx, vy, om = y[n + 3 * b], y[n + 3 * b + 1], y[n + 3 * b + 2]
        kinetic += 0.5 * m * (vx * vx + vy * vy) + 0.5 * system.body_inertia[b] * om * om
        potential -= m * (system.gravity[0] * y[3 * b] + system.gravity[1] * y[3 * b + 1])
    elastic = 0.0
    for i in range(system.foot_body.shape[0]):
        delta = foot_kinematics(y, system, i)[0]
        if modes[i, ARMED] > 0.5 and delta > 0.0:
            elastic += elastic_energy(delta, system.normal_params)
    return kinetic, potential, elastic


@njit(cache=True)
def constraint_violation(y: np.ndarray, system: PlanarSystem) -> tuple[float, float]:
    """Euclidean norms ||Phi|| and ||Phidot|| over all joints."""
    pos = 0.0
    vel = 0.0
    for j in range(system.joint_bodies.shape[0]):
        px, py, vx, vy = constraint_residuals(y, system, j)
        pos += px * px + py * py
        vel += vx * vx + vy * vy
    return math.sqrt(pos), math.sqrt(vel)


@njit(cache=True)
def event_functions(y: np.ndarray, system: PlanarSystem, g: np.ndarray) -> None:
    """Continuous functions whose zeros are the discrete events: per foot, delta and (x_foot - x_partner)."""
    nf = system.foot_body.shape[0]
    for i in range(nf):
        delta, _, _, x_i, _, _ = foot_kinematics(y, system, i)
        g[2 * i] = delta
        partner = system.foot_partner[i]
        g[2 * i + 1] = x_i - foot_kinematics(y, system, partner)[3] if partner >= 0 else 1.0


@njit(cache=True)
def update_modes(y: np.ndarray, system: PlanarSystem, modes: np.ndarray, work: Workspace) -> bool:
    """Apply the scuffing guard and contact onset/separation bookkeeping at an event (MODEL.md 3).

    A foot is armed once it is ahead of its partner and above the ground, and disarmed when it is
    in the air behind its partner (with the guard off every foot is always armed). A touchdown
    remembers the approach velocity deltadot^-; LuGre bristles start relaxed at each touchdown.
    Sets work.onset[i] for touchdowns.
    Returns True when any mode changed (the right-hand side then changes too).
    """
    nb = system.body_mass.shape[0]
    nf = system.foot_body.shape[0]
    changed = False
    lugre = system.switches[FRICTION_MODEL] == LUGRE
    for i in range(nf):
        work.onset[i] = 0
        delta, delta_dot, _, x_i, _, _ = foot_kinematics(y, system, i)
        partner = system.foot_partner[i]
        ahead = x_i - foot_kinematics(y, system, partner)[3] if partner >= 0 else 1.0
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
            work.onset[i] = 1
        if touching != was_touching or new_armed != armed:
            changed = True
            if lugre and touching and not was_touching:
                y[6 * nb + i] = 0.0
        modes[i, ARMED] = 1.0 if new_armed else 0.0
        modes[i, TOUCHING] = 1.0 if touching else 0.0
    return changed


@njit(cache=True)
def has_fallen(y: np.ndarray, system: PlanarSystem) -> bool:
    """Fall: hip (joint 0) below the height limit, or any body rotated past the leg-angle limit."""
    if system.joint_bodies.shape[0] > 0:
        jp = system.joint_points[0]
        _, _, _, hip_y = _body_point(y, system.joint_bodies[0, 0], jp[0], jp[1])
        if hip_y < system.limits[FALL_HIP_HEIGHT]:
            return True
    for b in range(system.body_mass.shape[0]):
        if abs(y[3 * b + 2]) > system.limits[FALL_LEG_ANGLE]:
            return True
    return False
