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

A latching stop (a knee latch: McGeer 1990's machines, Chen 2007's straight stance knee, which the rigid
model holds locked) is one-sided while free and two-sided while latched: then it resists the joint leaving
its limit in both directions with the same law, F(|delta|, sign(delta) deltadot) acting against sign(delta),
stored energy K |delta|^(n+1) / (n+1) and damping booked in W_stop as before. Its latch state, the ARMED
column of its mode row (:data:`LATCHED`: FREE, HELD, RELEASING; a plain stop's is always 1), engages (HELD)
when the stop is struck (its one-sided contact begins) while its leg's foot is ahead of the other leg's: the
knee strike that ends a swing, not the trailing knee touching its stop just after the heel strike or at a
run's start, which the one-sided stop holds as an unlatched one (a run starts with the stance leg's latches
held). It is released in two stages, so that both knees stay latched through
the whole impulse of a heel strike, as the rigid model holds them: at its leg's toe-off (``Stops.latch``'s
FOOT leaving the ground behind the other leg's foot) it becomes RELEASING, and it lets go (FREE) once the
other leg's foot (PARTNER), which has just struck, is no longer being compressed (the end of that strike's
impulse: an event function per latching stop, that foot's approach velocity). The rigid model's "the new
swing knee unlocks at once after the heel strike" is the limit of this rule as the contact stiffens. A
latched stop counts as touching (its contact log shows the engagement and the release) and keeps the
approach rate remembered at engagement. A latch released while the joint is inside its limit lets go of its
spring: the energy stored there is lost at the release and booked in W_stop (the state's last entry), so the
energy balance still closes.

The stops of a system are the arrays of one :class:`Stops` record; a formulation's right-hand side
adds :func:`stop_torque` to the generalized forces at the angles' indices in y (the planar and the
minimal formulations both keep each body's absolute angle as a coordinate). The stops' discrete modes
are rows of the contact-mode table after the feet's (:func:`update_stop_modes`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from biped_sim.contact.normal import N_NORMAL_PARAMS, elastic_energy
from biped_sim.contact.registry import by_type
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
LATCHED = ARMED  # a latching stop's mode column: FREE, HELD or RELEASING (a plain stop's: always 1)
FREE, HELD, RELEASING = 0.0, 1.0, 2.0  # RELEASING: held until the other foot's strike is over
# columns of Stops.latch: the foot whose toe-off releases the latch, the other leg's foot whose strike it waits for
FOOT, PARTNER = range(2)
NOT_LATCHING = -1  # Stops.latch of a stop without a latch


class Stops(NamedTuple):
    """The joint stops of a system, as the kernels read them (ns rows)."""

    index: np.ndarray  # (ns, 4) int64: CHILD_ANGLE, PARENT_ANGLE, CHILD_RATE, PARENT_RATE
    limit: np.ndarray  # (ns, 3): SIDE, ANGLE, RATE_FLOOR
    law: np.ndarray  # (ns,) int64: the normal law's number in NORMAL_LAWS
    params: np.ndarray  # (ns, N_NORMAL_PARAMS): its parameter vector (normal_parameters)
    latch: np.ndarray  # (ns, 2) int64: FOOT, PARTNER of a latching stop, NOT_LATCHING (both) of a plain one


class NoStops(Stops):
    """The joint stops of a walker without any: a :class:`Stops` record of no rows, of a type of its own.

    The stop kernels the engine calls (:func:`stop_torques`, :func:`stops_energy`, :func:`update_stop_modes`,
    :func:`stop_rate`, and the stops' event functions) are resolved at compile time from the record's type
    (:func:`~biped_sim.contact.registry.by_type`), so that a walker without stops compiles none of their code
    (``docs/architecture.md``, "Compile time"); :func:`make_stops` of no rows returns one. A new kernel that
    loops over a system's stops is registered the same way: its code for :class:`Stops`, a no-op for this type.
    """

    __slots__ = ()


def make_stops(
    index: np.ndarray, limit: np.ndarray, law: np.ndarray, params: np.ndarray, latch: np.ndarray | None = None
) -> Stops:
    """A :class:`Stops` record with the kernels' dtypes and shapes (a :class:`NoStops` of no rows; ``latch``
    None: no stop latches)."""
    law = np.asarray(law, dtype=np.int64).reshape(-1)
    latch = np.full((law.shape[0], 2), NOT_LATCHING) if latch is None else latch
    return (Stops if law.shape[0] else NoStops)(
        np.asarray(index, dtype=np.int64).reshape(-1, 4),
        np.asarray(limit, dtype=np.float64).reshape(-1, 3),
        law,
        np.asarray(params, dtype=np.float64).reshape(-1, N_NORMAL_PARAMS),
        np.asarray(latch, dtype=np.int64).reshape(-1, 2),
    )


def stop_event_count(stops: Stops) -> int:
    """Event functions of ``stops``: each stop's penetration, then each latching stop's other foot's approach
    velocity (the end of that foot's strike, which a releasing latch waits for)."""
    return int(stops.law.shape[0] + np.count_nonzero(stops.latch[:, FOOT] != NOT_LATCHING))


NO_STOPS = make_stops(np.zeros((0, 4)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, N_NORMAL_PARAMS)))


@kernel
def joint_entry(y: np.ndarray, k: int) -> float:
    """y[k], or 0 for the ground (k = -1: its angle and rate)."""
    return y[k] if k >= 0 else 0.0


@kernel
def _angle_penetration(y: np.ndarray, stops: Stops, s: int) -> tuple[float, float]:
    """(delta, deltadot) of stop s: the relative angle past its limit [rad] and its approach rate [rad/s]."""
    index, side = stops.index, stops.limit[s, SIDE]
    theta = joint_entry(y, index[s, CHILD_ANGLE]) - joint_entry(y, index[s, PARENT_ANGLE])
    rate = joint_entry(y, index[s, CHILD_RATE]) - joint_entry(y, index[s, PARENT_RATE])
    return side * (theta - stops.limit[s, ANGLE]), side * rate


@kernel
def _apply_angle_torque(y: np.ndarray, joints: tuple, row: int, tau: float, force: np.ndarray) -> None:
    """Add the torque tau of row ``row`` of ``joints`` (a stop's or a joint element's: both records' ``index``
    rows name the child's and the other body's angle) to the child's angle's generalized force, -tau to the
    other body's (none for the ground)."""
    index = joints.index
    force[index[row, CHILD_ANGLE]] += tau
    if index[row, PARENT_ANGLE] >= 0:
        force[index[row, PARENT_ANGLE]] -= tau


# a formulation whose coordinates are not the bodies' angles (the spatial one: multibody.hinge) adds its own stops
# record to these two and shares the other kernels of this module (contact.registry.share); apply_joint_torque
# serves the joint elements too (contact.joint_element adds its record): one couple for both
stop_penetration = by_type("stop_penetration", "stops", {Stops: _angle_penetration})
apply_joint_torque = by_type("apply_joint_torque", "joints", {Stops: _apply_angle_torque})


@kernel
def _stop_rate(y: np.ndarray, stops: Stops, s: int) -> float:
    return stop_penetration(y, stops, s)[1]


@kernel
def _no_stop_rate(y: np.ndarray, stops: NoStops, s: int) -> float:
    return 0.0


stop_rate = by_type("stop_rate", "stops", {Stops: _stop_rate, NoStops: _no_stop_rate})
stop_rate.__doc__ = (
    """Stop s's approach rate deltadot [rad/s] (:func:`stop_penetration`; a :class:`NoStops` has none)."""
)


@kernel
def is_latched(stops: Stops, modes: np.ndarray, row: int, s: int) -> bool:
    """Whether stop s (mode row ``row``) is a latching stop whose latch holds."""
    return stops.latch[s, FOOT] != NOT_LATCHING and modes[row, LATCHED] != FREE


@kernel
def stop_torque(y: np.ndarray, stops: Stops, modes: np.ndarray, row: int, s: int) -> tuple[float, float]:
    """(tau, P) of stop s, whose contact mode is ``modes[row]``: the torque on its child (-tau on its parent)
    and the power its damping dissipates; zero while the joint is inside its limit, unless it is latched."""
    delta, delta_dot = stop_penetration(y, stops, s)
    pressed = 1.0  # the side the joint presses: +1 past the limit, -1 inside it (latched only)
    if is_latched(stops, modes, row, s):
        if delta < 0.0:
            pressed = -1.0
    elif delta <= 0.0:
        return 0.0, 0.0
    law, floor = stops.law[s], stops.limit[s, RATE_FLOOR]
    f, power = normal_response(law, stops.params[s], floor, modes, row, pressed * delta, pressed * delta_dot)
    return -stops.limit[s, SIDE] * pressed * f, power


@kernel
def _stop_torques(y: np.ndarray, stops: Stops, modes: np.ndarray, first_row: int, force: np.ndarray) -> float:
    power = 0.0
    for s in range(stops.law.shape[0]):
        tau, p = stop_torque(y, stops, modes, first_row + s, s)
        apply_joint_torque(y, stops, s, tau, force)
        power += p
    return power


@kernel
def _no_stop_torques(y: np.ndarray, stops: NoStops, modes: np.ndarray, first_row: int, force: np.ndarray) -> float:
    return 0.0


stop_torques = by_type("stop_torques", "stops", {Stops: _stop_torques, NoStops: _no_stop_torques})
stop_torques.__doc__ = """Add every stop's torques to the generalized forces ``force`` (indexed as the angles in y: both
formulations' coordinates come first in y) and return the power their damping dissipates (W_stop's rate); the
stops' modes are rows first_row, ... of ``modes``."""


@kernel
def stop_energy(y: np.ndarray, stops: Stops, modes: np.ndarray, row: int, s: int) -> float:
    """Energy K |delta|^(n+1) / (n+1) stored in stop s (mode row ``row``) while it is pressed or latched, else 0."""
    delta = stop_penetration(y, stops, s)[0]
    if is_latched(stops, modes, row, s):
        return elastic_energy(abs(delta), stops.params[s])
    return elastic_energy(delta, stops.params[s]) if delta > 0.0 else 0.0


@kernel
def _stops_energy(y: np.ndarray, stops: Stops, modes: np.ndarray, first_row: int) -> float:
    elastic = 0.0
    for s in range(stops.law.shape[0]):
        elastic += stop_energy(y, stops, modes, first_row + s, s)
    return elastic


@kernel
def _no_stops_energy(y: np.ndarray, stops: NoStops, modes: np.ndarray, first_row: int) -> float:
    return 0.0


stops_energy = by_type("stops_energy", "stops", {Stops: _stops_energy, NoStops: _no_stops_energy})
stops_energy.__doc__ = """Energy stored in every stop of ``stops`` (their modes: rows first_row, ... of ``modes``)."""


@kernel
def _leaves_behind(modes: np.ndarray, gates: np.ndarray, foot: int) -> bool:
    """Whether ``foot`` (touching before this update) is now in the air behind its partner: the trailing toe-off
    (``gates``: the event functions, a foot's penetration then its lead over its partner)."""
    return modes[foot, TOUCHING] > 0.5 and gates[2 * foot] <= 0.0 and gates[2 * foot + 1] <= 0.0


@kernel
def _latch_after(stops: Stops, modes: np.ndarray, gates: np.ndarray, approach: np.ndarray, row: int, s: int) -> float:
    """The latch state of latching stop s after an event, before any strike of it: HELD becomes RELEASING at its
    foot's toe-off behind the other foot, RELEASING becomes FREE once that other foot is not being compressed
    (its strike's impulse over: not in the ground with a positive approach velocity ``approach``)."""
    state, partner = modes[row, LATCHED], stops.latch[s, PARTNER]
    if state == HELD and _leaves_behind(modes, gates, stops.latch[s, FOOT]):
        state = RELEASING
    if state == RELEASING and not (gates[2 * partner] > 0.0 and approach[partner] > 0.0):
        state = FREE
    return state


@kernel
def _update_stop_modes(
    t: float, y: np.ndarray, stops: Stops, modes: np.ndarray, first_row: int, recontact: float,
    gates: np.ndarray, approach: np.ndarray,
) -> bool:  # fmt: skip
    """The stops' contact bookkeeping at an event at time t (their modes are rows first_row, ...): an onset
    remembers the approach rate (:func:`~biped_sim.contact.response.remembered_impact_speed`, as a foot's) and
    engages a latch if its foot is ahead of the other (the gates' lead), a release records its time; a latch holds the
    stop touching until it is released (:func:`_latch_after`, from the feet's rows read before their own update,
    the event functions ``gates`` and the feet's approach velocities ``approach``), letting go of the energy
    its spring holds inside the limit (booked in W_stop, the state's last entry). A plain stop is always
    armed. Returns True when a stop's mode changed."""
    changed = False
    for s in range(stops.law.shape[0]):
        row, latching = first_row + s, stops.latch[s, FOOT] != NOT_LATCHING
        delta, delta_dot = stop_penetration(y, stops, s)
        was_latched, latch = is_latched(stops, modes, row, s), modes[row, LATCHED]
        if was_latched:
            latch = _latch_after(stops, modes, gates, approach, row, s)
            if latch == FREE and delta < 0.0:
                y[y.shape[0] - 1] += elastic_energy(-delta, stops.params[s])
        touching, was_touching = delta > 0.0 or (latching and latch != FREE), modes[row, TOUCHING] > 0.5
        if touching and not was_touching:
            modes[row, IMPACT_SPEED] = remembered_impact_speed(
                modes[row, IMPACT_SPEED], modes[row, LIFTOFF_TIME], t, delta_dot, recontact
            )
            if latching and gates[2 * stops.latch[s, FOOT] + 1] > 0.0:  # the knee strike ending a swing
                latch = HELD
        elif was_touching and not touching:
            modes[row, LIFTOFF_TIME] = t
        changed = changed or touching != was_touching or latch != modes[row, LATCHED]
        modes[row, LATCHED] = latch if latching else 1.0
        modes[row, TOUCHING] = 1.0 if touching else 0.0
    return changed


@kernel
def _no_stop_modes(
    t: float, y: np.ndarray, stops: NoStops, modes: np.ndarray, first_row: int, recontact: float,
    gates: np.ndarray, approach: np.ndarray,
) -> bool:  # fmt: skip
    return False


update_stop_modes = by_type("update_stop_modes", "stops", {Stops: _update_stop_modes, NoStops: _no_stop_modes})
update_stop_modes.__doc__ = _update_stop_modes.__doc__
