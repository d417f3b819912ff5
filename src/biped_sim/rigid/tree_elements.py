"""The joint elements (springs, dampers) of a rigid walker tree: their generalized forces, stored energy and
dissipated power, each from its law's one source (:mod:`biped_sim.contact.joint_element`), read from the tree's
``elements`` record (:class:`~biped_sim.rigid.tree_layout.RigidTree`)."""

from __future__ import annotations

import numpy as np

from biped_sim.contact.joint_element import element_energy, element_torque
from biped_sim.contact.stop import joint_entry
from biped_sim.kernel import kernel
from biped_sim.rigid.tree_layout import RigidTree


@kernel(reference_counts=False)
def joint_element(
    elements: np.ndarray, params: np.ndarray, e: int, q: np.ndarray, qd: np.ndarray
) -> tuple[int, int, float, float]:
    """(child, other, torque on the child, dissipated power) of joint element e (``elements``: the tree's record,
    ``params``: its laws' parameters): its law's one source (:mod:`biped_sim.contact.joint_element`) at the
    relative angle and rate of the child to the other body."""
    element = elements[e]
    child, other = element.child, element.other
    theta, theta_dot = q[child] - joint_entry(q, other), qd[child] - joint_entry(qd, other)
    tau, power = element_torque(element.law, theta, theta_dot, params[e])
    return child, other, tau, power


@kernel(reference_counts=False)
def element_forces(elements: np.ndarray, params: np.ndarray, q: np.ndarray, qd: np.ndarray, forces: np.ndarray) -> None:
    """Add the joint elements' torques to the generalized forces: with absolute angles as coordinates a couple tau
    on (child, other) is tau on the child's coordinate and -tau on the other's, none on the ground (the tree's
    records passed alone: the flow calls this once per evaluation, and a call passes every array of its arguments)."""
    for e in range(elements.shape[0]):
        child, other, tau, _ = joint_element(elements, params, e, q, qd)
        forces[child] += tau
        if other >= 0:  # not the ground
            forces[other] -= tau


@kernel
def tree_element_energy(tree: RigidTree, q: np.ndarray) -> float:
    """Energy stored in the joint elements (their springs) at angles q."""
    stored = 0.0
    for e in range(tree.elements.shape[0]):
        element = tree.elements[e]
        theta = q[element.child] - joint_entry(q, element.other)
        stored += element_energy(element.law, theta, tree.element_params[e])
    return stored


@kernel
def tree_element_power(tree: RigidTree, x: np.ndarray) -> float:
    """Power the joint elements dissipate at state x (their dampers'), >= 0."""
    n = tree.n
    dissipated = 0.0
    for e in range(tree.elements.shape[0]):
        dissipated += joint_element(tree.elements, tree.element_params, e, x[:n], x[n:])[3]
    return dissipated
