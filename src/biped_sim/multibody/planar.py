"""Planar multibody dynamics in absolute coordinates (MODEL.md 2), compiled with numba.

Each body i has q_i = (x_i, y_i, phi_i) at its centre of mass and M_i = diag(m_i, m_i, J_i).
Joints are revolute constraints Phi = r_a + A_a s_a - (r_b + A_b s_b) = 0 (body b may be the
ground, index -1, with s_b a fixed point). Forward dynamics solves the augmented system

    [ M      Phi_q^T ] [ qdd    ]   [ Q                                    ]
    [ Phi_q  0       ] [ lambda ] = [ gamma_c - 2 alpha Phidot - beta^2 Phi ]

by its Schur complement (M is diagonal): (Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - rhs,
solved with an in-place Cholesky factorisation, then qdd = M^-1 (Q - Phi_q^T lambda).

The ODE state is y = [q (3 nb) | qd (3 nb) | z (nf, LuGre bristles) | W_normal | W_friction (| W_element | W_stop)]
(named offsets: ``FORMULATION.layout_of(system)``): the dissipated work is integrated with the
motion, so that the energy balance E(t) - E(0) + W(t) = 0 is an independent check of the
integration. The feet are arcs against the system's ``ground`` (the slope line, or a profile:
:mod:`biped_sim.contact.ground`); what the ground does with them (normal force, dissipation, scuffing
guard) is :mod:`biped_sim.contact.response`; a joint stop's torque (:mod:`biped_sim.contact.stop`) and a joint
element's (:mod:`biped_sim.contact.joint_element`) act on the angles of their two bodies.

Every compiled kernel here is allocation-free: buffers live in :class:`Workspace`. Those of the right-hand side
count no references (``kernel(reference_counts=False)``, as the rigid step map's): numba would otherwise count each
of the system's two dozen arrays, a call at entry and one at exit, in every kernel that takes the system at every
evaluation, a cost that grew with each field the system gained (the joint elements', the body falls'). For the same
reason :func:`constrained_accelerations` is inlined in :func:`rhs`: a call passes the whole system, some two hundred
machine words copied on the stack, and that copy made the compliant runs slower than its instruction count says
(``make bench``). The module ends with the Python-side measurements and the formulation record :data:`FORMULATION`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.contact.ground import FLAT_GROUND, Ground, ground_clearance
from biped_sim.contact.joint_element import NO_ELEMENTS, JointElements, joint_torques, joints_energy
from biped_sim.contact.response import (
    FALL_HIP_HEIGHT,
    HIP_TOO_LOW,
    IMPACT_FLOOR,
    NO_BODY_FALLS,
    STANDING,
    arc_contact,
    arc_energy,
    arc_forces,
    body_fall,
)
from biped_sim.contact.stop import NO_STOPS, Stops
from biped_sim.kernel import inlined, kernel
from biped_sim.multibody.bodies import body_energy
from biped_sim.multibody.formulation import COMPLIANT_LIMIT_CYCLE, Formulation, Measures, impulsive_velocity_change
from biped_sim.multibody.linalg import cholesky_solve


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
    ground: Ground = FLAT_GROUND  # contact.ground: FlatGround or ProfileGround (kernels specialise on its type)
    stops: Stops = NO_STOPS  # contact.stop: the joint stops (their modes follow the feet's in the mode table)
    elements: JointElements = NO_ELEMENTS  # contact.joint_element: springs and dampers between bodies' angles
    body_falls: np.ndarray = NO_BODY_FALLS  # contact.response: each body's fall angle and code (none: as legs)


class Workspace(NamedTuple):
    """Preallocated buffers for one right-hand-side evaluation."""

    phi_q: np.ndarray  # (m, n)
    schur: np.ndarray  # (m, m)
    rhs: np.ndarray  # (m,)
    lam: np.ndarray  # (m,)
    force: np.ndarray  # (n,) generalized applied forces Q


def make_workspace(system: PlanarSystem) -> Workspace:
    """Allocate the buffers of ``system`` (once per simulation, not per step)."""
    n = 3 * system.body_mass.shape[0]
    m = 2 * system.joint_bodies.shape[0]
    return Workspace(np.zeros((m, n)), np.zeros((m, m)), np.zeros(m), np.zeros(m), np.zeros(n))


@kernel(reference_counts=False)
def _foot_arc(y: np.ndarray, system: PlanarSystem, i: int) -> tuple[float, float, float, float, float, float, float]:
    """(x, y, vx, vy, omega) of foot i's body (centre of mass) and its arc's centre (C_x, C_y)."""
    nb = system.body_mass.shape[0]
    b = system.foot_body[i]
    x, yb, phi = y[3 * b], y[3 * b + 1], y[3 * b + 2]
    vx, vy, om = y[3 * nb + 3 * b], y[3 * nb + 3 * b + 1], y[3 * nb + 3 * b + 2]
    c, s = math.cos(phi), math.sin(phi)
    sx, sy = system.foot_center[i, 0], system.foot_center[i, 1]
    return x, yb, vx, vy, om, x + c * sx - s * sy, yb + s * sx + c * sy


@kernel(reference_counts=False)
def foot_kinematics(y: np.ndarray, system: PlanarSystem, i: int) -> tuple[float, float, float, float, float, float]:
    """Foot i's arc against the ground (:func:`~biped_sim.contact.response.arc_contact`, about its body's centre
    of mass): (delta, delta_dot, slip, x_contact, dx, dy), (dx, dy) = P - r_body."""
    x, yb, vx, vy, om, cx, cy = _foot_arc(y, system, i)
    return arc_contact(x, yb, vx, vy, om, cx, cy, system.foot_radius[i], system.ground)


@kernel
def foot_contact(y: np.ndarray, system: PlanarSystem, foot: int) -> tuple[float, float, float]:
    """(delta, delta_dot, x_contact) of a foot: what the events and the mode update read (foot_kinematics)."""
    delta, delta_dot, _, x_contact, _, _ = foot_kinematics(y, system, foot)
    return delta, delta_dot, x_contact


@kernel(reference_counts=False)
def foot_forces(
    y: np.ndarray, system: PlanarSystem, modes: np.ndarray, i: int
) -> tuple[float, float, float, float, float, float, float, float, float, float, float]:
    """Contact forces on foot i and their dissipation rates: (F_x, F_y, torque, zdot, P_normal, P_friction) of
    :func:`~biped_sim.contact.response.arc_forces` about the body's centre of mass, then delta, delta_dot, slip
    of :func:`foot_kinematics` and the summed normal and friction forces F_N, F_T.
    """
    x, yb, vx, vy, om, cx, cy = _foot_arc(y, system, i)
    radius = system.foot_radius[i]
    arc = arc_contact(x, yb, vx, vy, om, cx, cy, radius, system.ground)
    f_x, f_y, torque, z_dot, p_normal, p_friction, f_n, f_t = arc_forces(
        (x, yb, vx, vy, om), cx, cy, radius, system.ground, arc, system.switches, system.normal_params,
        system.friction_params, system.limits[IMPACT_FLOOR], modes, i, y[6 * system.body_mass.shape[0] + i],
    )  # fmt: skip
    return f_x, f_y, torque, z_dot, p_normal, p_friction, arc[0], arc[1], arc[2], f_n, f_t


@kernel
def _body_point(y: np.ndarray, b: int, sx: float, sy: float) -> tuple[float, float, float, float]:
    """(A s)_x, (A s)_y and the global point r + A s of body b."""
    c, s = math.cos(y[3 * b + 2]), math.sin(y[3 * b + 2])
    ax = c * sx - s * sy
    ay = s * sx + c * sy
    return ax, ay, y[3 * b] + ax, y[3 * b + 1] + ay


@kernel(reference_counts=False)
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


@kernel(reference_counts=False)
def _inverse_mass(system: PlanarSystem, c: int) -> float:
    body = c // 3
    return 1.0 / system.body_inertia[body] if c % 3 == 2 else 1.0 / system.body_mass[body]


@kernel(reference_counts=False)
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


# inlined in rhs (the module docstring says why); its Cholesky solve stays a call
_constrained_accelerations = inlined(constrained_accelerations, calls=frozenset({"cholesky_solve"}))


@kernel(reference_counts=False)
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
        f_x, f_y, torque, z_dot, p_n, p_f, _, _, _, _, _ = foot_forces(y, system, modes, i)
        b = system.foot_body[i]
        force[3 * b] += f_x
        force[3 * b + 1] += f_y
        force[3 * b + 2] += torque
        ydot[2 * n + i] = z_dot
        w_normal += p_n
        w_friction += p_f
    ydot[2 * n + nf] = w_normal
    ydot[2 * n + nf + 1] = w_friction
    joint_torques(y, system.stops, system.elements, modes, nf, force, ydot, 2 * n + nf + 2)
    _constrained_accelerations(y, system, work, ydot[n : 2 * n])


@kernel(by_symbol=True)  # a measure: per check or sample
def mechanical_energy(y: np.ndarray, system: PlanarSystem, modes: np.ndarray) -> tuple[float, float, float]:
    """(kinetic, potential, elastic) energy; elastic = the springs of the touching feet, the pressed stops and the
    joint elements."""
    nb = system.body_mass.shape[0]
    n = 3 * nb
    kinetic = 0.0
    potential = 0.0
    for b in range(nb):
        m = system.body_mass[b]
        vx, vy, om = y[n + 3 * b], y[n + 3 * b + 1], y[n + 3 * b + 2]
        gx, gy = system.gravity[0], system.gravity[1]
        body_kinetic, body_potential = body_energy(
            m, system.body_inertia[b], vx, vy, om, y[3 * b], y[3 * b + 1], gx, gy
        )
        kinetic += body_kinetic
        potential += body_potential
    elastic = 0.0
    for i in range(system.foot_body.shape[0]):
        _, _, _, _, _, cx, cy = _foot_arc(y, system, i)
        elastic += arc_energy(system, modes, i, cx, cy, system.foot_radius[i], system.ground)
    return (
        kinetic,
        potential,
        elastic + joints_energy(y, system.stops, system.elements, modes, system.foot_body.shape[0]),
    )


@kernel(by_symbol=True)  # a measure: per check or sample
def constraint_violation(y: np.ndarray, system: PlanarSystem) -> tuple[float, float]:
    """Euclidean norms ||Phi|| and ||Phidot|| over all joints."""
    pos = 0.0
    vel = 0.0
    for j in range(system.joint_bodies.shape[0]):
        px, py, vx, vy = constraint_residuals(y, system, j)
        pos += px * px + py * py
        vel += vx * vx + vy * vy
    return math.sqrt(pos), math.sqrt(vel)


@kernel
def fall(y: np.ndarray, system: PlanarSystem) -> int:
    """HIP_TOO_LOW: hip (joint 0) below the height limit over the ground under it; LEG_TOO_FAR (or a body's own code,
    ``body_falls``): a body past its fall angle; else STANDING."""
    if system.joint_bodies.shape[0] > 0:
        jp = system.joint_points[0]
        _, _, hip_x, hip_y = _body_point(y, system.joint_bodies[0, 0], jp[0], jp[1])
        if ground_clearance(hip_x, hip_y, system.ground) < system.limits[FALL_HIP_HEIGHT]:
            return HIP_TOO_LOW
    for b in range(system.body_mass.shape[0]):
        code = body_fall(y[3 * b + 2], b, system.limits, system.body_falls)
        if code != STANDING:
            return code
    return STANDING


@kernel(by_symbol=True)  # a measure: per check or sample
def audit(y: np.ndarray, system: PlanarSystem, modes: np.ndarray, work: Workspace) -> tuple[float, float]:
    """(mechanical energy [J], ||Phi|| [m]) of a state, for the loops' blow-up checks."""
    kinetic, potential, elastic = mechanical_energy(y, system, modes)
    return kinetic + potential + elastic, constraint_violation(y, system)[0]


# ---------------------------------------------------------------- post-processing (Python side)


def pitch(y: np.ndarray, system: PlanarSystem, body: int) -> tuple[float, float]:
    """A body's angle phi from the slope normal [rad] and its rate [rad/s]."""
    nb = system.body_mass.shape[0]
    return float(y[3 * body + 2]), float(y[3 * nb + 3 * body + 2])


def contact_channels(y: np.ndarray, system: PlanarSystem, modes: np.ndarray, foot: int) -> tuple[float, ...]:
    """(penetration, normal force, friction force, slip velocity) of a foot (forces summed over its features)."""
    _, _, _, _, _, _, delta, _, slip, f_n, f_t = foot_forces(y, system, modes, foot)
    return delta, f_n, f_t, slip


def hip_position(y: np.ndarray, system: PlanarSystem) -> tuple[float, ...]:
    """Position of the hip (joint 0's point on its first body) in the slope frame."""
    b = int(system.joint_bodies[0, 0])
    sx, sy = system.joint_points[0, 0], system.joint_points[0, 1]
    c, s = math.cos(y[3 * b + 2]), math.sin(y[3 * b + 2])
    return y[3 * b] + c * sx - s * sy, y[3 * b + 1] + s * sx + c * sy


def hip_impulse(y: np.ndarray, system: PlanarSystem, impulse: np.ndarray) -> np.ndarray:
    """The state just after the impulse p = [px, py] [N s] (slope frame) on the hip, joint 0's point on body a.

    Positions, friction states and dissipated work are unchanged; the rates jump by the constrained
    impulsive solution (:func:`~biped_sim.multibody.formulation.impulsive_velocity_change`) with the
    generalized impulse J_hip^T p = (px, py, (A s_a) x p) on body a, so the joints' velocities still agree
    (Phidot unchanged). Phi_q is the Jacobian the right-hand side builds (one source); M is diagonal.
    """
    n = 3 * system.body_mass.shape[0]
    work = make_workspace(system)
    constrained_accelerations(y, system, work, np.zeros(n))  # fills work.phi_q (work.force is zero: unused)
    a = int(system.joint_bodies[0, 0])
    ax, ay, _, _ = _body_point(y, a, system.joint_points[0, 0], system.joint_points[0, 1])
    px, py = float(impulse[0]), float(impulse[1])
    generalized = np.zeros(n)
    generalized[3 * a : 3 * a + 3] = px, py, ax * py - ay * px
    minv = np.diag([_inverse_mass(system, c) for c in range(n)])
    out = np.array(y, dtype=np.float64)
    out[n : 2 * n] += impulsive_velocity_change(minv, work.phi_q, generalized)
    return out


CONTACT_NAMES = ("penetration", "normal_force", "friction_force", "slip_velocity")

FORMULATION = Formulation(
    name="planar",
    system_type=PlanarSystem,
    rhs=rhs,
    foot_contact=foot_contact,
    fall=fall,
    audit=audit,
    make_workspace=make_workspace,
    measures=Measures(
        pitch=pitch,
        mechanical_energy=mechanical_energy,
        violation=constraint_violation,
        violation_names=("position", "velocity"),
        contact=contact_channels,
        contact_names=CONTACT_NAMES,
        hip=hip_position,
        attitude=None,
    ),
    coordinates=("x", "y", "phi"),
    rates=("vx", "vy", "omega"),
    bristles=("z",),
    capabilities=frozenset({COMPLIANT_LIMIT_CYCLE}),
    hip_impulse=hip_impulse,
)
