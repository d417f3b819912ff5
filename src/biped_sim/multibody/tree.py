"""The minimal-coordinate formulation's equations over a tree of bodies (:mod:`.minimal` has the system, the
star's arrow solve and the formulation record; its module docstring the equations).

The kinematics go down the tree, parents first (:func:`tree_kinematics`: each body's origin, its velocity
and the velocity products of its acceleration, into the workspace table's body rows); a force on a body
enters the generalized forces through the body's Jacobian, J^T F (:func:`add_generalized_force`); the mass
matrix is sum_b m_b J_b^T J_b + J_b e_b e_b^T, each body's terms and its gravity's by the rigid step map's
kernel (:func:`tree_mass_matrix`, :mod:`~biped_sim.multibody.bodies`), solved by Cholesky in
:func:`tree_rhs`. ``system`` is a :class:`~biped_sim.multibody.minimal.MinimalSystem` (not imported here:
that module imports this one). :func:`tree_origins` reads the tree of a planar absolute-coordinate system.

The right-hand side's kernels count no references and the three that take the whole system are inlined in
:func:`tree_rhs`, as the planar formulation's (:mod:`.planar`'s docstring says why): a call passes the system, some
two hundred machine words, and numba counts each of its arrays at entry and exit; that cost grew with every field the
system gained (the joint stops' and elements' records) and made the kneed walker's run 1.65 times 566eddb's.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.contact.joint_element import joint_torques, joints_energy
from biped_sim.contact.registry import by_type
from biped_sim.contact.response import IMPACT_FLOOR, arc_contact, arc_energy, arc_forces, is_loaded
from biped_sim.kernel import inlined, kernel
from biped_sim.multibody.bodies import add_body_terms, body_energy, lever_terms
from biped_sim.multibody.linalg import cholesky_solve
from biped_sim.multibody.planar import PlanarSystem

HIP = 2  # the root's origin (x_o, y_o), the hip, comes first in q


class Star(NamedTuple):
    """A system's ``topology``: every body hinged at the root's origin, no joint stops (the arrow solve). No arrays:
    its type alone selects the compiled code (as the ground's), so a star compiles none of the tree's solve."""


class Tree(NamedTuple):
    """A system's ``topology``: any other tree of bodies (:func:`tree_rhs`)."""


STAR, TREE = Star(), Tree()

# columns of a tree's body rows (tree_kinematics): cos and sin phi_b, the origin o_b, its velocity, the velocity
# products of its acceleration (-sum omega_k^2 of each lever above it), A(phi_b) c_b and the joint A(phi_p) s_b
T_COS, T_SIN, OX, OY, VX, VY, UX, UY, T_ARM_X, T_ARM_Y, JX, JY = range(12)
N_TREE_COLUMNS = 12


@kernel
def body_origin(y: np.ndarray, system: tuple, b: int) -> tuple[float, float, float, float]:
    """(o_x, o_y, v_x, v_y): body b's origin and its velocity, up the tree from b to the root."""
    parent, joint, n = system.body_parent, system.body_joint, HIP + system.body_mass.shape[0]
    ox = oy = vx = vy = 0.0
    j = b
    while parent[j] >= 0:
        p = parent[j]
        c, s = math.cos(y[HIP + p]), math.sin(y[HIP + p])
        jx, jy = c * joint[j, 0] - s * joint[j, 1], s * joint[j, 0] + c * joint[j, 1]
        om = y[n + HIP + p]
        ox += jx
        oy += jy
        vx -= om * jy
        vy += om * jx
        j = p
    return y[0] + ox, y[1] + oy, y[n] + vx, y[n + 1] + vy


@kernel
def foot_motion(y: np.ndarray, system: tuple, i: int) -> tuple[float, float, float, float, float, float, float]:
    """(o_x, o_y, v_x, v_y, omega) of foot i's body (its origin and rates) and its arc's centre (C_x, C_y)."""
    b = system.foot_body[i]
    n = HIP + system.body_mass.shape[0]
    c, s = math.cos(y[HIP + b]), math.sin(y[HIP + b])
    ox, oy, vx, vy = body_origin(y, system, b)
    fx, fy = system.foot_center[i, 0], system.foot_center[i, 1]
    return ox, oy, vx, vy, y[n + HIP + b], ox + c * fx - s * fy, oy + s * fx + c * fy


@kernel
def _star_motion(
    y: np.ndarray, system: tuple, i: int, topology: Star
) -> tuple[float, float, float, float, float, float, float]:
    """:func:`foot_motion` about the hip, as a star's right-hand side takes it (its origin is the hip plus zeros)."""
    _, _, _, _, om, cx, cy = foot_motion(y, system, i)
    n = HIP + system.body_mass.shape[0]
    return y[0], y[1], y[n], y[n + 1], om, cx, cy


@kernel
def _tree_motion(
    y: np.ndarray, system: tuple, i: int, topology: Tree
) -> tuple[float, float, float, float, float, float, float]:
    return foot_motion(y, system, i)


# the motion a foot's contact forces are computed with: about the hip for a star, its body's origin for a tree
contact_motion = by_type("contact_motion", "topology", {Star: _star_motion, Tree: _tree_motion})


@kernel(reference_counts=False)
def tree_kinematics(y: np.ndarray, system: tuple, table: np.ndarray) -> None:
    """Fill the tree's body rows of ``table`` (the T_* columns), parents before children."""
    parent, joint, com = system.body_parent, system.body_joint, system.body_com
    n = HIP + system.body_mass.shape[0]
    for b in range(system.body_mass.shape[0]):
        c, s = math.cos(y[HIP + b]), math.sin(y[HIP + b])
        p = parent[b]
        if p < 0:
            jx = jy = ux = uy = 0.0
            ox, oy, vx, vy = y[0], y[1], y[n], y[n + 1]
        else:
            cp, sp, om = table[p, T_COS], table[p, T_SIN], y[n + HIP + p]
            jx, jy = cp * joint[b, 0] - sp * joint[b, 1], sp * joint[b, 0] + cp * joint[b, 1]
            ox, oy = table[p, OX] + jx, table[p, OY] + jy
            vx, vy = table[p, VX] - om * jy, table[p, VY] + om * jx
            _, _, ux, uy = lever_terms(jx, jy, om, table[p, UX], table[p, UY])  # the bias down the tree
        table[b, T_COS], table[b, T_SIN], table[b, OX], table[b, OY], table[b, VX], table[b, VY] = c, s, ox, oy, vx, vy
        table[b, UX], table[b, UY], table[b, JX], table[b, JY] = ux, uy, jx, jy
        table[b, T_ARM_X] = c * com[b, 0] - s * com[b, 1]
        table[b, T_ARM_Y] = s * com[b, 0] + c * com[b, 1]


@kernel
def add_generalized_force(
    table: np.ndarray, parent: np.ndarray, q: np.ndarray, b: int, fx: float, fy: float, torque: float
) -> None:
    """Add to ``q`` the generalized force of a force (fx, fy) on body b whose moment about b's origin is
    ``torque``: J^T F, the force on the base, its moment in b's column, and in each ancestor p's the moment
    of F about p's origin through the joint below p on the path (table's JX, JY)."""
    q[0] += fx
    q[1] += fy
    q[HIP + b] += torque
    j = b
    while parent[j] >= 0:
        q[HIP + parent[j]] += table[j, JX] * fy - table[j, JY] * fx
        j = parent[j]


@kernel
def body_levers(table: np.ndarray, parent: np.ndarray, b: int, levers: np.ndarray, columns: np.ndarray) -> int:
    """Body b's centre-of-mass Jacobian but the base's columns (the identity, every body's alike): its columns
    HIP + k, b's own angle then each ancestor's (descending), into ``columns`` and their values into ``levers``,
    perp(A(phi_b) c_b) and perp(A(phi_p) s_j) (s_j: the joint of p's child on the path; every other angle's column
    is zero), from the body rows of ``table``; returns their count, b's depth in the tree."""
    count, k, kx, ky = 0, b, table[b, T_ARM_X], table[b, T_ARM_Y]  # the levers, from b up to the root
    while k >= 0:
        columns[count], levers[count, 0], levers[count, 1] = HIP + k, -ky, kx
        kx, ky, k = table[k, JX], table[k, JY], parent[k]
        count += 1
    return count


@kernel(reference_counts=False)
def tree_mass_matrix(
    y: np.ndarray, system: tuple, table: np.ndarray, mass: np.ndarray, q: np.ndarray, levers: np.ndarray,
    columns: np.ndarray, with_forces: bool,
) -> None:  # fmt: skip
    """The lower triangle of M(q) = sum_b m_b J_b^T J_b + J_b e_b e_b^T into ``mass`` (n x n; the Cholesky solve
    reads no other) and, ``with_forces``, each body's gravity and velocity products at its centre of mass,
    J_b^T m_b (g - u_b + omega_b^2 a_b), added to ``q``, from the body rows of ``table``. The base's block is the
    total mass times the identity and its rows m_b times each body's angle columns; the angles' block is each
    body's :func:`~biped_sim.multibody.bodies.add_body_terms` (the rigid step map's) over its path's columns
    (:func:`body_levers`, into ``levers`` and ``columns`` meanwhile): the terms of the whole Jacobian but its zeros,
    the same bits."""
    nb = system.body_mass.shape[0]
    n = HIP + nb
    for i in range(n):
        for k in range(i + 1):
            mass[i, k] = 0.0
    gx, gy = system.gravity[0], system.gravity[1]
    total = 0.0
    for b in range(nb):
        m, om, ax, ay = system.body_mass[b], y[n + HIP + b], table[b, T_ARM_X], table[b, T_ARM_Y]
        _, _, bx, by = lever_terms(ax, ay, om, table[b, UX] - gx, table[b, UY] - gy)  # Jdot qd - g at its centre
        fx, fy = -m * bx, -m * by
        count = body_levers(table, system.body_parent, b, levers, columns)
        add_body_terms(mass, q, levers, columns, count, m, system.body_inertia[b], HIP + b, fx, fy, with_forces)
        if m == 0.0:
            continue
        total += m
        if with_forces:
            q[0] += fx
            q[1] += fy
        for a in range(count):
            mass[columns[a], 0] += m * levers[a, 0]
            mass[columns[a], 1] += m * levers[a, 1]
    mass[0, 0] = mass[1, 1] = total


@kernel(reference_counts=False)
def _tree_foot_forces(y: np.ndarray, system: tuple, modes: np.ndarray, table: np.ndarray, q: np.ndarray,
                      ydot: np.ndarray) -> tuple[float, float]:  # fmt: skip
    """The feet's generalized forces into ``q`` and their bristle rates into ``ydot``; (W_normal, W_friction) rates."""
    nb, nf = system.body_mass.shape[0], system.foot_body.shape[0]
    n = HIP + nb
    w_normal = w_friction = 0.0
    for i in range(nf):
        b = system.foot_body[i]
        c, s, ox, oy = table[b, T_COS], table[b, T_SIN], table[b, OX], table[b, OY]
        fx, fy, radius = system.foot_center[i, 0], system.foot_center[i, 1], system.foot_radius[i]
        cx, cy = ox + c * fx - s * fy, oy + s * fx + c * fy
        motion = (ox, oy, table[b, VX], table[b, VY], y[n + HIP + b])
        arc = arc_contact(motion[0], motion[1], motion[2], motion[3], motion[4], cx, cy, radius, system.ground)
        ydot[2 * n + i] = 0.0
        if not is_loaded(modes, i, arc[0]):
            continue
        f_x, f_y, torque, z_dot, p_n, p_f, _, _ = arc_forces(
            motion, cx, cy, radius, system.ground, arc, system.switches, system.normal_params, system.friction_params,
            system.limits[IMPACT_FLOOR], modes, i, y[2 * n + i],
        )  # fmt: skip
        add_generalized_force(table, system.body_parent, q, b, f_x, f_y, torque)
        ydot[2 * n + i] = z_dot
        w_normal += p_n
        w_friction += p_f
    return w_normal, w_friction


_kinematics = inlined(tree_kinematics)  # the three take the whole system: inlined (module docstring)
_mass_matrix = inlined(tree_mass_matrix)
_foot_forces = inlined(_tree_foot_forces, calls=frozenset({"arc_contact", "arc_forces", "is_loaded",
                                                          "add_generalized_force"}))  # fmt: skip


@kernel(reference_counts=False)
def tree_rhs(
    t: float, y: np.ndarray, system: tuple, modes: np.ndarray, work: tuple, ydot: np.ndarray, topology: Tree
) -> None:
    """Right-hand side of a tree: M(q) qdd = Q by Cholesky, Q the gravity, the velocity products, the feet
    and the joint stops and elements (module docstring)."""
    table = work.table
    nb, nf = system.body_mass.shape[0], system.foot_body.shape[0]
    n = HIP + nb
    _kinematics(y, system, table)
    mass, q, levers = table[nb : nb + n, :n], table[nb : nb + n, n], table[nb : nb + n, n + 1 : n + 3]
    for k in range(n):
        q[k] = 0.0
        ydot[k] = y[n + k]
    _mass_matrix(y, system, table, mass, q, levers, work.columns, True)
    w_normal, w_friction = _foot_forces(y, system, modes, table, q, ydot)
    ydot[2 * n + nf] = w_normal
    ydot[2 * n + nf + 1] = w_friction
    joint_torques(y, system.stops, system.elements, modes, nf, q, ydot, 2 * n + nf + 2)
    cholesky_solve(mass, q, n)
    for k in range(n):
        ydot[n + k] = q[k]


@kernel
def tree_energy(y: np.ndarray, system: tuple, modes: np.ndarray) -> tuple[float, float, float]:
    """:func:`mechanical_energy` of any tree, a star's too: each body's centre of mass from its origin
    (:func:`body_origin`; a star's is the hip)."""
    n = HIP + system.body_mass.shape[0]
    kinetic = potential = 0.0
    for b in range(system.body_mass.shape[0]):
        m, om = system.body_mass[b], y[n + HIP + b]
        c, s = math.cos(y[HIP + b]), math.sin(y[HIP + b])
        ax = c * system.body_com[b, 0] - s * system.body_com[b, 1]
        ay = s * system.body_com[b, 0] + c * system.body_com[b, 1]
        ox, oy, vx, vy = body_origin(y, system, b)
        vx, vy = vx - om * ay, vy + om * ax
        gx, gy = system.gravity[0], system.gravity[1]
        body_kinetic, body_potential = body_energy(m, system.body_inertia[b], vx, vy, om, ox + ax, oy + ay, gx, gy)
        kinetic += body_kinetic
        potential += body_potential
    elastic = 0.0
    for i in range(system.foot_body.shape[0]):
        _, _, _, _, _, cx, cy = foot_motion(y, system, i)
        elastic += arc_energy(system, modes, i, cx, cy, system.foot_radius[i], system.ground)
    return (
        kinetic,
        potential,
        elastic + joints_energy(y, system.stops, system.elements, modes, system.foot_body.shape[0]),
    )


def minimal_angles(index: np.ndarray, nb: int) -> np.ndarray:
    """Indices of bodies' angles and rates in a planar state (angle 3 b + 2, rate 3 nb + 3 b + 2; -1: the ground)
    as in the minimal state (HIP + b, n + HIP + b), columns angle, angle, rate, rate (contact.stop's)."""
    n = HIP + nb
    body = (index % (3 * nb) - 2) // 3
    return np.where(index >= 0, HIP + body + np.array([0, 0, n, n]), -1)


def tree_origins(planar: PlanarSystem) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(parent, origin, joint) of a planar system whose joints form a tree rooted at body 0 (joint j hinges
    parent a = joint_bodies[j, 0] to child b = joint_bodies[j, 1], a < b, one joint per body b > 0): each body's
    parent, its origin in its own centre-of-mass frame (its joint to its parent; the root's: the point of its
    first joint, the hip) and that origin from the parent's, in the parent's frame. ValueError for any other
    topology (a joint to the ground, a loop, a child before its parent)."""
    nb = planar.body_mass.shape[0]
    joints, points = planar.joint_bodies, planar.joint_points
    if sorted(joints[:, 1].tolist()) != list(range(1, nb)) or np.any(joints[:, 0] >= joints[:, 1]):
        raise ValueError("minimal coordinates need a tree of bodies rooted at body 0, parents before children")
    parent = np.full(nb, -1, dtype=np.int64)
    origin, joint = np.zeros((nb, 2)), np.zeros((nb, 2))
    first = np.flatnonzero(joints[:, 0] == 0)
    if first.size:
        origin[0] = points[first[0], :2]
    for j in np.argsort(joints[:, 1], kind="stable"):
        a, b = joints[j]
        parent[b], origin[b] = a, points[j, 2:]
        joint[b] = points[j, :2] - origin[a]
    return parent, origin, joint


def hip_impulse(y: np.ndarray, system: tuple, impulse: np.ndarray) -> np.ndarray:
    """The state just after the impulse p = [px, py] [N s] (slope frame) on the hip: M(q) dqd = (px, py, 0, ...).

    The hip (the root's origin) is the floating base, so the generalized impulse is p on the base coordinates
    alone and there are no constraints to project through; M is the right-hand side's (:func:`tree_mass_matrix`).
    """
    nb = system.body_mass.shape[0]
    n = HIP + nb
    table, mass, generalized = np.zeros((nb, N_TREE_COLUMNS)), np.zeros((n, n)), np.zeros(n)
    tree_kinematics(y, system, table)
    tree_mass_matrix(y, system, table, mass, generalized, np.zeros((nb, 2)), np.zeros(nb, dtype=np.int64), False)
    mass += np.tril(mass, -1).T  # its lower triangle, mirrored
    generalized[:HIP] = impulse[:HIP]
    out = np.array(y, dtype=np.float64)
    out[n : 2 * n] += np.linalg.solve(mass, generalized)
    return out


def _rotate(phi: float, v: np.ndarray) -> np.ndarray:
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def tree_state(y: np.ndarray, planar: PlanarSystem) -> np.ndarray:
    """The minimal-coordinate state of the planar tree state ``y``: the root's origin (the hip), the angles and
    rates, the bristles and the dissipated work (the joints are taken as satisfied)."""
    nb = planar.body_mass.shape[0]
    hip_arm = _rotate(y[2], tree_origins(planar)[1][0])
    phi, omega = y[2 : 3 * nb : 3], y[3 * nb + 2 : 6 * nb : 3]
    hip = y[0:2] + hip_arm
    hip_velocity = y[3 * nb : 3 * nb + 2] + omega[0] * np.array([-hip_arm[1], hip_arm[0]])
    return np.concatenate([hip, phi, hip_velocity, omega, y[6 * nb :]])


@kernel
def tree_foot(y: np.ndarray, system: tuple, i: int, topology: Tree) -> tuple[float, float, float, float, float, float]:
    """:func:`~biped_sim.multibody.minimal.foot_kinematics` of foot i of a tree (about its body's origin)."""
    ox, oy, vx, vy, om, cx, cy = foot_motion(y, system, i)
    return arc_contact(ox, oy, vx, vy, om, cx, cy, system.foot_radius[i], system.ground)


def pitch(y: np.ndarray, system: tuple, body: int) -> tuple[float, float]:
    """A body's angle phi from the slope normal [rad] and its rate [rad/s]."""
    n = HIP + system.body_mass.shape[0]
    return float(y[HIP + body]), float(y[n + HIP + body])


def no_violation(y: np.ndarray, system: tuple) -> tuple[float, float]:
    """||Phi||, ||Phidot||: structurally zero, the coordinates satisfy the hip joints exactly."""
    return 0.0, 0.0
