"""A joint stop as a compliant contact: a one-sided limit of a revolute joint's relative angle (MODEL.md 4).

A stop of the joint between a parent body (angle phi_p) and a child (phi_c) limits the relative angle
theta = phi_c - phi_p from one side: an upper stop holds theta <= theta_s (a knee that cannot
hyperextend), a lower one theta >= theta_s. Its penetration is the angle past the limit,
delta = side (theta - theta_s) with side = +1 (upper) or -1 (lower), and its approach rate
deltadot = side (omega_c - omega_p). While delta > 0 the stop pushes back with a normal law of
:data:`~biped_sim.contact.normal.NORMAL_LAWS` (its own stiffness [N m / rad^n], exponent and restitution,
and the approach rate remembered at the stop's onset, as a foot's impact speed), as the torque
tau = -side F(delta, deltadot) on the child and -tau on the parent: equal and opposite, so it does no
work on the rest of the walker. The elastic part is stored (:func:`stop_energy`), the damping part
P = (F - K delta^n) deltadot is lost and integrated as the state W_stop, booked in the energy audit.

The stops of a system are the arrays of one :class:`Stops` record; a formulation's right-hand side
adds :func:`stop_torque` to the generalized forces at the angles' indices in y (the planar and the
minimal formulations both keep each body's absolute angle as a coordinate). The stops' discrete modes
are rows of the contact-mode table after the feet's (:func:`update_stop_modes`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from biped_sim.contact.normal import N_NORMAL_PARAMS, elastic_energy
from biped_sim.contact.response import (
    ARMED,
    IMPACT_SPEED,
    LIFTOFF_TIME,
    TOUCHING,
    normal_response,
    remembered_impact_speed,
)
from biped_sim.kernel import kernel

# columns of Stops.index: the indices in y of the child's and the parent's angle and of their rates (-1: the ground)
CHILD_ANGLE, PARENT_ANGLE, CHILD_RATE, PARENT_RATE = range(4)
# columns of Stops.limit: side (+1 upper, -1 lower), limit angle theta_s [rad], floor of the remembered rate [rad/s]
SIDE, ANGLE, RATE_FLOOR = range(3)


class Stops(NamedTuple):
    """The joint stops of a system, as the kernels read them (ns rows)."""

    index: np.ndarray  # (ns, 4) int64: CHILD_ANGLE, PARENT_ANGLE, CHILD_RATE, PARENT_RATE
    limit: np.ndarray  # (ns, 3): SIDE, ANGLE, RATE_FLOOR
    law: np.ndarray  # (ns,) int64: the normal law's number in NORMAL_LAWS
    params: np.ndarray  # (ns, N_NORMAL_PARAMS): its parameter vector (normal_parameters)


def make_stops(index: np.ndarray, limit: np.ndarray, law: np.ndarray, params: np.ndarray) -> Stops:
    """A :class:`Stops` record with the kernels' dtypes and shapes (any number of rows, 0 included)."""
    return Stops(
        np.asarray(index, dtype=np.int64).reshape(-1, 4),
        np.asarray(limit, dtype=np.float64).reshape(-1, 3),
        np.asarray(law, dtype=np.int64).reshape(-1),
        np.asarray(params, dtype=np.float64).reshape(-1, N_NORMAL_PARAMS),
    )


NO_STOPS = make_stops(np.zeros((0, 4)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, N_NORMAL_PARAMS)))


@kernel
def _entry(y: np.ndarray, k: int) -> float:
    """y[k], or 0 for the ground (k = -1: its angle and rate)."""
    return y[k] if k >= 0 else 0.0


@kernel
def stop_penetration(y: np.ndarray, stops: Stops, s: int) -> tuple[float, float]:
    """(delta, deltadot) of stop s: the relative angle past its limit [rad] and its approach rate [rad/s]."""
    index, side = stops.index, stops.limit[s, SIDE]
    theta = _entry(y, index[s, CHILD_ANGLE]) - _entry(y, index[s, PARENT_ANGLE])
    rate = _entry(y, index[s, CHILD_RATE]) - _entry(y, index[s, PARENT_RATE])
    return side * (theta - stops.limit[s, ANGLE]), side * rate


@kernel
def stop_torque(y: np.ndarray, stops: Stops, modes: np.ndarray, row: int, s: int) -> tuple[float, float]:
    """(tau, P) of stop s, whose contact mode is ``modes[row]``: the torque on its child (-tau on its parent)
    and the power its damping dissipates; zero while the joint is inside its limit."""
    delta, delta_dot = stop_penetration(y, stops, s)
    if delta <= 0.0:
        return 0.0, 0.0
    f, power = normal_response(stops.law[s], stops.params[s], stops.limit[s, RATE_FLOOR], modes, row, delta, delta_dot)
    return -stops.limit[s, SIDE] * f, power


@kernel
def stop_torques(y: np.ndarray, stops: Stops, modes: np.ndarray, first_row: int, force: np.ndarray) -> float:
    """Add every stop's torques to the generalized forces ``force`` (indexed as the angles in y: both
    formulations' coordinates come first in y) and return the power their damping dissipates (W_stop's rate);
    the stops' modes are rows first_row, ... of ``modes``."""
    power = 0.0
    for s in range(stops.law.shape[0]):
        tau, p = stop_torque(y, stops, modes, first_row + s, s)
        child, parent = stops.index[s, CHILD_ANGLE], stops.index[s, PARENT_ANGLE]
        force[child] += tau
        if parent >= 0:
            force[parent] -= tau
        power += p
    return power


@kernel
def stop_energy(y: np.ndarray, stops: Stops, s: int) -> float:
    """Energy K delta^(n+1) / (n+1) stored in stop s while it is pressed, else 0."""
    delta = stop_penetration(y, stops, s)[0]
    return elastic_energy(delta, stops.params[s]) if delta > 0.0 else 0.0


@kernel
def stops_energy(y: np.ndarray, stops: Stops) -> float:
    """Energy stored in every stop of ``stops``."""
    elastic = 0.0
    for s in range(stops.law.shape[0]):
        elastic += stop_energy(y, stops, s)
    return elastic


@kernel
def update_stop_modes(
    t: float, y: np.ndarray, stops: Stops, modes: np.ndarray, first_row: int, recontact: float
) -> bool:
    """The stops' contact bookkeeping at an event at time t (their modes are rows first_row, ...): an onset
    remembers the approach rate (:func:`~biped_sim.contact.response.remembered_impact_speed`, as a foot's),
    a release records its time. A stop is always armed. Returns True when a stop's mode changed."""
    changed = False
    for s in range(stops.law.shape[0]):
        row = first_row + s
        delta, delta_dot = stop_penetration(y, stops, s)
        touching, was_touching = delta > 0.0, modes[row, TOUCHING] > 0.5
        if touching and not was_touching:
            modes[row, IMPACT_SPEED] = remembered_impact_speed(
                modes[row, IMPACT_SPEED], modes[row, LIFTOFF_TIME], t, delta_dot, recontact
            )
        elif was_touching and not touching:
            modes[row, LIFTOFF_TIME] = t
        changed = changed or touching != was_touching
        modes[row, ARMED] = 1.0
        modes[row, TOUCHING] = 1.0 if touching else 0.0
    return changed
