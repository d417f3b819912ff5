"""Joint stops, springs and dampers on the revolute joints of the spatial formulation (Euler parameters).

The stops (:mod:`biped_sim.contact.stop`) and the joint elements (:mod:`biped_sim.contact.joint_element`) of the
planar formulations act on a joint's relative angle, a difference of two coordinates. In space a body has no angle
coordinate: a revolute joint's angle is read from the two bodies' Euler parameters. Its frame (:data:`FRAME`
columns) is the joint axis a_c and a reference vector u_c perpendicular to it in the child's body frame, and a
reference u_p in the parent's (perpendicular to the axis as the joint holds it); the angle is

    theta = atan2(((A_p u_p) x (A_c u_c)) . n, (A_p u_p) . (A_c u_c)),  n = A_c a_c,

zero where the two references coincide, positive for the child turned about +n (a planar walker lifted into
space, its joints about z' and its references x', has theta = phi_c - phi_p), and its rate is
thetadot = (omega_c - omega_p) . n with omega = 2 E pdot. A torque tau about the axis acts on the child as the
body-frame moment tau a_c and on the parent as -tau n, in its frame: the generalized forces 2 G^T n' of each
body's Euler parameters, whose power tau thetadot is the element's or the stop's, so that their energy closes the
audit as in the plane. The ground (-1) is a parent of identity attitude at rest.

:class:`HingeStops` and :class:`HingeElements` carry the planar records' fields plus the frame; their
``index`` columns (CHILD_ANGLE, PARENT_ANGLE, CHILD_RATE, PARENT_RATE) are the first indices in y of the two
bodies' Euler parameters and of their rates. Everything else (the laws, latches, modes, events, energy and the
work states) is the planar records' code, which this module registers for the new records.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.contact import joint_element, stop
from biped_sim.contact.registry import extend, share
from biped_sim.contact.stop import ANGLE, CHILD_ANGLE, CHILD_RATE, PARENT_ANGLE, PARENT_RATE, SIDE
from biped_sim.kernel import kernel
from biped_sim.multibody.euler_parameters import dot3, e_mul, g_tmul, rotate, rotate_t, vec3

AXIS, CHILD_REFERENCE, PARENT_REFERENCE = 0, 3, 6  # first columns of the three vectors of a frame row
FRAME = 9  # columns of a frame row
IDENTITY, AT_REST = (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)  # the ground's Euler parameters and rates


class HingeStops(NamedTuple):
    """The joint stops of a spatial system (:class:`~biped_sim.contact.stop.Stops`' fields and the frames)."""

    index: np.ndarray  # (ns, 4) int64: y indices of the child's and the parent's Euler parameters, then rates
    limit: np.ndarray  # (ns, 3): SIDE, ANGLE, RATE_FLOOR
    law: np.ndarray  # (ns,) int64
    params: np.ndarray  # (ns, N_NORMAL_PARAMS)
    latch: np.ndarray  # (ns, 2) int64
    frame: np.ndarray  # (ns, FRAME): a_c, u_c (child's frame), u_p (parent's frame)


class HingeElements(NamedTuple):
    """The joint elements of a spatial system (:class:`~biped_sim.contact.joint_element.JointElements`' fields and
    the frames)."""

    index: np.ndarray  # (ne, 4) int64: as HingeStops.index
    law: np.ndarray  # (ne,) int64
    params: np.ndarray  # (ne, N_ELEMENT_PARAMS)
    frame: np.ndarray  # (ne, FRAME)


@kernel
def entries(y: np.ndarray, k: int, ground: tuple) -> tuple[float, float, float, float]:
    """The four entries of y from k (Euler parameters or their rates), or ``ground``'s for k = -1."""
    if k < 0:
        return ground
    return y[k], y[k + 1], y[k + 2], y[k + 3]


@kernel
def _squared(p: tuple) -> float:
    return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]


@kernel
def joint_axis(p_c: tuple, frame: np.ndarray, row: int) -> tuple[float, float, float]:
    """n = A_c a_c (A of unit parameters: the homogeneous form divided by |p|^2)."""
    n = rotate(p_c, vec3(frame, row, AXIS))
    inv = 1.0 / _squared(p_c)
    return n[0] * inv, n[1] * inv, n[2] * inv


@kernel
def hinge_angle(y: np.ndarray, index: np.ndarray, frame: np.ndarray, row: int) -> tuple[float, float]:
    """(theta, thetadot) of the revolute joint ``index[row]`` of frame ``frame[row]`` (see the module)."""
    p_c, p_p = entries(y, index[row, CHILD_ANGLE], IDENTITY), entries(y, index[row, PARENT_ANGLE], IDENTITY)
    n = joint_axis(p_c, frame, row)
    u_c = rotate(p_c, vec3(frame, row, CHILD_REFERENCE))
    u_p = rotate(p_p, vec3(frame, row, PARENT_REFERENCE))
    cross = (u_p[1] * u_c[2] - u_p[2] * u_c[1], u_p[2] * u_c[0] - u_p[0] * u_c[2], u_p[0] * u_c[1] - u_p[1] * u_c[0])
    w_c = e_mul(p_c, entries(y, index[row, CHILD_RATE], AT_REST))
    w_p = e_mul(p_p, entries(y, index[row, PARENT_RATE], AT_REST))
    return math.atan2(dot3(cross, n), dot3(u_p, u_c)), 2.0 * (dot3(w_c, n) - dot3(w_p, n))


@kernel
def hinge_couple(y: np.ndarray, index: np.ndarray, frame: np.ndarray, row: int, tau: float, force: np.ndarray) -> None:
    """Add the torque tau about the joint's axis on the child, -tau on the parent, to the generalized forces of
    their Euler parameters (2 G^T n', n' the moment in the body's frame)."""
    k_c, k_p = index[row, CHILD_ANGLE], index[row, PARENT_ANGLE]
    p_c = entries(y, k_c, IDENTITY)
    a_c = vec3(frame, row, AXIS)
    q = g_tmul(p_c, (2.0 * tau * a_c[0], 2.0 * tau * a_c[1], 2.0 * tau * a_c[2]))
    for j in range(4):
        force[k_c + j] += q[j]
    if k_p >= 0:
        p_p = entries(y, k_p, IDENTITY)
        m = rotate_t(p_p, joint_axis(p_c, frame, row))
        scale = -2.0 * tau / _squared(p_p)
        q = g_tmul(p_p, (scale * m[0], scale * m[1], scale * m[2]))
        for j in range(4):
            force[k_p + j] += q[j]


@kernel
def _hinge_penetration(y: np.ndarray, stops: HingeStops, s: int) -> tuple[float, float]:
    theta, rate = hinge_angle(y, stops.index, stops.frame, s)
    side = stops.limit[s, SIDE]
    return side * (theta - stops.limit[s, ANGLE]), side * rate


@kernel
def _hinge_torque(y: np.ndarray, joints: tuple, row: int, tau: float, force: np.ndarray) -> None:
    """:func:`hinge_couple` of row ``row`` of ``joints`` (a :class:`HingeStops` or :class:`HingeElements`)."""
    hinge_couple(y, joints.index, joints.frame, row, tau, force)


@kernel
def _hinge_relative_angle(y: np.ndarray, elements: HingeElements, e: int) -> tuple[float, float]:
    return hinge_angle(y, elements.index, elements.frame, e)


extend(stop.stop_penetration, HingeStops, _hinge_penetration)
extend(stop.apply_joint_torque, HingeStops, _hinge_torque)
for _generic in (stop.stop_rate, stop.stop_torques, stop.stops_energy, stop.update_stop_modes):
    share(_generic, HingeStops, stop.Stops)
extend(joint_element.relative_angle, HingeElements, _hinge_relative_angle)
share(stop.apply_joint_torque, HingeElements, HingeStops)
for _generic in (joint_element.element_torques, joint_element.elements_energy):
    share(_generic, HingeElements, joint_element.JointElements)


def hinge_index(child: int, parent: int, n_bodies: int) -> list[int]:
    """The ``index`` row of a joint between bodies ``child`` and ``parent`` (-1: the ground) of a system of
    ``n_bodies`` bodies (the state y = [q (7 nb) | qd (7 nb) | ...])."""
    rates = 7 * n_bodies
    if parent < 0:
        return [7 * child + 3, -1, rates + 7 * child + 3, -1]
    return [7 * child + 3, 7 * parent + 3, rates + 7 * child + 3, rates + 7 * parent + 3]


def make_hinge_stops(planar: stop.Stops, index: np.ndarray, frame: np.ndarray) -> stop.Stops | HingeStops:
    """The stops of ``planar`` (laws, limits, latches) on the spatial joints of ``index`` and ``frame`` rows (a
    walker without stops keeps its :class:`~biped_sim.contact.stop.NoStops`: none of their code compiles)."""
    if planar.law.shape[0] == 0:
        return planar
    return HingeStops(
        np.asarray(index, dtype=np.int64).reshape(-1, 4), planar.limit, planar.law, planar.params, planar.latch,
        np.asarray(frame, dtype=np.float64).reshape(-1, FRAME),
    )  # fmt: skip


def make_hinge_elements(
    planar: joint_element.JointElements, index: np.ndarray, frame: np.ndarray
) -> joint_element.JointElements | HingeElements:
    """The elements of ``planar`` (laws, parameters) on the spatial joints of ``index`` and ``frame`` rows (none:
    ``planar``'s :class:`~biped_sim.contact.joint_element.NoElements`)."""
    if planar.law.shape[0] == 0:
        return planar
    return HingeElements(
        np.asarray(index, dtype=np.int64).reshape(-1, 4), planar.law, planar.params,
        np.asarray(frame, dtype=np.float64).reshape(-1, FRAME),
    )  # fmt: skip
