"""Contact events of every formulation, written once over its ``foot_contact`` kernel (compiled).

A walker's discrete events are the sign changes of two functions per foot i (MODEL.md 3): its
penetration delta_i (touchdown, lift-off) and its lead x_i - x_partner over its partner foot along
the slope (the scuffing guard arms a foot once it is ahead). At an event the integrators call
:func:`system_update_modes`, which evaluates the feet and hands them to
:func:`~biped_sim.contact.response.update_contact_modes`; a touchdown of a foot that
:func:`system_is_leading` is a heel strike, logged with :func:`system_approach_velocity`. All of
it reads a formulation only through ``system_foot_contact`` (penetration, approach velocity,
contact point), so a new formulation gets its events for free. A joint stop (:mod:`biped_sim.contact.stop`)
adds one event function, its penetration (the joint angle past its limit), after the feet's; its mode is a
row of the mode table after the feet's, updated with theirs (first: a latching stop's release reads its leg's
foot's mode before the feet's update); a latching stop adds one more, the other leg's foot's approach
velocity, whose zero ends that foot's strike and releases the latch.
"""

from __future__ import annotations

import numpy as np

from biped_sim.contact.registry import by_type
from biped_sim.contact.response import RECONTACT_TIME, ContactBuffers, update_contact_modes
from biped_sim.contact.stop import (
    FOOT,
    NOT_LATCHING,
    PARTNER,
    NoStops,
    Stops,
    stop_event_count,
    stop_penetration,
    stop_rate,
    update_stop_modes,
)
from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import system_foot_contact
from biped_sim.multibody.hinge import HingeStops


def event_count(system: tuple) -> int:
    """Number of event functions of ``system``: two per foot, one per joint stop, one per latching stop."""
    return 2 * int(system.foot_body.shape[0]) + stop_event_count(system.stops)


def contact_count(system: tuple) -> int:
    """Rows of ``system``'s contact-mode table: its feet, then its joint stops."""
    return int(system.foot_body.shape[0]) + int(system.stops.law.shape[0])


@kernel
def system_event_functions(y: np.ndarray, system: tuple, g: np.ndarray) -> None:
    """g[2 i] = penetration of foot i, g[2 i + 1] = its lead over its partner (1 without a partner);
    g[2 nf + s] = penetration of joint stop s; then, per latching stop, the approach velocity of the foot whose
    strike its release waits for (:mod:`biped_sim.contact.stop`)."""
    nf = system.foot_body.shape[0]
    for i in range(nf):
        delta, _, x_i = system_foot_contact(y, system, i)
        g[2 * i] = delta
        partner = system.foot_partner[i]
        g[2 * i + 1] = x_i - system_foot_contact(y, system, partner)[2] if partner >= 0 else 1.0
    stop_event_functions(y, system, system.stops, g)


@kernel
def _stop_events(y: np.ndarray, system: tuple, stops: Stops, g: np.ndarray) -> None:
    nf = system.foot_body.shape[0]
    k = 2 * nf + stops.law.shape[0]
    for s in range(stops.law.shape[0]):
        g[2 * nf + s] = stop_penetration(y, stops, s)[0]
        if stops.latch[s, FOOT] != NOT_LATCHING:
            g[k] = system_foot_contact(y, system, stops.latch[s, PARTNER])[1]
            k += 1


@kernel
def _no_stop_events(y: np.ndarray, system: tuple, stops: NoStops, g: np.ndarray) -> None:
    return None


stop_event_functions = by_type(
    "stop_event_functions", "stops", {Stops: _stop_events, HingeStops: _stop_events, NoStops: _no_stop_events}
)
stop_event_functions.__doc__ = """The joint stops' event functions after the feet's in ``g`` (see
:func:`system_event_functions`), of ``system`` whose ``stops`` they are (none for a
:class:`~biped_sim.contact.stop.NoStops`)."""


@kernel
def system_approach_velocity(y: np.ndarray, system: tuple, contact: int) -> float:
    """Approach velocity deltadot of a contact: a foot's [m/s], or a joint stop's after the feet [rad/s]."""
    nf = system.foot_body.shape[0]
    if contact >= nf:
        return stop_rate(y, system.stops, contact - nf)
    return system_foot_contact(y, system, contact)[1]


@kernel
def system_is_leading(y: np.ndarray, system: tuple, foot: int) -> bool:
    """Whether a foot's contact point is downhill of its partner's (a foot without a partner always leads)."""
    partner = system.foot_partner[foot]
    if partner < 0:
        return True
    return system_foot_contact(y, system, foot)[2] > system_foot_contact(y, system, partner)[2]


@kernel(by_symbol=True)  # at a start and at events
def system_update_modes(t: float, y: np.ndarray, system: tuple, modes: np.ndarray, contact: ContactBuffers) -> bool:
    """Scuffing guard and contact bookkeeping at an event at time t (feet, then joint stops); sets contact.onset
    (the feet's touchdowns); True when a mode changed."""
    system_event_functions(y, system, contact.gates)
    nf = system.foot_body.shape[0]
    for i in range(nf):
        contact.approach[i] = system_approach_velocity(y, system, i)
    stops_changed = False
    if system.stops.law.shape[0] > 0:  # first: a latch's release reads its foot's mode before the feet's update
        recontact = system.limits[RECONTACT_TIME]
        stops_changed = update_stop_modes(t, y, system.stops, modes, nf, recontact, contact.gates, contact.approach)
    changed = update_contact_modes(t, y, system, modes, contact)
    return changed or stops_changed
