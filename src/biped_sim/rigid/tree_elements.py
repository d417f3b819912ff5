"""The joint elements (springs, dampers) of a rigid walker tree: their generalized forces, stored energy and
dissipated power, each from its law's one source (:mod:`biped_sim.contact.joint_element`), read from the tree's
parameter vector (:mod:`biped_sim.rigid.tree_layout`)."""

from __future__ import annotations

import numpy as np

from biped_sim.contact.joint_element import element_energy, element_torque
from biped_sim.contact.stop import joint_entry
from biped_sim.kernel import kernel
from biped_sim.rigid.tree_layout import ELEMENT_FIELDS, ELEMENT_HEAD, T_NELEM, coords, element_offset


@kernel(reference_counts=False)
def joint_element(p: np.ndarray, e: int, q: np.ndarray, qd: np.ndarray) -> tuple[int, int, float, float]:
    """(child, other, torque on the child, dissipated power) of joint element e: its law's one source
    (:mod:`biped_sim.contact.joint_element`) at the relative angle and rate of the child to the other body."""
    o = element_offset(p, e)
    child, other = int(p[o + 1]), int(p[o + 2])
    params = p[o + ELEMENT_HEAD : o + ELEMENT_FIELDS]
    tau, power = element_torque(int(p[o]), q[child] - joint_entry(q, other), qd[child] - joint_entry(qd, other), params)
    return child, other, tau, power


@kernel(reference_counts=False)
def element_forces(p: np.ndarray, q: np.ndarray, qd: np.ndarray, r: int) -> None:
    """Add the joint elements' torques to the generalized forces at p[r:]: with absolute angles as coordinates a
    couple tau on (child, other) is tau on the child's coordinate and -tau on the other's (none on the ground)."""
    for e in range(int(p[T_NELEM])):
        child, other, tau, _ = joint_element(p, e, q, qd)
        p[r + child] += tau
        if other >= 0:  # not the ground
            p[r + other] -= tau


@kernel
def tree_element_energy(p: np.ndarray, q: np.ndarray) -> float:
    """Energy stored in the joint elements (their springs) at angles q."""
    stored = 0.0
    for e in range(int(p[T_NELEM])):
        o = element_offset(p, e)
        theta = q[int(p[o + 1])] - joint_entry(q, int(p[o + 2]))
        stored += element_energy(int(p[o]), theta, p[o + ELEMENT_HEAD : o + ELEMENT_FIELDS])
    return stored


@kernel
def tree_element_power(p: np.ndarray, x: np.ndarray) -> float:
    """Power the joint elements dissipate at state x (their dampers'), >= 0."""
    n = coords(p)
    dissipated = 0.0
    for e in range(int(p[T_NELEM])):
        dissipated += joint_element(p, e, x[:n], x[n:])[3]
    return dissipated
