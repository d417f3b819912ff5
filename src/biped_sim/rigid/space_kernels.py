"""The compiled stance-phase flow of the rigid walker in space: the equations of
:mod:`biped_sim.rigid.space_dynamics` (Kane's, generalized speeds = the stance leg's angular velocity and the
hinge rate) over a flat parameter vector, for the integrator's many calls. The plain-numpy
:func:`~biped_sim.rigid.space_dynamics.flow` is their reference (tests compare them to rounding).

Parameter vector (:func:`space_params`): gravity (3, slope frame), the number of parts, then per part its frame
(0 stance leg, 1 swing leg, 2 swing shank, 3 torso), mass, centre of mass (3) and inertia (9, row-major; the walker
frame, hinge at zero), then per foot (stance, swing) its shape code, radius, centre (3), unit normal (3), tube radius
and an ellipsoid's quadric (9, row-major), then the swing knee's: whether the walker has knees (1.0), whether the
swing knee is free (1.0; the step map sets it), its flexion's sign and its point (3); then the torso's: its angle's
index in the state (0: no torso), its elements' count and per element its law's number and parameter vector
(:func:`~biped_sim.contact.joint_element.element_parameters`). The speeds are the stance leg's angular velocity, the
hinge rate, the torso's rate and the swing knee's (the last, so that a locked knee leaves the leading block).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from biped_sim.config.space_description import MAX_TORSO_ELEMENTS
from biped_sim.contact.joint_element import N_ELEMENT_PARAMS, element_energy, element_torque
from biped_sim.kernel import kernel
from biped_sim.multibody.linalg import cholesky_solve
from biped_sim.rigid.space_model import ELLIPSOID, KNEE_ANGLE, KNEE_RATE, RING, SPHERE, TORSO_FRAME, TORUS, SpaceModel

MAX_PARTS = 6  # two legs of a thigh and a shank each, a hip mass, a torso
PART_SIZE = 14
FOOT_SIZE = 18
ELEMENT_SIZE = 1 + N_ELEMENT_PARAMS
PARTS = 4
FEET = PARTS + MAX_PARTS * PART_SIZE
KNEE = FEET + 2 * FOOT_SIZE
HAS_KNEES, KNEE_FREE, KNEE_FLEXION, KNEE_POINT = KNEE, KNEE + 1, KNEE + 2, KNEE + 3
TORSO = KNEE + 6
TORSO_AT, N_ELEMENTS, ELEMENTS = TORSO, TORSO + 1, TORSO + 2
N_PARAMS = ELEMENTS + MAX_TORSO_ELEMENTS * ELEMENT_SIZE


def space_params(model: SpaceModel) -> np.ndarray:
    """The model as the kernels' parameter vector."""
    p = np.zeros(N_PARAMS)
    p[:3] = model.gravity_vector
    p[3] = len(model.parts)
    for k, part in enumerate(model.parts):
        o = PARTS + k * PART_SIZE
        p[o : o + PART_SIZE] = [part.frame, part.mass, *part.com, *part.inertia.ravel()]
    for k, foot in enumerate(model.feet):
        o = FEET + k * FOOT_SIZE
        p[o : o + FOOT_SIZE] = [foot.shape, foot.radius, *foot.centre, *foot.normal, foot.tube, *foot.quadric.ravel()]
    if model.knee:
        p[HAS_KNEES], p[KNEE_FLEXION] = 1.0, model.knee.flexion
        p[KNEE_POINT : KNEE_POINT + 3] = model.knee.point
    if model.torso:
        p[TORSO_AT], p[N_ELEMENTS] = model.torso_angle, len(model.torso.laws)
        for k, (law, values) in enumerate(zip(model.torso.laws, model.torso.params, strict=True)):
            o = ELEMENTS + k * ELEMENT_SIZE
            p[o], p[o + 1 : o + ELEMENT_SIZE] = law, values
    return p


@kernel
def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@kernel
def dot(a: np.ndarray, b: np.ndarray) -> float:
    """a . b for 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel
def mat_vec(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    """a v for a 3 x 3 matrix (a loop: numba's ``@`` calls BLAS, whose call costs more than the product)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = a[i, 0] * v[0] + a[i, 1] * v[1] + a[i, 2] * v[2]
    return out


@kernel
def mat_mat(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a b for a 3 x 3 matrix a and a 3 x n matrix b (a loop, as :func:`mat_vec`)."""
    out = np.empty((3, b.shape[1]))
    for i in range(3):
        for j in range(b.shape[1]):
            out[i, j] = a[i, 0] * b[0, j] + a[i, 1] * b[1, j] + a[i, 2] * b[2, j]
    return out


@kernel
def rotations(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The stance leg's rotation Rz(psi) Rx(phi) Ry(theta) and the swing leg's (times Ry(beta))."""
    cz, sz, cx, sx = math.cos(x[0]), math.sin(x[0]), math.cos(x[1]), math.sin(x[1])
    cy, sy, cb, sb = math.cos(x[2]), math.sin(x[2]), math.cos(x[3]), math.sin(x[3])
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rb = np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    stance = mat_mat(mat_mat(rz, rx), ry)
    return stance, mat_mat(stance, rb)


@kernel
def attitude_rates(x: np.ndarray) -> np.ndarray:
    """(psi', phi', theta') from omega = E (psi', phi', theta'), E's columns z, Rz x and Rz Rx y
    (:func:`~biped_sim.rigid.space_model.rate_matrix`) solved in closed form (|phi| < pi / 2)."""
    cz, sz, cx, sx = math.cos(x[0]), math.sin(x[0]), math.cos(x[1]), math.sin(x[1])
    theta_rate = (x[5] * cz - x[4] * sz) / cx
    return np.array([x[6] - theta_rate * sx, x[4] * cz + x[5] * sz, theta_rate])


@kernel(literal_arguments=False)
def bottom(p: np.ndarray, foot: int, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A foot's lowest point from its frame's origin and the unit vector d from its centre toward it (slope frame;
    a torus's: its ring's, lowered by the tube radius). Compiled once for both feet (callers pass 0 and 1)."""
    o = FEET + foot * FOOT_SIZE
    centre = mat_vec(rotation, p[o + 2 : o + 5])
    d = np.zeros(3)
    if p[o] == ELLIPSOID:  # d: the whole offset -Q z / sqrt(z' Q z)
        q = ellipsoid_quadric(p, o, rotation)
        d = -q[:, 2] / math.sqrt(q[2, 2])
        return centre + d, d
    if p[o] == SPHERE:
        d[2] = -1.0
    elif p[o] == RING or p[o] == TORUS:
        n = mat_vec(rotation, p[o + 5 : o + 8])
        w = -n[2] * n
        w[2] += 1.0
        d = -w / math.sqrt(dot(w, w))
    lowest = centre + p[o + 1] * d
    if p[o] == TORUS:
        lowest[2] -= p[o + 8]
    return lowest, d


@njit(cache=True, inline="always")  # inlined in its two callers: a kernel of its own compiled three times
def ellipsoid_quadric(p: np.ndarray, o: int, rotation: np.ndarray) -> np.ndarray:
    """The ellipsoid foot at parameter offset ``o``: its quadric turned into the slope frame, R Q R^T."""
    q = np.ascontiguousarray(p[o + 9 : o + 18]).reshape((3, 3))
    return mat_mat(mat_mat(rotation, q), rotation.T)


@kernel
def ellipsoid_offset_rate(p: np.ndarray, o: int, rotation: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The rate of an ellipsoid's offset -Q z / sqrt(z' Q z) to its bottom as it turns at ``omega``
    (Q' = [omega]x Q - Q [omega]x)."""
    q = ellipsoid_quadric(p, o, rotation)
    spin = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]], [-omega[1], omega[0], 0.0]])
    q_dot = mat_mat(spin, q) - mat_mat(q, spin)
    s = math.sqrt(q[2, 2])
    return -q_dot[:, 2] / s + q[:, 2] * q_dot[2, 2] / (2.0 * s**3)


@kernel
def contact_rate(p: np.ndarray, rotation: np.ndarray, d: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The stance contact point's velocity over the ground (the material point's is zero)."""
    o = FEET
    if p[o] == ELLIPSOID:
        return cross(omega, -d) + ellipsoid_offset_rate(p, o, rotation, omega)
    radius = p[o + 1]
    arm = -radius * d
    if p[o] == TORUS:  # the centre sits at tube z - radius d from the contact point
        arm[2] += p[o + 8]
    rate = cross(omega, arm)
    if p[o] == RING or p[o] == TORUS:
        n = mat_vec(rotation, p[o + 5 : o + 8])
        n_dot = cross(omega, n)
        w = -n[2] * n
        w[2] += 1.0
        norm = math.sqrt(dot(w, w))
        w_dot = -n_dot[2] * n - n[2] * n_dot
        unit = w / norm
        rate -= radius * (w_dot - unit * dot(unit, w_dot)) / norm
    return rate


@kernel
def knee_frame(p: np.ndarray, x: np.ndarray, swing: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The swing shank's rotation (the swing leg's turned by the knee angle about y) and its frame's shift from
    the hinge's midpoint, R_swing k - R_shank k for the knee's point k (so that the shank turns about the knee);
    the swing leg's and zero without knees."""
    if p[HAS_KNEES] != 1.0:
        return swing, np.zeros(3)
    shank = turned_y(swing, x[KNEE_ANGLE])
    knee = p[KNEE_POINT : KNEE_POINT + 3].copy()
    return shank, mat_vec(swing, knee) - mat_vec(shank, knee)


@kernel
def torso_elements(p: np.ndarray, x: np.ndarray) -> tuple[float, float, float]:
    """(generalized force on the torso's rate, on the hinge rate, the power dissipated) of the torso's elements,
    each acting against both legs: its law at the torso's angle relative to each leg in the planar sense (minus
    the angle about y: t from the stance leg, t - beta from the swing leg), the torque tau on the torso and -tau on
    the leg; a couple's power tau theta' makes it -tau on the torso's rate and +tau on the hinge rate against the
    swing leg."""
    at = int(p[TORSO_AT])
    on_torso, on_hinge, power = 0.0, 0.0, 0.0
    for k in range(int(p[N_ELEMENTS])):
        o = ELEMENTS + k * ELEMENT_SIZE
        law, values = int(p[o]), p[o + 1 : o + ELEMENT_SIZE]
        tau, dissipated = element_torque(law, -x[at], -x[at + 1], values)
        on_torso, power = on_torso - tau, power + dissipated
        tau, dissipated = element_torque(law, x[3] - x[at], x[7] - x[at + 1], values)
        on_torso, on_hinge, power = on_torso - tau, on_hinge + tau, power + dissipated
    return on_torso, on_hinge, power


@kernel
def torso_elements_energy(p: np.ndarray, x: np.ndarray) -> float:
    """The energy the torso's elements store (their springs')."""
    at, stored = int(p[TORSO_AT]), 0.0
    for k in range(int(p[N_ELEMENTS])):
        o = ELEMENTS + k * ELEMENT_SIZE
        law, values = int(p[o]), p[o + 1 : o + ELEMENT_SIZE]
        stored += element_energy(law, -x[at], values) + element_energy(law, x[3] - x[at], values)
    return stored


@kernel
def _add_part(
    p: np.ndarray, o: int, u: np.ndarray, turn: np.ndarray, at: np.ndarray, axis: np.ndarray, joints: np.ndarray,
    p_dot: np.ndarray, mass: np.ndarray, force: np.ndarray,
) -> None:  # fmt: skip
    """The part at parameter offset ``o`` (turned by ``turn``, its frame's origin ``at``) added to Kane's M
    (m A^T A + B^T I B) and F (A^T m (g - b) - B^T (I e + w x I w)), in place, over the speeds ``u``. ``joints``
    rows: the hinge's midpoint (the torso's joint too) and the knee's point, then their velocities, then omega x axis
    (every axis turns with the stance leg); the part's frame (p[o]) says which joints turn it (all about ``axis``):
    the swing leg the hinge, its shank the knee too, the torso its own joint at the midpoint (:func:`_joint_count`,
    :func:`_slot`)."""
    omega, m, n, frame = u[:3], p[o + 1], u.shape[0], int(p[o])
    count = _joint_count(frame)
    r = at + mat_vec(turn, p[o + 2 : o + 5])
    inertia = mat_mat(mat_mat(turn, np.ascontiguousarray(p[o + 5 : o + 14]).reshape((3, 3))), turn.T)
    a_matrix = np.zeros((3, n))
    b_matrix = np.zeros((3, n))
    for i in range(3):  # omega x r = -[r]x omega
        a_matrix[i, (i + 1) % 3] = r[(i + 2) % 3]
        a_matrix[i, (i + 2) % 3] = -r[(i + 1) % 3]
        b_matrix[i, i] = 1.0
    for j in range(count):  # axis x (r - joint_j) on joint j's speed
        dx, dy, dz = r[0] - joints[j, 0], r[1] - joints[j, 1], r[2] - joints[j, 2]
        k = _slot(j, n, frame)
        a_matrix[0, k] = axis[1] * dz - axis[2] * dy
        a_matrix[1, k] = axis[2] * dx - axis[0] * dz
        a_matrix[2, k] = axis[0] * dy - axis[1] * dx
        for i in range(3):
            b_matrix[i, k] = axis[i]
    v, w = np.zeros(3), np.zeros(3)
    for i in range(3):
        for j in range(n):
            v[i] += a_matrix[i, j] * u[j]
            w[i] += b_matrix[i, j] * u[j]
    b, turning, spin = cross(omega, v - p_dot), 0.0, joints[4]
    for j in range(count):  # d/dt of rate_j axis x (r - joint_j): spin x (r - joint_j) + axis x (v - v_joint_j)
        rate = u[_slot(j, n, frame)]
        dx, dy, dz = r[0] - joints[j, 0], r[1] - joints[j, 1], r[2] - joints[j, 2]
        vx, vy, vz = v[0] - joints[2 + j, 0], v[1] - joints[2 + j, 1], v[2] - joints[2 + j, 2]
        b[0] += rate * (spin[1] * dz - spin[2] * dy + axis[1] * vz - axis[2] * vy)
        b[1] += rate * (spin[2] * dx - spin[0] * dz + axis[2] * vx - axis[0] * vz)
        b[2] += rate * (spin[0] * dy - spin[1] * dx + axis[0] * vy - axis[1] * vx)
        turning += rate
    linear = m * (p[:3] - b)
    torque = turning * mat_vec(inertia, spin) + cross(w, mat_vec(inertia, w))  # e = (sum of rates) spin
    inertia_b = mat_mat(inertia, b_matrix)
    for i in range(n):
        for j in range(n):
            for k in range(3):
                mass[i, j] += m * a_matrix[k, i] * a_matrix[k, j] + b_matrix[k, i] * inertia_b[k, j]
        for k in range(3):
            force[i] += a_matrix[k, i] * linear[k] - b_matrix[k, i] * torque[k]


@njit(cache=True, inline="always")
def _joint_count(frame: int) -> int:
    """How many of :func:`_add_part`'s joints (the first rows) turn a part of ``frame``: the torso its own joint,
    at the hinge's midpoint (row 0)."""
    return 1 if frame == TORSO_FRAME else frame


@njit(cache=True, inline="always")
def _slot(joint: int, n: int, frame: int) -> int:
    """The speed among ``n`` of joint ``joint`` (row 0: the hinge, or the torso's joint for the torso; row 1: the
    knee) turning a part of ``frame``: the hinge's 3, the torso's 4, the knee's the last."""
    if joint == 1:
        return n - 1
    return 4 if frame == TORSO_FRAME else 3


@njit(cache=True, inline="always")  # inlined: a kernel of its own would be one more compile
def turned_y(rotation: np.ndarray, angle: float) -> np.ndarray:
    """``rotation`` turned by ``angle`` about its y axis: rotation Ry(angle)."""
    c, s = math.cos(angle), math.sin(angle)
    return mat_mat(rotation, np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]))


@kernel
def space_flow(p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """dx/dt of the stance phase: Kane's M u' = F (a Cholesky solve over the free speeds: M is symmetric positive
    definite) and the attitude's and contact point's rates; with knees, the swing knee free while p[KNEE_FREE] is
    1; with a torso, its elements' forces and their dissipated power (the work's rate)."""
    stance, swing = rotations(x)
    foot, d = bottom(p, 0, stance)
    axis = stance[:, 1].copy()
    p_dot = contact_rate(p, stance, d, x[4:7].copy())
    shank, shift = knee_frame(p, x, swing)
    knees, at = p[HAS_KNEES] == 1.0, int(p[TORSO_AT])
    n = 4 + (1 if at else 0) + (1 if knees else 0)
    u = np.empty(n)
    for i in range(4):
        u[i] = x[4 + i]
    joints = np.empty((5, 3))  # _add_part's: the joints' points, their velocities, omega x axis
    for i in range(3):
        joints[0, i], joints[1, i] = -foot[i], -foot[i]
    if knees:
        u[n - 1] = x[KNEE_RATE]
        joints[1] += mat_vec(swing, p[KNEE_POINT : KNEE_POINT + 3].copy())
    torso = stance
    if at:
        u[4] = x[at + 1]
        torso = turned_y(stance, x[at])
    omega = x[4:7]
    rows = (cross(omega, joints[0]), cross(omega, joints[1]) + x[7] * cross(axis, joints[1] - joints[0]))
    spin = cross(omega, axis)
    for i in range(3):  # not slice assignments: their shape check's message compiles numba's string functions
        joints[2, i], joints[3, i], joints[4, i] = rows[0][i], rows[1][i], spin[i]
    mass = np.zeros((n, n))
    force = np.zeros(n)
    for k in range(int(p[3])):
        o = PARTS + k * PART_SIZE
        frame = int(p[o])
        turn = stance if frame == 0 else (swing if frame == 1 else (shank if frame == 2 else torso))
        _add_part(p, o, u, turn, joints[0] + shift if frame == 2 else joints[0], axis, joints, p_dot, mass, force)
    power = 0.0
    if at:
        on_torso, on_hinge, power = torso_elements(p, x)
        force[4] += on_torso
        force[3] += on_hinge
    free = n - 1 if knees and p[KNEE_FREE] != 1.0 else n
    cholesky_solve(mass, force, free)
    rates = attitude_rates(x)
    x_dot = np.zeros(x.shape[0])
    # not slice assignments: their shape check's message compiles numba's string functions
    x_dot[0], x_dot[1], x_dot[2], x_dot[3] = rates[0], rates[1], rates[2], x[7]
    for i in range(4):
        x_dot[4 + i] = force[i]
    x_dot[8], x_dot[9] = p_dot[0], p_dot[1]
    if knees:
        x_dot[KNEE_ANGLE] = x[KNEE_RATE]
        x_dot[KNEE_RATE] = force[n - 1] if free == n else 0.0
    if at:
        x_dot[at], x_dot[at + 1], x_dot[at + 2] = x[at + 1], force[4], power
    return x_dot
