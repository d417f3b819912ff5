"""The spatial formulation's right-hand side, energy, falls, measurements and formulation record (compiled with numba).

The feet against the ground (the plane or a profile: their penetration, slip, forces and spring energy) are
:mod:`biped_sim.multibody.spatial_feet`; the normal response and the scuffing guard are
:mod:`biped_sim.contact.response`, as for the planar formulation. The system, the state
y = [q (7 nb) | qd (7 nb) | z (2 nf) | W_normal | W_friction] (named offsets: ``FORMULATION.layout_of(system)``)
and the constrained equations of motion are :mod:`biped_sim.multibody.spatial`. Every compiled kernel here is
allocation-free; the module ends with the Python-side measurements and the formulation record
:data:`FORMULATION`.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.contact.ground import ground_clearance
from biped_sim.contact.joint_element import joint_torques, joints_energy
from biped_sim.contact.response import FALL_HIP_HEIGHT, FALL_LEG_ANGLE, HIP_TOO_LOW, LEG_TOO_FAR, STANDING
from biped_sim.kernel import inlined, kernel
from biped_sim.multibody.euler_parameters import (
    attitude,
    b_tmul,
    dot3,
    g_mul,
    g_tmul,
    inertia_mul,
    parameters,
    point_state,
    position,
    rotate,
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
from biped_sim.multibody.spatial_feet import foot_energy, foot_kinematics, foot_load


@kernel
def foot_contact(y: np.ndarray, system: SpatialSystem, foot: int) -> tuple[float, float, float]:
    """(delta, delta_dot, x_contact) of a foot: what the events and the mode update read (foot_kinematics)."""
    kin = foot_kinematics(y, system, foot)
    return kin[0], kin[1], kin[4]


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
        f_x, f_y, f_z, q0, q1, q2, q3, zdx, zdz, p_n, p_f, _, _, _ = foot_load(y, system, modes, i, system.ground)
        b = system.foot_body[i]
        force[7 * b] += f_x
        force[7 * b + 1] += f_y
        force[7 * b + 2] += f_z
        force[7 * b + 3] += q0
        force[7 * b + 4] += q1
        force[7 * b + 5] += q2
        force[7 * b + 6] += q3
        ydot[2 * n + 2 * i] = zdx
        ydot[2 * n + 2 * i + 1] = zdz
        w_normal += p_n
        w_friction += p_f
    ydot[2 * n + 2 * nf] = w_normal
    ydot[2 * n + 2 * nf + 1] = w_friction
    joint_torques(y, system.stops, system.elements, modes, nf, force, ydot, 2 * n + 2 * nf + 2)
    _constrained_accelerations(y, system, work, ydot[n : 2 * n])


# ---------------------------------------------------------------- energy and falls


@kernel(by_symbol=True)  # a measure: per check or sample
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
        elastic += foot_energy(y, system, modes, i, system.ground)
    return kinetic, potential, elastic + joints_energy(y, system.stops, system.elements, modes, nf)


@kernel
def fall(y: np.ndarray, system: SpatialSystem) -> int:
    """HIP_TOO_LOW: the hip (point s_a of primitive 0) below the height limit; LEG_TOO_FAR: a body's legs tilted
    past the limit angle; else STANDING."""
    nb = system.body_mass.shape[0]
    if system.con_type.shape[0] > 0:
        hip = point_state(y, nb, system.con_bodies[0, 0], vec3(system.con_vecs, 0, 0))[0]
        if ground_clearance(hip[0], hip[1], system.ground) < system.limits[FALL_HIP_HEIGHT]:
            return HIP_TOO_LOW
    for b in range(nb):
        p = parameters(y, b)
        pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
        cos_tilt = rotate(p, (0.0, 1.0, 0.0))[1] / pp
        if math.acos(min(1.0, max(-1.0, cos_tilt))) > system.limits[FALL_LEG_ANGLE]:
            return LEG_TOO_FAR
    return STANDING


@kernel(by_symbol=True)  # a measure: per check or sample
def audit(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, work: Workspace) -> tuple[float, float]:
    """(mechanical energy [J], ||Phi|| [m]) of a state, for the loops' blow-up checks (the Jacobian is not filled)."""
    kinetic, potential, elastic = mechanical_energy(y, system, modes)
    return kinetic + potential + elastic, constraint_violation(y, system, work.phi_q)[0]


# ---------------------------------------------------------------- post-processing (Python side)


@kernel(by_symbol=True)  # a measure: per check or sample
def violation(y: np.ndarray, system: SpatialSystem) -> tuple[float, float, float]:
    """:func:`~biped_sim.multibody.spatial.constraint_violation`'s norms (residuals only: no Jacobian is filled)."""
    return constraint_violation(y, system, np.zeros((1, 1)))


def pitch(y: np.ndarray, system: SpatialSystem, body: int) -> tuple[float, float]:
    """A body's sagittal leg angle [rad] and its rate about the lateral axis [rad/s] (see ``attitude``)."""
    angle, _, _, rate = attitude(y, system.body_mass.shape[0], body)
    return angle, rate


def contact_channels(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, foot: int) -> tuple[float, ...]:
    """(penetration, normal force, friction force x, slip velocity x, friction force z, slip velocity z)."""
    delta, _, slip, slip_lateral = foot_kinematics(y, system, foot)[:4]
    f_n, f_t, f_lateral = foot_load(y, system, modes, foot, system.ground)[11:]
    return delta, f_n, f_t, slip, f_lateral, slip_lateral


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
