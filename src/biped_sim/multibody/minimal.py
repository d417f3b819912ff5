"""Planar walkers in minimal (generalized) coordinates, compiled with numba: any tree of bodies.

The bodies form a tree (``body_parent``, parents before children): body b's frame has its origin o_b at its
joint to its parent, o_b = o_p + A(phi_p) s_b (``body_joint``: s_b in the parent's frame), the root's origin
being the floating base (the hip). The generalized coordinates are that base and every body's absolute
angle, q = (x_o, y_o, phi_0, ..., phi_{nb-1}), so the joints hold by construction. A body's centre of mass
moves as r_b = o_b + A(phi_b) c_b; its Jacobian has the identity on the base, perp(A(phi_b) c_b) in its own
angle's column and perp(A(phi_p) s_j) in the column of each ancestor p (s_j: the joint of p's child on the
path), and M(q) qdd = Q with M = sum_b m_b J_b^T J_b + J_b e_b e_b^T, Q the gravity, contact and joint-stop
forces minus the velocity products (the omega^2 terms of each lever), solved by Cholesky (:func:`rhs`).

A star (every body hinged at the root's origin, all s_b = 0, no joint stops: the compass, the four-legged
walker) has the type ``topology`` STAR, which compiles the arrow-shaped solve below instead. Every body b hangs
from the hip H, its centre of mass at c_b from H and its feet's arc centres at f_i (body frame, any 2-D
vectors). With a_b = A(phi_b) c_b and e_b = d a_b / d phi_b = (-a_by, a_bx), the centre of
mass moves as r_b = r_h + a_b, v_b = v_h + omega_b e_b, and M(q) qdd = Q with the arrow-shaped

    M = [ m I2        m_b e_b ... ]        Q_h = sum_b m_b (g + omega_b^2 a_b) + sum_feet F
        [ m_b e_b^T   D_b         ]        Q_b = m_b e_b . g + sum_{feet of b} (P - r_h) x F

(m the total mass, D_b = J_b + m_b |c_b|^2 the inertia about the hip, F the contact force at the
contact point P). It is solved by the Schur complement on the diagonal leg block: a 2x2 system for
the hip acceleration, then each leg's angular acceleration. The feet, contact laws, events and
energy audit are those of every formulation (:mod:`biped_sim.contact.response`); the state is
y = [q | qd | z (one bristle per foot) | W_normal | W_friction (| W_element | W_stop)] (``FORMULATION.layout_of``).
:func:`tree_system` and :func:`~biped_sim.multibody.tree.tree_state` convert a planar absolute-coordinate tree
(the walker builders' output) into this formulation, so both describe the same walker by construction.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.contact.ground import FLAT_GROUND, FlatGround, Ground, ProfileGround, ground_clearance
from biped_sim.contact.joint_element import NO_ELEMENTS, JointElements
from biped_sim.contact.registry import by_type
from biped_sim.contact.response import (
    FALL_HIP_HEIGHT,
    HIP_TOO_LOW,
    IMPACT_FLOOR,
    NO_BODY_FALLS,
    STANDING,
    arc_contact,
    arc_forces,
    body_fall,
    ground_forces,
    is_loaded,
)
from biped_sim.contact.stop import NO_STOPS, Stops
from biped_sim.kernel import inlined, kernel
from biped_sim.multibody.formulation import Formulation, Measures
from biped_sim.multibody.planar import CONTACT_NAMES, PlanarSystem
from biped_sim.multibody.tree import (
    HIP,
    N_TREE_COLUMNS,
    STAR,
    TREE,
    Star,
    Tree,
    contact_motion,
    hip_impulse,
    minimal_angles,
    no_violation,
    pitch,
    tree_energy,
    tree_foot,
    tree_origins,
    tree_rhs,
)


class MinimalSystem(NamedTuple):
    """Numeric description of a planar tree of bodies in minimal coordinates, as the kernels read it."""

    body_mass: np.ndarray  # (nb,) [kg]
    body_inertia: np.ndarray  # (nb,) about the centre of mass [kg m^2]
    body_com: np.ndarray  # (nb, 2) centre of mass from the body's origin (its joint to its parent), body frame
    body_parent: np.ndarray  # (nb,) int64: the parent body (-1: the root, body 0); parents before children
    body_joint: np.ndarray  # (nb, 2) the body's origin from its parent's, in the parent's frame (root: 0)
    topology: Star | Tree  # STAR: every body hinged at the root's origin, no stops nor elements (arrow solve); TREE
    foot_body: np.ndarray  # (nf,) int64
    foot_center: np.ndarray  # (nf, 2) arc centre from its body's origin, body frame
    foot_radius: np.ndarray  # (nf,)
    foot_partner: np.ndarray  # (nf,) int64: the foot this one must be ahead of to arm (-1: none)
    gravity: np.ndarray  # (2,) in the slope frame
    normal_params: np.ndarray
    friction_params: np.ndarray
    switches: np.ndarray  # (3,) int64: normal model, friction model, scuffing guard
    limits: np.ndarray  # (3,) impact velocity floor, fall hip height, fall leg angle
    ground: Ground = FLAT_GROUND  # contact.ground: FlatGround or ProfileGround (kernels specialise on its type)
    stops: Stops = NO_STOPS  # contact.stop: the joint stops (their modes follow the feet's in the mode table)
    elements: JointElements = NO_ELEMENTS  # contact.joint_element: springs and dampers between bodies' angles
    body_falls: np.ndarray = NO_BODY_FALLS  # contact.response: each body's fall angle and code (none: as legs)

    @property
    def star(self) -> bool:
        """Whether the system is a star (``topology`` STAR): Python's view; compiled code dispatches on the type."""
        return isinstance(self.topology, Star)


# columns of the workspace table's body rows: Q_b, a_b = A(phi_b) c_b (centre of mass from the hip), cos and
# sin phi_b, m_b and D_b = J_b + m_b |a_b|^2 (the inertia about the hip)
TORQUE, ARM_X, ARM_Y, COS, SIN, MASS, HIP_INERTIA = range(7)
# columns of its foot rows: the foot's geometry (foot_arc), its body (an exact small integer) and its bristle
# state z, which the force loop replaces by zdot
DELTA, DELTA_DOT, SLIP, LEVER_X, LEVER_Y, BODY, BRISTLE = range(7)
N_COLUMNS = 7


class Workspace(NamedTuple):
    """Preallocated buffers for one right-hand-side evaluation of a star (one array: each array costs reference
    counts, and each field a word more on every call that passes it)."""

    table: np.ndarray  # (nb + nf, N_COLUMNS), a row per body, then a row per foot; the hip's Q_h are local variables


class TreeWorkspace(NamedTuple):
    """A tree's buffers (:func:`~biped_sim.multibody.tree.tree_rhs`)."""

    table: np.ndarray  # (nb + n, max(N_TREE_COLUMNS, n + 3)), a row per body, then [M | Q | J] (n = len(q))
    columns: np.ndarray  # (nb,) int64: the coordinates of J's columns, the nonzero ones of a body's Jacobian


def make_workspace(system: MinimalSystem) -> Workspace | TreeWorkspace:
    """Allocate the buffers of ``system`` (once per simulation, not per step)."""
    nb = system.body_mass.shape[0]
    if system.star:
        return Workspace(np.zeros((nb + system.foot_body.shape[0], N_COLUMNS)))
    n = HIP + nb
    return TreeWorkspace(np.zeros((nb + n, max(N_TREE_COLUMNS, n + 3))), np.zeros(nb, dtype=np.int64))


# the contact response is written once for every formulation as ordinary kernels; inlined here, the call and the
# reference counts around it go (make bench shows the cost per evaluation); the laws reached through the registry
# tuples are direct calls that LLVM inlines already
_ground_forces = inlined(ground_forces)
_is_loaded = inlined(is_loaded)


@kernel
def foot_arc(
    y: np.ndarray, n: int, b: int, c: float, s: float, fx: float, fy: float, radius: float, ground: Ground
) -> tuple[float, float, float, float, float, float]:
    """A foot of body b (c, s = cos, sin phi_b), arc centre (fx, fy) from the hip (body frame), against
    ``ground`` (:func:`~biped_sim.contact.response.arc_contact` about the hip; n = len(q)):
    (delta, delta_dot, slip, x_contact, dx, dy), (dx, dy) = P - r_h."""
    cx, cy = arc_centre(y, c, s, fx, fy)
    return arc_contact(y[0], y[1], y[n], y[n + 1], y[n + HIP + b], cx, cy, radius, ground)


@kernel
def arc_centre(y: np.ndarray, c: float, s: float, fx: float, fy: float) -> tuple[float, float]:
    """Centre of a foot arc at (fx, fy) from the hip in the frame of a body at angle phi (c, s = cos, sin phi)."""
    return y[0] + c * fx - s * fy, y[1] + s * fx + c * fy


@kernel
def _star_foot(
    y: np.ndarray, system: MinimalSystem, i: int, topology: Star
) -> tuple[float, float, float, float, float, float]:
    centre, b = system.foot_center, system.foot_body[i]
    c, s = math.cos(y[HIP + b]), math.sin(y[HIP + b])
    n = HIP + system.body_mass.shape[0]
    return foot_arc(y, n, b, c, s, centre[i, 0], centre[i, 1], system.foot_radius[i], system.ground)


_foot_of = by_type("foot_kinematics", "topology", {Star: _star_foot, Tree: tree_foot})


@kernel
def foot_kinematics(y: np.ndarray, system: MinimalSystem, i: int) -> tuple[float, float, float, float, float, float]:
    """:func:`foot_arc` of foot i (about the hip for a star, about its body's origin for a tree)."""
    return _foot_of(y, system, i, system.topology)


@kernel
def foot_contact(y: np.ndarray, system: MinimalSystem, foot: int) -> tuple[float, float, float]:
    """(delta, delta_dot, x_contact) of a foot: what the events and the mode update read (foot_kinematics)."""
    delta, delta_dot, _, x_contact, _, _ = foot_kinematics(y, system, foot)
    return delta, delta_dot, x_contact


@kernel
def _flat_foot_forces(
    y: np.ndarray, n: int, nb: int, nf: int, table: np.ndarray, centre: np.ndarray, radius: np.ndarray,
    ground: FlatGround, switches: np.ndarray, npar: np.ndarray, fpar: np.ndarray, floor: float, modes: np.ndarray,
    hip_x: float, hip_y: float,
) -> tuple[float, float, float, float]:  # fmt: skip
    # reads only the table's foot rows (the arc geometry, ahead of the forces): no other array is live here
    w_normal = w_friction = 0.0
    for i in range(nf):
        foot = nb + i
        delta = table[foot, DELTA]
        if not _is_loaded(modes, i, delta):  # ground_forces would return zeros: skip it
            table[foot, BRISTLE] = 0.0
            continue
        f_n, f_t, z_dot, p_n, p_f = _ground_forces(
            switches, npar, fpar, floor, modes, i, delta, table[foot, DELTA_DOT], table[foot, SLIP],
            table[foot, BRISTLE],
        )  # fmt: skip
        hip_x += f_t
        hip_y += f_n
        b = int(table[foot, BODY])
        table[b, TORQUE] += table[foot, LEVER_X] * f_n - table[foot, LEVER_Y] * f_t
        table[foot, BRISTLE] = z_dot
        w_normal += p_n
        w_friction += p_f
    return hip_x, hip_y, w_normal, w_friction


@kernel
def _profile_foot_forces(
    y: np.ndarray, n: int, nb: int, nf: int, table: np.ndarray, centre: np.ndarray, radius: np.ndarray,
    ground: ProfileGround, switches: np.ndarray, npar: np.ndarray, fpar: np.ndarray, floor: float, modes: np.ndarray,
    hip_x: float, hip_y: float,
) -> tuple[float, float, float, float]:  # fmt: skip
    w_normal = w_friction = 0.0
    for i in range(nf):
        foot = nb + i
        b = int(table[foot, BODY])
        cx, cy = arc_centre(y, table[b, COS], table[b, SIN], centre[i, 0], centre[i, 1])
        motion = (y[0], y[1], y[n], y[n + 1], y[n + HIP + b])
        arc = arc_contact(motion[0], motion[1], motion[2], motion[3], motion[4], cx, cy, radius[i], ground)
        if not is_loaded(modes, i, arc[0]):  # arc_forces would return zeros: skip it
            table[foot, BRISTLE] = 0.0
            continue
        f_x, f_y, torque, z_dot, p_n, p_f, _, _ = arc_forces(
            motion, cx, cy, radius[i], ground, arc, switches, npar, fpar, floor, modes, i, table[foot, BRISTLE]
        )
        hip_x += f_x
        hip_y += f_y
        table[b, TORQUE] += torque
        table[foot, BRISTLE] = z_dot
        w_normal += p_n
        w_friction += p_f
    return hip_x, hip_y, w_normal, w_friction


foot_forces = by_type("foot_forces", "ground", {FlatGround: _flat_foot_forces, ProfileGround: _profile_foot_forces})
foot_forces.__doc__ = """The feet's forces in the right-hand side: (Q_h x, Q_h y) with them added, and the powers
(W_normal, W_friction rates); each foot's torque about the hip is added to its body's row of the table and its
bristle rate written in its own row.

On the flat ground from the feet's rows of the workspace table (their arc geometry, read ahead of the
forces: see :func:`rhs`) through the inlined :func:`~biped_sim.contact.response.ground_forces`; on a
profile through :func:`~biped_sim.contact.response.arc_forces`, summed over each foot's contact features.
"""


@kernel
def star_rhs(
    t: float, y: np.ndarray, system: MinimalSystem, modes: np.ndarray, work: Workspace, ydot: np.ndarray, topology: Star
) -> None:
    """Right-hand side of a star (the arrow-shaped solve of the module docstring).

    numba counts references to every array the kernel reads, at entry and exit, and cannot elide the
    counts of an array that is live across the contact forces' code: these were most of this kernel's
    time. So the system's arrays are read first (the bodies, then the feet's geometry) into the one
    workspace table, and from the contact forces on the kernel reads only that table, ``ydot`` and what
    the forces need (the modes and the law parameters).
    """
    mass, inertia, com = system.body_mass, system.body_inertia, system.body_com
    foot_body, centre, radius = system.foot_body, system.foot_center, system.foot_radius
    table = work.table
    nb, nf = mass.shape[0], foot_body.shape[0]
    n = HIP + nb
    gx, gy = system.gravity[0], system.gravity[1]
    hip_x = hip_y = 0.0  # Q_h
    for b in range(nb):
        m, om = mass[b], y[n + HIP + b]
        c, s = math.cos(y[HIP + b]), math.sin(y[HIP + b])
        ax = c * com[b, 0] - s * com[b, 1]
        ay = s * com[b, 0] + c * com[b, 1]
        hip_x += m * (gx + om * om * ax)
        hip_y += m * (gy + om * om * ay)
        table[b, TORQUE], table[b, ARM_X], table[b, ARM_Y] = m * (ax * gy - ay * gx), ax, ay
        table[b, COS], table[b, SIN] = c, s
        table[b, MASS], table[b, HIP_INERTIA] = m, inertia[b] + m * (ax * ax + ay * ay)
    for k in range(n):
        ydot[k] = y[n + k]
    ground = system.ground
    for i in range(nf):
        b, foot = foot_body[i], nb + i
        c, s = table[b, COS], table[b, SIN]
        delta, delta_dot, slip, _, dx, dy = foot_arc(y, n, b, c, s, centre[i, 0], centre[i, 1], radius[i], ground)
        table[foot, DELTA], table[foot, DELTA_DOT], table[foot, SLIP] = delta, delta_dot, slip
        table[foot, LEVER_X], table[foot, LEVER_Y] = dx, dy
        table[foot, BODY], table[foot, BRISTLE] = b, y[2 * n + i]
    switches, npar, fpar = system.switches, system.normal_params, system.friction_params
    hip_x, hip_y, w_normal, w_friction = foot_forces(
        y, n, nb, nf, table, centre, radius, ground, switches, npar, fpar, system.limits[IMPACT_FLOOR], modes,
        hip_x, hip_y,
    )  # fmt: skip
    for i in range(nf):
        ydot[2 * n + i] = table[nb + i, BRISTLE]
    ydot[2 * n + nf] = w_normal
    ydot[2 * n + nf + 1] = w_friction
    # M qdd = Q by the Schur complement on the diagonal leg block: the 2x2 hip block
    # S = m I2 - sum_b m_b^2 e_b e_b^T / D_b against Q_h - sum_b m_b e_b Q_b / D_b, then each leg
    s00 = s01 = s11 = 0.0
    for b in range(nb):
        m, ax, ay = table[b, MASS], table[b, ARM_X], table[b, ARM_Y]
        k = m / table[b, HIP_INERTIA]
        s00 += m - k * m * ay * ay
        s01 += k * m * ax * ay
        s11 += m - k * m * ax * ax
        hip_x += k * ay * table[b, TORQUE]
        hip_y -= k * ax * table[b, TORQUE]
    det = s00 * s11 - s01 * s01
    acc_x = (s11 * hip_x - s01 * hip_y) / det
    acc_y = (s00 * hip_y - s01 * hip_x) / det
    ydot[n] = acc_x
    ydot[n + 1] = acc_y
    for b in range(nb):
        m, ax, ay = table[b, MASS], table[b, ARM_X], table[b, ARM_Y]
        ydot[n + HIP + b] = (table[b, TORQUE] - m * (ax * acc_y - ay * acc_x)) / table[b, HIP_INERTIA]


_rhs_of = by_type("rhs", "topology", {Star: star_rhs, Tree: tree_rhs})  # inlined: the star's is the whole rhs


@kernel(reference_counts=False)
def rhs(
    t: float, y: np.ndarray, system: MinimalSystem, modes: np.ndarray, work: Workspace | TreeWorkspace, ydot: np.ndarray
) -> None:
    """Right-hand side ydot = f(t, y) for the current contact modes (allocation-free): a star's arrow solve
    (:func:`star_rhs`) or a tree's (:func:`~biped_sim.multibody.tree.tree_rhs`), chosen by the topology's type."""
    _rhs_of(t, y, system, modes, work, ydot, system.topology)


@kernel(by_symbol=True)  # a measure: per check or sample
def mechanical_energy(y: np.ndarray, system: MinimalSystem, modes: np.ndarray) -> tuple[float, float, float]:
    """(kinetic, potential, elastic) energy; elastic = the springs of the touching feet and the pressed stops (a
    star's too by the tree's sum: its origins are the hip)."""
    return tree_energy(y, system, modes)


@kernel
def fall(y: np.ndarray, system: MinimalSystem) -> int:
    """HIP_TOO_LOW: hip below the height limit over the ground under it; LEG_TOO_FAR (or a body's own code,
    ``body_falls``): a body rotated past its fall angle; else STANDING."""
    if ground_clearance(y[0], y[1], system.ground) < system.limits[FALL_HIP_HEIGHT]:
        return HIP_TOO_LOW
    for b in range(system.body_mass.shape[0]):
        code = body_fall(y[HIP + b], b, system.limits, system.body_falls)
        if code != STANDING:
            return code
    return STANDING


@kernel(by_symbol=True)  # a measure: per check or sample
def audit(y: np.ndarray, system: MinimalSystem, modes: np.ndarray, work: tuple) -> tuple[float, float]:
    """(mechanical energy [J], 0): the coordinates hold the hip joints exactly, so there is no drift."""
    kinetic, potential, elastic = mechanical_energy(y, system, modes)
    return kinetic + potential + elastic, 0.0


# ---------------------------------------------------------------- conversion and post-processing (Python side)


# the system arrays the minimal formulation takes from the planar one unchanged (copied)
SHARED_WITH_PLANAR = ("body_mass", "body_inertia", "foot_body", "foot_radius", "foot_partner", "gravity",
                      "normal_params", "friction_params", "switches", "limits", "body_falls")  # fmt: skip


def tree_system(planar: PlanarSystem) -> MinimalSystem:
    """The same walker as the planar tree ``planar`` (:func:`tree_origins`) in minimal coordinates; a star
    without joint stops or elements is flagged for the arrow solve. The stops' and the elements' indices move to
    the minimal state's angles."""
    parent, origin, joint = tree_origins(planar)
    stops, elements = planar.stops, planar.elements
    plain = stops.law.shape[0] == 0 and elements.law.shape[0] == 0
    return MinimalSystem(
        **{name: getattr(planar, name).copy() for name in SHARED_WITH_PLANAR},
        body_com=-origin,
        body_parent=parent,
        body_joint=joint,
        topology=STAR if bool(np.all(joint == 0.0)) and plain else TREE,
        foot_center=planar.foot_center - origin[planar.foot_body],
        ground=planar.ground,
        stops=stops._replace(index=minimal_angles(stops.index, planar.body_mass.shape[0])),
        elements=elements._replace(index=minimal_angles(elements.index, planar.body_mass.shape[0])),
    )


def contact_channels(y: np.ndarray, system: MinimalSystem, modes: np.ndarray, foot: int) -> tuple[float, ...]:
    """(penetration, normal force, friction force, slip velocity) of a foot (the right-hand side's equations)."""
    n = HIP + system.body_mass.shape[0]
    ox, oy, vx, vy, om, cx, cy = contact_motion(y, system, foot, system.topology)
    arc = foot_kinematics(y, system, foot)
    _, _, _, _, _, _, f_n, f_t = arc_forces(
        (ox, oy, vx, vy, om), cx, cy, system.foot_radius[foot], system.ground, arc,
        system.switches, system.normal_params, system.friction_params, system.limits[IMPACT_FLOOR], modes, foot,
        y[2 * n + foot],
    )  # fmt: skip
    return arc[0], f_n, f_t, arc[2]


FORMULATION = Formulation(
    name="minimal",
    system_type=MinimalSystem,
    rhs=rhs,
    foot_contact=foot_contact,
    fall=fall,
    audit=audit,
    make_workspace=make_workspace,
    measures=Measures(
        pitch=pitch,
        mechanical_energy=mechanical_energy,
        violation=no_violation,
        violation_names=("position", "velocity"),
        contact=contact_channels,
        contact_names=CONTACT_NAMES,
        hip=lambda y, system: (float(y[0]), float(y[1])),
        attitude=None,
    ),
    coordinates=("phi",),
    rates=("omega",),
    bristles=("z",),
    base_coordinates=("x_hip", "y_hip"),
    base_rates=("vx_hip", "vy_hip"),
    hip_impulse=hip_impulse,
)
