"""The spatial formulation's feet, right-hand side, measurements and formulation record (compiled with numba).

Feet: a disc of radius R (a circle in the body's x'-y' plane, the sagittal plane, around its
local axis, normally z': the 3D form of the planar walker's arc), a sphere (axis = 0), a torus
(a disc with a tube) or an ellipsoid (a quadric). The contact point is the foot's lowest point
with respect to the ground plane y = 0 (:func:`foot_bottom`); penetration, approach velocity and
the 2D slip velocity (x, z) are those of the material point there. The normal response and the scuffing guard are
:mod:`biped_sim.contact.response`, as for the planar formulation. The scalar friction laws of
:mod:`biped_sim.contact.friction` act along the slip direction: F_T = F(|v|) v / |v|, exactly 0
at |v| = 0 (every law is odd in v and vanishes at 0, so this is continuous). LuGre carries a
2-vector bristle state per foot, zdot = v - sigma0 |v| z / g(|v|), written with the scalar law as
zdot_k = rate(|v|, z_k) - |v| + v_k, and F_k = lugre_friction(v_k, z_k, zdot_k, F_N).

The system, the state y = [q (7 nb) | qd (7 nb) | z (2 nf) | W_normal | W_friction] (named offsets:
``FORMULATION.layout_of(system)``) and the constrained equations of motion are
:mod:`biped_sim.multibody.spatial`. Every compiled kernel here is allocation-free; the module ends
with the Python-side measurements and the formulation record :data:`FORMULATION`.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.contact.friction import LUGRE, friction_force, lugre_bristle_rate, lugre_friction
from biped_sim.contact.joint_element import joint_torques, joints_energy
from biped_sim.contact.response import (
    FALL_HIP_HEIGHT,
    FALL_LEG_ANGLE,
    FRICTION_MODEL,
    HIP_TOO_LOW,
    IMPACT_FLOOR,
    LEG_TOO_FAR,
    NORMAL_MODEL,
    STANDING,
    is_loaded,
    normal_response,
    stored_energy,
)
from biped_sim.kernel import inlined, kernel
from biped_sim.multibody.euler_parameters import (
    attitude,
    b_mul,
    b_tmul,
    dot3,
    g_mul,
    g_tmul,
    inertia_mul,
    parameters,
    point_state,
    position,
    rotate,
    rotate_t,
    vec3,
)
from biped_sim.multibody.formulation import Formulation, Measures, impulsive_velocity_change
from biped_sim.multibody.planar import CONTACT_NAMES
from biped_sim.multibody.spatial import (
    SpatialSystem,
    Workspace,
    constrained_accelerations,
    constraint_violation,
    make_workspace,
)

DOWN = (0.0, -1.0, 0.0)  # against the ground's normal


@kernel
def foot_bottom(p: tuple, system: SpatialSystem, i: int) -> tuple[tuple, tuple, tuple]:
    """Foot i's lowest point P against the ground plane y = 0 on a body turned by the parameters p: (c, b, s') with
    c = A c' its centre and b = P - c from there (slope frame, P = r + c + b), and s' its body-frame lever,
    A s' = c + b (A = rotate(p, .): p.p times the rotation, so that the lever holds off the unit sphere too).

    A disc (axis a): R d, d the unit direction in its plane most against the normal; a sphere (axis 0): R below
    the centre; a torus: its disc's point lowered by the tube radius (the tube's section there is a circle in the
    vertical plane through d, lowest straight below its centre); an ellipsoid (quadric Q, body frame): A Q m /
    sqrt(m.Q m) / p.p, m = A^T (0, -1, 0) the ground's inward normal in the body frame.
    """
    sc = vec3(system.foot_center, i, 0)
    centre = rotate(p, sc)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    if system.foot_quadric[i, 0, 0] > 0.0:
        m = rotate_t(p, DOWN)
        qm = inertia_mul(system.foot_quadric, i, m)
        k = 1.0 / (pp * math.sqrt(dot3(m, qm)))
        lever = (k * qm[0], k * qm[1], k * qm[2])
        return centre, rotate(p, lever), (sc[0] + lever[0], sc[1] + lever[1], sc[2] + lever[2])
    radius = system.foot_radius[i]
    axis = vec3(system.foot_axis, i, 0)
    d = DOWN
    if dot3(axis, axis) > 0.0:
        a = rotate(p, axis)
        inv = 1.0 / math.sqrt(dot3(a, a))
        a0, a1, a2 = a[0] * inv, a[1] * inv, a[2] * inv
        norm = math.sqrt(max(1.0 - a1 * a1, 1e-300))
        d = (a1 * a0 / norm, -(1.0 - a1 * a1) / norm, a1 * a2 / norm)
    local_d = rotate_t(p, d)
    scale = radius / (pp * pp)
    s = (sc[0] + scale * local_d[0], sc[1] + scale * local_d[1], sc[2] + scale * local_d[2])
    bottom = (radius * d[0], radius * d[1], radius * d[2])
    tube = system.foot_tube[i]
    if tube > 0.0:
        local_n = rotate_t(p, DOWN)
        k = tube / (pp * pp)
        s = (s[0] + k * local_n[0], s[1] + k * local_n[1], s[2] + k * local_n[2])
        bottom = (bottom[0], bottom[1] - tube, bottom[2])
    return centre, bottom, s


@kernel(reference_counts=False)
def foot_kinematics(
    y: np.ndarray, system: SpatialSystem, i: int
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Foot i against the ground plane y = 0 with normal n = (0, 1, 0).

    Returns (delta, delta_dot, slip_x, slip_z, x_contact, z_contact, s0, s1, s2): penetration
    -P.n of the lowest point P of the foot (:func:`foot_bottom`), approach velocity -v_P.n and 2D slip
    velocity (v_P.x, v_P.z) of the material point at P, P's position in the ground plane, and
    s' = A^-1 (P - r), the body-frame lever of the contact force (its velocity is
    rdot + B(p, s') pdot, so the contact power and the generalized force B^T F agree exactly).
    """
    nb = system.body_mass.shape[0]
    b = system.foot_body[i]
    r = position(y, b)
    p = parameters(y, b)
    centre, bottom, s = foot_bottom(p, system, i)
    px = r[0] + centre[0] + bottom[0]
    py = r[1] + centre[1] + bottom[1]
    pz = r[2] + centre[2] + bottom[2]
    v = position(y, nb + b)
    w = b_mul(p, s, parameters(y, nb + b))
    return -py, -(v[1] + w[1]), v[0] + w[0], v[2] + w[2], px, pz, s[0], s[1], s[2]


@kernel
def foot_contact(y: np.ndarray, system: SpatialSystem, foot: int) -> tuple[float, float, float]:
    """(delta, delta_dot, x_contact) of a foot: what the events and the mode update read (foot_kinematics)."""
    kin = foot_kinematics(y, system, foot)
    return kin[0], kin[1], kin[4]


@kernel(reference_counts=False)
def foot_forces(
    y: np.ndarray, system: SpatialSystem, modes: np.ndarray, i: int
) -> tuple[float, float, float, float, float, float, float, float, float, float, float, float, float, float]:
    """Contact forces on foot i and their dissipation rates.

    Returns (F_N, F_x, F_z, zdot_x, zdot_z, P_normal, P_friction, delta, delta_dot, slip_x,
    slip_z, s0, s1, s2): the normal force along the ground normal, the friction force in the
    ground plane, the LuGre bristle rates, the powers lost in the normal damping
    (:func:`~biped_sim.contact.response.normal_response`) and in friction -F_T.v_t, the kinematics
    and the body-frame lever.
    """
    delta, delta_dot, vx, vz, _, _, s0, s1, s2 = foot_kinematics(y, system, i)
    f_n = f_x = f_z = zdx = zdz = p_normal = p_friction = 0.0  # one return: numba then elides reference counting
    if is_loaded(modes, i, delta):
        npar, floor = system.normal_params, system.limits[IMPACT_FLOOR]
        f_n, p_normal = normal_response(system.switches[NORMAL_MODEL], npar, floor, modes, i, delta, delta_dot)
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


# the right-hand side's kernels count no references and its constraint solve is inlined, as the planar
# formulation's (its module docstring says why: a call passes the whole system and numba counts its arrays)
_constrained_accelerations = inlined(
    constrained_accelerations, calls=frozenset({"constraint_terms", "normalisation", "mass_blocks", "cholesky_solve"})
)


@kernel(reference_counts=False)
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
        pd = parameters(y, nb + b)
        h = inertia_mul(system.body_inertia, b, g_mul(pd, parameters(y, b)))
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
        q = b_tmul(parameters(y, b), (s0, s1, s2), (f_x, f_n, f_z))
        for k in range(4):
            force[7 * b + 3 + k] += q[k]
        ydot[2 * n + 2 * i] = zdx
        ydot[2 * n + 2 * i + 1] = zdz
        w_normal += p_n
        w_friction += p_f
    ydot[2 * n + 2 * nf] = w_normal
    ydot[2 * n + 2 * nf + 1] = w_friction
    joint_torques(y, system.stops, system.elements, modes, nf, force, ydot, 2 * n + 2 * nf + 2)
    _constrained_accelerations(y, system, work, ydot[n : 2 * n])


# ---------------------------------------------------------------- energy and falls


@kernel
def mechanical_energy(y: np.ndarray, system: SpatialSystem, modes: np.ndarray) -> tuple[float, float, float]:
    """(kinetic, potential, elastic) energy; kinetic = m rdot^2/2 + omega'.J' omega'/2, omega' = 2 G pdot."""
    nb = system.body_mass.shape[0]
    kinetic = 0.0
    potential = 0.0
    g = system.gravity
    for b in range(nb):
        m = system.body_mass[b]
        v = position(y, nb + b)
        w = g_mul(parameters(y, b), parameters(y, nb + b))
        w = (2.0 * w[0], 2.0 * w[1], 2.0 * w[2])
        kinetic += 0.5 * m * dot3(v, v) + 0.5 * dot3(w, inertia_mul(system.body_inertia, b, w))
        potential -= m * dot3(g, position(y, b))
    elastic = 0.0
    nf = system.foot_body.shape[0]
    for i in range(nf):
        elastic += stored_energy(system, modes, i, foot_kinematics(y, system, i)[0])
    return kinetic, potential, elastic + joints_energy(y, system.stops, system.elements, modes, nf)


@kernel
def fall(y: np.ndarray, system: SpatialSystem) -> int:
    """HIP_TOO_LOW: the hip (point s_a of primitive 0) below the height limit; LEG_TOO_FAR: a body's legs tilted
    past the limit angle; else STANDING."""
    nb = system.body_mass.shape[0]
    if system.con_type.shape[0] > 0:
        hip = point_state(y, nb, system.con_bodies[0, 0], vec3(system.con_vecs, 0, 0))[0]
        if hip[1] < system.limits[FALL_HIP_HEIGHT]:
            return HIP_TOO_LOW
    for b in range(nb):
        p = parameters(y, b)
        pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
        cos_tilt = rotate(p, (0.0, 1.0, 0.0))[1] / pp
        if math.acos(min(1.0, max(-1.0, cos_tilt))) > system.limits[FALL_LEG_ANGLE]:
            return LEG_TOO_FAR
    return STANDING


@kernel
def audit(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, work: Workspace) -> tuple[float, float]:
    """(mechanical energy [J], ||Phi|| [m]) of a state, for the loops' blow-up checks (the Jacobian is not filled)."""
    kinetic, potential, elastic = mechanical_energy(y, system, modes)
    return kinetic + potential + elastic, constraint_violation(y, system, work.phi_q)[0]


# ---------------------------------------------------------------- post-processing (Python side)


@kernel
def violation(y: np.ndarray, system: SpatialSystem) -> tuple[float, float, float]:
    """:func:`~biped_sim.multibody.spatial.constraint_violation`'s norms (residuals only: no Jacobian is filled)."""
    return constraint_violation(y, system, np.zeros((1, 1)))


def pitch(y: np.ndarray, system: SpatialSystem, body: int) -> tuple[float, float]:
    """A body's sagittal leg angle [rad] and its rate about the lateral axis [rad/s] (see ``attitude``)."""
    angle, _, _, rate = attitude(y, system.body_mass.shape[0], body)
    return angle, rate


def contact_channels(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, foot: int) -> tuple[float, ...]:
    """(penetration, normal force, friction force x, slip velocity x, friction force z, slip velocity z)."""
    f_n, f_x, f_z, _, _, _, _, delta, _, vx, vz, _, _, _ = foot_forces(y, system, modes, foot)
    return delta, f_n, f_x, vx, f_z, vz


def hip_position(y: np.ndarray, system: SpatialSystem) -> tuple[float, ...]:
    """Position of the hip (point s_a of constraint primitive 0) in the slope frame."""
    s_a = (system.con_vecs[0, 0], system.con_vecs[0, 1], system.con_vecs[0, 2])
    return point_state(y, system.body_mass.shape[0], system.con_bodies[0, 0], s_a)[0]


def hip_impulse(y: np.ndarray, system: SpatialSystem, impulse: np.ndarray) -> np.ndarray:
    """The state just after the impulse p = [px, py] or [px, py, pz] [N s] on the hip (point s_a of primitive 0,
    body a), in the slope frame (pz lateral, 0 when not given).

    Positions, friction states and dissipated work are unchanged; the rates jump by the constrained impulsive
    solution (:func:`~biped_sim.multibody.formulation.impulsive_velocity_change`) with the generalized impulse
    (p, B(p_a, s_a)^T p) on body a, the point-force map of the right-hand side. The Jacobian (normalisation rows
    included) and the inverse mass blocks are the right-hand side's: the modified rotational block
    4 G^T J' G + 4 j p p^T gives the same jump, since the normalisation row keeps p.dpdot = 0.
    """
    nb = system.body_mass.shape[0]
    n = 7 * nb
    work = make_workspace(system)
    constrained_accelerations(y, system, work, np.zeros(n))  # fills work.phi_q and work.minv (force zero: unused)
    a = int(system.con_bodies[0, 0])
    force = (float(impulse[0]), float(impulse[1]), float(impulse[2]) if impulse.shape[0] > 2 else 0.0)
    generalized = np.zeros(n)
    generalized[7 * a : 7 * a + 3] = force
    generalized[7 * a + 3 : 7 * a + 7] = b_tmul(parameters(y, a), vec3(system.con_vecs, 0, 0), force)
    minv = np.zeros((n, n))
    for b in range(nb):
        minv[7 * b : 7 * b + 3, 7 * b : 7 * b + 3] = np.eye(3) / system.body_mass[b]
        minv[7 * b + 3 : 7 * b + 7, 7 * b + 3 : 7 * b + 7] = work.minv[b]
    out = np.array(y, dtype=np.float64)
    out[n : 2 * n] += impulsive_velocity_change(minv, work.phi_q, generalized)
    return out


FORMULATION = Formulation(
    name="spatial",
    system_type=SpatialSystem,
    rhs=rhs,
    foot_contact=foot_contact,
    fall=fall,
    audit=audit,
    make_workspace=make_workspace,
    measures=Measures(
        pitch=pitch,
        mechanical_energy=mechanical_energy,
        violation=violation,
        violation_names=("position", "velocity", "normalization"),
        contact=contact_channels,
        contact_names=(*CONTACT_NAMES, "friction_force_lateral", "slip_velocity_lateral"),
        hip=hip_position,
        attitude=lambda y, system, body: attitude(y, system.body_mass.shape[0], body),
        foot_point=lambda y, system, foot: foot_kinematics(y, system, foot)[4:6],
    ),
    coordinates=("x", "y", "z", "e0", "e1", "e2", "e3"),
    rates=("vx", "vy", "vz", "e0dot", "e1dot", "e2dot", "e3dot"),
    bristles=("zx", "zz"),
    hip_impulse=hip_impulse,
)
