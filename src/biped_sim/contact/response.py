"""The contact response every formulation shares: one source per contact equation (MODEL.md 3, 4).

A formulation computes the geometry of its feet (penetration delta, approach velocity deltadot, slip,
lead over the partner foot); what the ground does with it is written once, here:

* the per-foot discrete mode table ``modes[i]`` = (ARMED, TOUCHING, IMPACT_SPEED) and the indices of
  the kernels' ``switches`` and ``limits`` vectors;
* :func:`normal_response`: the normal force of the selected law with the approach velocity
  remembered at touchdown (floored) and the power its damping dissipates;
* :func:`update_contact_modes`: the scuffing guard's arming rule (:func:`guard_arms`), touchdown and
  lift-off bookkeeping, and the touchdown marks that the integrator turns into heel strikes, with
  its per-foot buffers :class:`ContactBuffers` (part of every formulation's workspace).

Every function is compiled and allocation-free; ``system`` is any formulation's system NamedTuple
(numba specialises on its type), read through the fields of :class:`ContactSystem`.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np
from numba import njit

from biped_sim.contact.friction import LUGRE
from biped_sim.contact.normal import elastic_energy, elastic_force, normal_force

# columns of the per-foot discrete mode table
ARMED, TOUCHING, IMPACT_SPEED = 0, 1, 2
N_MODE_COLUMNS = 3
# entries of the kernels' switches vector (int64)
NORMAL_MODEL, FRICTION_MODEL, SCUFFING_GUARD = 0, 1, 2
# entries of the kernels' limits vector: impact velocity floor [m/s], fall hip height [m], fall leg angle [rad]
IMPACT_FLOOR, FALL_HIP_HEIGHT, FALL_LEG_ANGLE = 0, 1, 2
# onset marks written by update_contact_modes
TOUCHDOWN = 1  # the foot touched down and no other foot of its body was or did: one heel strike per body
_WAS_TOUCHING = 2  # transient, inside one update


class ContactSystem(Protocol):
    """The fields of a formulation's system that the contact response reads."""

    foot_body: np.ndarray  # (nf,) int64
    normal_params: np.ndarray
    friction_params: np.ndarray
    switches: np.ndarray  # (3,) int64: NORMAL_MODEL, FRICTION_MODEL, SCUFFING_GUARD
    limits: np.ndarray  # (3,): IMPACT_FLOOR, FALL_HIP_HEIGHT, FALL_LEG_ANGLE


class ContactBuffers(NamedTuple):
    """Per-foot buffers of the mode update, part of every formulation's workspace (allocated once)."""

    onset: np.ndarray  # (nf,) int64: TOUCHDOWN marks written by update_contact_modes
    gates: np.ndarray  # (2 nf,) the event functions at the update: penetration, lead over the partner
    approach: np.ndarray  # (nf,) the approach velocities at the update
    bristles: np.ndarray  # (nf, k) int64: indices in y of each foot's k friction (LuGre bristle) states


def make_contact_buffers(bristles: np.ndarray) -> ContactBuffers:
    """Allocate the buffers for the feet whose bristle-state indices are the rows of ``bristles``."""
    nf = bristles.shape[0]
    return ContactBuffers(np.zeros(nf, dtype=np.int64), np.zeros(2 * nf), np.zeros(nf), bristles.astype(np.int64))


@njit(cache=True)
def is_loaded(modes: np.ndarray, i: int, delta: float) -> bool:
    """Whether the ground pushes on foot i: it is armed (scuffing guard) and penetrates."""
    return modes[i, ARMED] > 0.5 and delta > 0.0


@njit(cache=True)
def normal_response(
    model: int, npar: np.ndarray, floor: float, modes: np.ndarray, i: int, delta: float, delta_dot: float
) -> tuple[float, float]:
    """(F_N, P_normal) of a loaded foot i.

    F_N is the law number ``model`` with parameters ``npar`` (the system's ``switches[NORMAL_MODEL]``
    and ``normal_params``: :func:`~biped_sim.contact.normal.normal_force`) with the approach velocity
    deltadot^- remembered at touchdown (the current deltadot before the touchdown event registers),
    floored at ``floor`` (``limits[IMPACT_FLOOR]``) so that the Hunt-Crossley-type damping
    chi deltadot / deltadot^- stays bounded for grazing contacts. P_normal = (F_N - K delta^n) deltadot
    is the power lost in the normal damping (MODEL.md 4): the elastic part K delta^n is stored, not
    lost. It takes the system's arrays, not the system: inside the right-hand side every array of a
    NamedTuple handed to a function costs a reference-count update.
    """
    impact = modes[i, IMPACT_SPEED] if modes[i, TOUCHING] > 0.5 else delta_dot
    if impact < floor:
        impact = floor
    f_n = normal_force(model, delta, delta_dot, impact, npar)
    return f_n, (f_n - elastic_force(delta, npar)) * delta_dot


@njit(cache=True)
def stored_energy(system: ContactSystem, modes: np.ndarray, i: int, delta: float) -> float:
    """Energy K delta^(n+1) / (n+1) in the contact spring of foot i while it is loaded, else 0."""
    return elastic_energy(delta, system.normal_params) if is_loaded(modes, i, delta) else 0.0


@njit(cache=True)
def guard_arms(guard: bool, armed: bool, delta: float, lead: float) -> bool:
    """The scuffing guard's arming rule (MODEL.md 3): whether a foot is armed after an event.

    A foot is armed once it is ahead of its partner (lead > 0) and not in the ground (delta <= 0), and
    disarmed when it is in the air (delta <= 0) behind its partner (lead <= 0); in between it keeps
    its state, so the swing foot's mid-stance dip below the ground is ignored. Without the guard
    every foot is always armed. The sides are those of the event functions (> 0 and <= 0): a foot
    that leaves the ground at an event located exactly at delta = 0 is armed there.
    """
    if not guard:
        return True
    if armed:
        return not (delta <= 0.0 and lead <= 0.0)
    return delta <= 0.0 and lead > 0.0


@njit(cache=True)
def _claim_touchdown(foot_body: np.ndarray, onset: np.ndarray, i: int) -> None:
    """Mark foot i's touchdown unless another foot of its body is touching or touched down already."""
    for j in range(onset.shape[0]):
        if j != i and foot_body[j] == foot_body[i] and onset[j] > 0:
            return
    onset[i] = TOUCHDOWN


@njit(cache=True)
def update_contact_modes(y: np.ndarray, system: ContactSystem, modes: np.ndarray, contact: ContactBuffers) -> bool:
    """Apply the scuffing guard and contact onset/separation bookkeeping at an event (MODEL.md 3).

    Reads the feet's penetration, lead and approach velocity from ``contact.gates`` and
    ``contact.approach``. A touchdown remembers the approach velocity deltadot^- (IMPACT_SPEED) and
    relaxes the foot's LuGre bristles (sets its states ``contact.bristles[i]`` of y to 0).
    ``contact.onset[i]`` = TOUCHDOWN marks a touchdown when no other foot of the same body was
    touching or touched down in this update (the feet of one leg land together and make one heel
    strike); 0 otherwise. Returns True when any mode changed (the right-hand side then changes too).
    """
    nf = modes.shape[0]
    onset, gates = contact.onset, contact.gates
    changed = False
    guard = system.switches[SCUFFING_GUARD] != 0
    lugre = system.switches[FRICTION_MODEL] == LUGRE
    for i in range(nf):
        onset[i] = _WAS_TOUCHING if modes[i, TOUCHING] > 0.5 else 0
    for i in range(nf):
        delta = gates[2 * i]
        armed = modes[i, ARMED] > 0.5
        new_armed = guard_arms(guard, armed, delta, gates[2 * i + 1])
        touching = new_armed and delta > 0.0
        was_touching = modes[i, TOUCHING] > 0.5
        if touching and not was_touching:
            modes[i, IMPACT_SPEED] = contact.approach[i]
            _claim_touchdown(system.foot_body, onset, i)
            if lugre:
                for k in range(contact.bristles.shape[1]):
                    y[contact.bristles[i, k]] = 0.0
        if touching != was_touching or new_armed != armed:
            changed = True
        modes[i, ARMED] = 1.0 if new_armed else 0.0
        modes[i, TOUCHING] = 1.0 if touching else 0.0
    for i in range(nf):
        if onset[i] == _WAS_TOUCHING:
            onset[i] = 0
    return changed
