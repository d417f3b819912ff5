"""Passive joint elements: torsional springs and dampers between two bodies, a law registry like the contact laws.

An element acts on a pair of bodies, a child (angle phi_c) and the body it acts against (phi_a: the child's
joint parent, or another body hinged at the same point, e.g. a torso's spring to the other leg), through
their relative angle theta = phi_c - phi_a and its rate thetadot = omega_c - omega_a. Its torque tau is applied
to the child and -tau to the other body: a pure couple, so it does no work on the rest of the walker and the
walker's momentum about the joint is untouched. Every law has the signature
``law(theta, theta_dot, p) -> (tau, P)``: the torque on the child [N m] and the power its non-conservative part
dissipates [W] (>= 0), ``p`` the parameter vector of :func:`element_parameters` (columns STIFFNESS, REST_ANGLE,
DAMPING); its stored energy is its own ``energy(theta, p)`` (0 for a law with no spring), the one source the
compliant energy audit and the rigid model read. The dissipated power is integrated as a state of the ODE
(the work W_element, before W_stop), so the energy balance closes with elements as with contacts. A formulation
adds the elements' torques with the stops' (:func:`joint_torques`) at the angles' indices in y and their energy
to the elastic energy (:func:`joints_energy`).

To add a law (a nonlinear spring, a preloaded one): one ``@kernel`` torque function and its energy below, and
one line in :data:`JOINT_ELEMENT_LAWS` naming the parameters it reads; the schema's names and the compiled
dispatch read the registry.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import literal_unroll

from biped_sim.contact.registry import by_type, registered_functions, share
from biped_sim.contact.stop import (
    CHILD_ANGLE,
    CHILD_RATE,
    PARENT_ANGLE,
    PARENT_RATE,
    Stops,
    apply_joint_torque,
    joint_entry,
    stop_torques,
    stops_energy,
)
from biped_sim.kernel import kernel

STIFFNESS, REST_ANGLE, DAMPING = range(3)
ELEMENT_PARAMETERS = ("stiffness", "rest_angle", "damping")  # the parameter vector's columns, by the schema's names
N_ELEMENT_PARAMS = len(ELEMENT_PARAMETERS)


@kernel
def linear_spring_torque(theta: float, theta_dot: float, p: np.ndarray) -> tuple[float, float]:
    """Linear torsional spring about a rest angle (Hooke): tau = -k (theta - theta_0); conservative (P = 0).

    The hip spring of McGeer's and Wisse's walkers (T. McGeer, Int. J. Robot. Res. 9(2) (1990) 62-82; M. Wisse,
    A. L. Schwab, F. C. T. van der Helm, Robotica 22 (2004) 681-688).
    """
    return -p[STIFFNESS] * (theta - p[REST_ANGLE]), 0.0


@kernel
def linear_spring_energy(theta: float, p: np.ndarray) -> float:
    """Energy stored in a linear torsional spring: V = k (theta - theta_0)^2 / 2."""
    d = theta - p[REST_ANGLE]
    return 0.5 * p[STIFFNESS] * d * d


@kernel
def linear_damper_torque(theta: float, theta_dot: float, p: np.ndarray) -> tuple[float, float]:
    """Linear viscous torsional damper: tau = -c thetadot, dissipating P = c thetadot^2."""
    return -p[DAMPING] * theta_dot, p[DAMPING] * theta_dot * theta_dot


@kernel
def no_energy(theta: float, p: np.ndarray) -> float:
    """A law without a spring stores nothing: V = 0."""
    return 0.0


@dataclass(frozen=True)
class JointElementLaw:
    """A registered element law: its dispatch number, torque and energy functions, the parameters it reads
    (names of :data:`ELEMENT_PARAMETERS`) and those a description must give (the others read default to 0)."""

    index: int
    function: Callable[..., tuple[float, float]]
    energy: Callable[..., float]
    reads: tuple[str, ...]
    needs: tuple[str, ...]


JOINT_ELEMENT_LAWS: dict[str, JointElementLaw] = {
    "linear_spring": JointElementLaw(0, linear_spring_torque, linear_spring_energy, ("stiffness", "rest_angle"),
                                     ("stiffness",)),
    "linear_damper": JointElementLaw(1, linear_damper_torque, no_energy, ("damping",), ("damping",)),
}  # fmt: skip
ELEMENT_TORQUES = registered_functions(JOINT_ELEMENT_LAWS)
ELEMENT_ENERGIES = tuple(law.energy for law in JOINT_ELEMENT_LAWS.values())


def element_parameters(law: str, **values: float | None) -> np.ndarray:
    """The parameter vector of an element of law ``law`` from its named values (``stiffness``, ``rest_angle``,
    ``damping``; None or absent: 0, a value the law does not read: ValueError)."""
    reads = JOINT_ELEMENT_LAWS[law].reads
    p = np.zeros(N_ELEMENT_PARAMS)
    for name, value in values.items():
        if value is None:
            continue
        if name not in reads:
            raise ValueError(f"{name}: a {law} reads only {', '.join(reads)}")
        p[ELEMENT_PARAMETERS.index(name)] = value
    return p


@kernel
def element_torque(law: int, theta: float, theta_dot: float, p: np.ndarray) -> tuple[float, float]:
    """(tau, P) of the law numbered ``law`` (its position in JOINT_ELEMENT_LAWS) at (theta, thetadot)."""
    tau, power = 0.0, 0.0
    index = 0
    for function in literal_unroll(ELEMENT_TORQUES):  # unrolled at compile time: one direct call per law
        if index == law:
            tau, power = function(theta, theta_dot, p)
        index += 1  # noqa: SIM113 (numba cannot enumerate a literal_unroll)
    return tau, power


@kernel
def element_energy(law: int, theta: float, p: np.ndarray) -> float:
    """Energy stored by the law numbered ``law`` at relative angle theta."""
    energy = 0.0
    index = 0
    for function in literal_unroll(ELEMENT_ENERGIES):
        if index == law:
            energy = function(theta, p)
        index += 1  # noqa: SIM113 (numba cannot enumerate a literal_unroll)
    return energy


class JointElements(NamedTuple):
    """The joint elements of a system, as the kernels read them (ne rows)."""

    index: np.ndarray  # (ne, 4) int64: CHILD_ANGLE, PARENT_ANGLE (the other body's; -1: the ground), CHILD_RATE,
    # PARENT_RATE in y
    law: np.ndarray  # (ne,) int64: the law's number in JOINT_ELEMENT_LAWS
    params: np.ndarray  # (ne, N_ELEMENT_PARAMS): element_parameters


class NoElements(JointElements):
    """The joint elements of a walker without any: a :class:`JointElements` record of no rows, of a type of its own.

    As :class:`~biped_sim.contact.stop.NoStops`: the kernels over the elements (:func:`element_torques`,
    :func:`elements_energy`) resolve at compile time from the record's type to no-ops, so that a walker without
    elements compiles none of their code or laws; :func:`make_elements` of no rows returns one.
    """

    __slots__ = ()


def make_elements(index: np.ndarray, law: np.ndarray, params: np.ndarray) -> JointElements:
    """A :class:`JointElements` record with the kernels' dtypes and shapes (a :class:`NoElements` of no rows)."""
    law = np.asarray(law, dtype=np.int64).reshape(-1)
    return (JointElements if law.shape[0] else NoElements)(
        np.asarray(index, dtype=np.int64).reshape(-1, 4),
        law,
        np.asarray(params, dtype=np.float64).reshape(-1, N_ELEMENT_PARAMS),
    )


NO_ELEMENTS = make_elements(np.zeros((0, 4)), np.zeros(0), np.zeros((0, N_ELEMENT_PARAMS)))


@kernel
def _angle_difference(y: np.ndarray, elements: JointElements, e: int) -> tuple[float, float]:
    """(theta, thetadot) of element e: the child's angle and rate relative to the other body's (or to the slope
    normal: the other body -1, the ground, as a stop's)."""
    index = elements.index
    theta = y[index[e, CHILD_ANGLE]] - joint_entry(y, index[e, PARENT_ANGLE])
    return theta, y[index[e, CHILD_RATE]] - joint_entry(y, index[e, PARENT_RATE])


# as contact.stop's: a formulation whose coordinates are not angles adds its own elements record (multibody.hinge);
# an element's couple is a stop's (contact.stop.apply_joint_torque, the same index columns)
relative_angle = by_type("relative_angle", "elements", {JointElements: _angle_difference})
share(apply_joint_torque, JointElements, Stops)


@kernel
def _element_torques(y: np.ndarray, elements: JointElements, force: np.ndarray) -> float:
    power = 0.0
    for e in range(elements.law.shape[0]):
        theta, theta_dot = relative_angle(y, elements, e)
        tau, p = element_torque(elements.law[e], theta, theta_dot, elements.params[e])
        apply_joint_torque(y, elements, e, tau, force)
        power += p
    return power


@kernel
def _no_element_torques(y: np.ndarray, elements: NoElements, force: np.ndarray) -> float:
    return 0.0


element_torques = by_type(
    "element_torques", "elements", {JointElements: _element_torques, NoElements: _no_element_torques}
)
element_torques.__doc__ = """Add every element's torques to the generalized forces ``force`` (indexed as the angles
in y) and return the power they dissipate (W_element's rate; none for a :class:`NoElements`)."""


@kernel
def _elements_energy(y: np.ndarray, elements: JointElements) -> float:
    energy = 0.0
    for e in range(elements.law.shape[0]):
        energy += element_energy(elements.law[e], relative_angle(y, elements, e)[0], elements.params[e])
    return energy


@kernel
def _no_elements_energy(y: np.ndarray, elements: NoElements) -> float:
    return 0.0


elements_energy = by_type(
    "elements_energy", "elements", {JointElements: _elements_energy, NoElements: _no_elements_energy}
)
elements_energy.__doc__ = """Energy stored in every element of ``elements`` (none in a :class:`NoElements`)."""


@kernel
def joint_torques(
    y: np.ndarray, stops: Stops, elements: JointElements, modes: np.ndarray, first_row: int, force: np.ndarray,
    ydot: np.ndarray, work: int,
) -> None:  # fmt: skip
    """Add the elements' and the stops' torques to the generalized forces ``force`` and write the rates of the work
    they dissipate: W_element at ydot[work] (with elements), then W_stop (with stops; their modes: rows
    first_row, ... of ``modes``). A system without either computes nothing here."""
    if elements.law.shape[0] > 0:
        ydot[work] = element_torques(y, elements, force)
        work += 1
    if stops.law.shape[0] > 0:
        ydot[work] = stop_torques(y, stops, modes, first_row, force)


@kernel
def joints_energy(y: np.ndarray, stops: Stops, elements: JointElements, modes: np.ndarray, first_row: int) -> float:
    """Energy stored in the stops (their modes: rows first_row, ... of ``modes``) and the elements' springs."""
    energy = stops_energy(y, stops, modes, first_row)
    if elements.law.shape[0] > 0:
        energy += elements_energy(y, elements)
    return energy
