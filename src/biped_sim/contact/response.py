"""The contact response every formulation shares: one source per contact equation (MODEL.md 3, 4).

A formulation computes the geometry of its feet (penetration delta, approach velocity deltadot, slip,
lead over the partner foot); what the ground does with it is written once, here:

* the per-foot discrete mode table ``modes[i]`` = (ARMED, TOUCHING, IMPACT_SPEED, LIFTOFF_TIME) and the
  indices of the kernels' ``switches`` and ``limits`` vectors;
* :func:`arc_contact`, :func:`arc_forces`, :func:`arc_energy`: a foot arc against the ground (penetration,
  approach and slip velocities, contact point; the forces summed over the ground's contact features;
  their spring energy): the one place where the ground enters, resolved at compile time from the type
  of the system's ``ground`` (:mod:`.ground`: a flat run compiles only the plane's arithmetic);
* :func:`ground_forces`: the normal and friction forces on a loaded foot and their dissipation;
* :func:`normal_response`: the normal force of the selected law with the approach velocity
  remembered at touchdown (floored) and the power its damping dissipates;
* :func:`update_contact_modes`: the scuffing guard's arming rule (:func:`guard_arms`), touchdown and
  lift-off bookkeeping with the impact-velocity memory (:func:`remembered_impact_speed`), and the
  touchdown marks that the integrator turns into heel strikes, with its per-foot buffers
  :class:`ContactBuffers` (part of every formulation's workspace).

Every function is compiled and allocation-free; ``system`` is any formulation's system NamedTuple
(numba specialises on its type), read through the fields of :class:`ContactSystem`.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from biped_sim.contact.friction import LUGRE, friction_force, lugre_bristle_rate, lugre_friction
from biped_sim.contact.ground import FlatGround, ProfileGround, ground_contact, ground_contacts, ground_window
from biped_sim.contact.normal import elastic_energy, elastic_force, normal_force
from biped_sim.contact.registry import by_type
from biped_sim.kernel import kernel

# columns of the per-foot discrete mode table (LIFTOFF_TIME: when the foot last left the ground [s])
ARMED, TOUCHING, IMPACT_SPEED, LIFTOFF_TIME = 0, 1, 2, 3
N_MODE_COLUMNS = 4
# entries of the kernels' switches vector (int64)
NORMAL_MODEL, FRICTION_MODEL, SCUFFING_GUARD = 0, 1, 2
# entries of the kernels' limits vector: impact velocity floor [m/s], fall hip height [m], fall leg angle [rad],
# re-contact time [s] (0: every touchdown is a new impact; see remembered_impact_speed)
IMPACT_FLOOR, FALL_HIP_HEIGHT, FALL_LEG_ANGLE, RECONTACT_TIME = 0, 1, 2, 3
N_LIMITS = 4
# what a formulation's fall kernel returns: standing, or which fall limit the state passed (BODY_TOO_FAR + b: body b,
# off the legs, past its own fall angle)
STANDING, HIP_TOO_LOW, LEG_TOO_FAR, BODY_TOO_FAR = 0, 1, 2, 3
# a system's body_falls: none (every body falls past limits[FALL_LEG_ANGLE] as a leg), or a row per body: its fall
# angle [rad] and its code (LEG_TOO_FAR, or BODY_TOO_FAR + b off the legs), an exact small integer
NO_BODY_FALLS = np.zeros((0, 2))
# onset marks written by update_contact_modes
TOUCHDOWN = 1  # the foot touched down and no other foot of its body was or did: one heel strike per body
_WAS_TOUCHING = 2  # transient, inside one update


class ContactSystem(Protocol):
    """The fields of a formulation's system that the contact response reads."""

    foot_body: np.ndarray  # (nf,) int64
    normal_params: np.ndarray
    friction_params: np.ndarray
    switches: np.ndarray  # (3,) int64: NORMAL_MODEL, FRICTION_MODEL, SCUFFING_GUARD
    limits: np.ndarray  # (4,): IMPACT_FLOOR, FALL_HIP_HEIGHT, FALL_LEG_ANGLE, RECONTACT_TIME


class ContactBuffers(NamedTuple):
    """Per-foot buffers of the mode update, part of every formulation's workspace (allocated once)."""

    onset: np.ndarray  # (nf,) int64: TOUCHDOWN marks written by update_contact_modes
    gates: np.ndarray  # the event functions at the update: each foot's penetration and lead over its partner; stops
    approach: np.ndarray  # (nf,) the approach velocities at the update
    bristles: np.ndarray  # (nf, k) int64: indices in y of each foot's k friction (LuGre bristle) states


def make_contact_buffers(bristles: np.ndarray, n_stop_events: int = 0) -> ContactBuffers:
    """Allocate the buffers for the feet whose bristle-state indices are the rows of ``bristles`` and the joint
    stops' ``n_stop_events`` event functions (:mod:`.stop`: one per stop, one more per latching stop)."""
    nf = bristles.shape[0]
    gates = np.zeros(2 * nf + n_stop_events)
    return ContactBuffers(np.zeros(nf, dtype=np.int64), gates, np.zeros(nf), bristles.astype(np.int64))


@kernel
def _flat_arc_contact(
    rx: float, ry: float, vx: float, vy: float, omega: float, cx: float, cy: float, radius: float, ground: FlatGround
) -> tuple[float, float, float, float, float, float]:
    px = cx
    py = cy - radius
    dx, dy = px - rx, py - ry
    vpx = vx - omega * dy
    vpy = vy + omega * dx
    return -py, -vpy, vpx, px, dx, dy


@kernel
def _material_point(
    rx: float, ry: float, vx: float, vy: float, omega: float, px: float, py: float, nx: float, ny: float
) -> tuple[float, float, float, float]:
    """(delta_dot, slip, dx, dy) at contact point P with normal n: -v_P.n, v_P.t with t = (n_y, -n_x), P - r."""
    dx, dy = px - rx, py - ry
    vpx = vx - omega * dy
    vpy = vy + omega * dx
    return -(vpx * nx + vpy * ny), vpx * ny - vpy * nx, dx, dy


@kernel
def _profile_arc_contact(
    rx: float, ry: float, vx: float, vy: float, omega: float, cx: float, cy: float, radius: float, ground: ProfileGround
) -> tuple[float, float, float, float, float, float]:
    delta, px, py, nx, ny = ground_contact(cx, cy, radius, ground.vertices, ground.ends)
    delta_dot, slip, dx, dy = _material_point(rx, ry, vx, vy, omega, px, py, nx, ny)
    return delta, delta_dot, slip, px, dx, dy


arc_contact = by_type("arc_contact", "ground", {FlatGround: _flat_arc_contact, ProfileGround: _profile_arc_contact})
arc_contact.__doc__ = """A foot arc of centre (cx, cy) and ``radius`` against ``ground`` (MODEL.md 3; :mod:`.ground`).

(rx, ry) is a reference point of the foot's body, (vx, vy) its velocity and ``omega`` the body's
angular velocity: the planar formulation passes the centre of mass, the minimal one the hip.
Returns, for the deepest contact feature, (delta, delta_dot, slip, x_contact, dx, dy): penetration,
approach velocity -v_P.n, slip velocity v_P.t of the material point at P = C - R n, the contact
point's position along the slope, and P - r (the lever arm of the contact force about the reference
point). On the flat ground: the line y = 0, normal (0, 1), delta = R - C_y.
"""


@kernel
def _flat_arc_forces(
    motion: tuple[float, float, float, float, float], cx: float, cy: float, radius: float, ground: FlatGround,
    arc: tuple[float, float, float, float, float, float], switches: np.ndarray, npar: np.ndarray, fpar: np.ndarray,
    floor: float, modes: np.ndarray, i: int, z: float,
) -> tuple[float, float, float, float, float, float, float, float]:  # fmt: skip
    delta, delta_dot, slip, _, dx, dy = arc
    f_n, f_t, z_dot, p_normal, p_friction = ground_forces(
        switches, npar, fpar, floor, modes, i, delta, delta_dot, slip, z
    )
    return f_t, f_n, dx * f_n - dy * f_t, z_dot, p_normal, p_friction, f_n, f_t


@kernel
def _profile_arc_forces(
    motion: tuple[float, float, float, float, float], cx: float, cy: float, radius: float, ground: ProfileGround,
    arc: tuple[float, float, float, float, float, float], switches: np.ndarray, npar: np.ndarray, fpar: np.ndarray,
    floor: float, modes: np.ndarray, i: int, z: float,
) -> tuple[float, float, float, float, float, float, float, float]:  # fmt: skip
    rx, ry, vx, vy, omega = motion
    vertices, ends, lugre = ground.vertices, ground.ends, switches[FRICTION_MODEL] == LUGRE
    z_dot = lugre_bristle_rate(arc[2], z, fpar) if lugre and is_loaded(modes, i, arc[0]) else 0.0
    f_x = f_y = torque = p_normal = p_friction = f_normal = f_tangent = 0.0
    first, count = ground_window(cx, radius, vertices)
    for f in range(count):
        depth, px, py, nx, ny, sign = ground_contacts(cx, cy, radius, vertices, ends, first, count, f)
        if not is_loaded(modes, i, depth):
            continue
        depth_dot, v_t, dx, dy = _material_point(rx, ry, vx, vy, omega, px, py, nx, ny)
        f_n, p_n = normal_response(switches[NORMAL_MODEL], npar, floor, modes, i, depth, depth_dot)
        if lugre:
            f_t = lugre_friction(v_t, z, z_dot, f_n, fpar)
        else:
            f_t = friction_force(switches[FRICTION_MODEL], v_t, f_n, fpar)
        f_n, f_t, p_n = sign * f_n, sign * f_t, sign * p_n  # a valley's corner term is subtracted
        fx_f, fy_f = f_n * nx + f_t * ny, f_n * ny - f_t * nx
        f_x += fx_f
        f_y += fy_f
        torque += dx * fy_f - dy * fx_f
        p_normal += p_n
        p_friction += -f_t * v_t
        f_normal += f_n
        f_tangent += f_t
    return f_x, f_y, torque, z_dot, p_normal, p_friction, f_normal, f_tangent


arc_forces = by_type("arc_forces", "ground", {FlatGround: _flat_arc_forces, ProfileGround: _profile_arc_forces})
arc_forces.__doc__ = """Contact force on a foot arc against ``ground``, summed over its contact features.

``motion`` = (rx, ry, vx, vy, omega) and (cx, cy, radius) as for :func:`arc_contact`, whose result is
``arc``; the law arrays and ``z`` as for :func:`ground_forces`. Returns (F_x, F_y, torque, zdot,
P_normal, P_friction, F_N, F_T): the force F_N n + F_T t of each loaded feature (the corner of a valley
counts negatively: :mod:`.ground`) and its moment about r, the powers as in :func:`ground_forces`
(every feature uses the foot's impact speed: one contact mode per foot; the LuGre bristle follows the
deepest feature), and the summed normal and friction forces. On the flat ground it is
:func:`ground_forces` on ``arc`` with n = (0, 1): (F_T, F_N, dx F_N - dy F_T, ...).
"""


@kernel
def _flat_arc_energy(system: ContactSystem, modes: np.ndarray, i: int, cx: float, cy: float, radius: float,
                     ground: FlatGround) -> float:  # fmt: skip
    return stored_energy(system, modes, i, -(cy - radius))


@kernel
def _profile_arc_energy(system: ContactSystem, modes: np.ndarray, i: int, cx: float, cy: float, radius: float,
                        ground: ProfileGround) -> float:  # fmt: skip
    first, count = ground_window(cx, radius, ground.vertices)
    elastic = 0.0
    for f in range(count):
        feature = ground_contacts(cx, cy, radius, ground.vertices, ground.ends, first, count, f)
        elastic += feature[5] * stored_energy(system, modes, i, feature[0])
    return elastic


arc_energy = by_type("arc_energy", "ground", {FlatGround: _flat_arc_energy, ProfileGround: _profile_arc_energy})
arc_energy.__doc__ = (
    """Energy in the contact springs of foot i, arc (cx, cy, radius), against ``ground``, summed over features."""
)


@kernel
def ground_forces(
    switches: np.ndarray,
    npar: np.ndarray,
    fpar: np.ndarray,
    floor: float,
    modes: np.ndarray,
    i: int,
    delta: float,
    delta_dot: float,
    slip: float,
    z: float,
) -> tuple[float, float, float, float, float]:
    """(F_N, F_T, zdot, P_normal, P_friction) on foot i, zero unless it is loaded (:func:`is_loaded`).

    F_N and the power P_normal lost in the normal damping come from :func:`normal_response`; F_T from
    the friction law ``switches[FRICTION_MODEL]`` (LuGre with bristle deflection ``z``, whose rate is
    zdot); P_friction = -F_T v_t is the power friction takes (for LuGre this includes the small,
    load-dependent bristle energy, which is not a potential). Arrays, not the system: see
    :func:`normal_response`.
    """
    f_n = f_t = z_dot = p_normal = p_friction = 0.0  # one return: numba then elides the reference counting
    if is_loaded(modes, i, delta):
        f_n, p_normal = normal_response(switches[NORMAL_MODEL], npar, floor, modes, i, delta, delta_dot)
        if switches[FRICTION_MODEL] == LUGRE:
            z_dot = lugre_bristle_rate(slip, z, fpar)
            f_t = lugre_friction(slip, z, z_dot, f_n, fpar)
        else:
            f_t = friction_force(switches[FRICTION_MODEL], slip, f_n, fpar)
        p_friction = -f_t * slip
    return f_n, f_t, z_dot, p_normal, p_friction


@kernel
def is_loaded(modes: np.ndarray, i: int, delta: float) -> bool:
    """Whether the ground pushes on foot i: it is armed (scuffing guard) and penetrates."""
    return modes[i, ARMED] > 0.5 and delta > 0.0


@kernel
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


@kernel
def stored_energy(system: ContactSystem, modes: np.ndarray, i: int, delta: float) -> float:
    """Energy K delta^(n+1) / (n+1) in the contact spring of foot i while it is loaded, else 0."""
    return elastic_energy(delta, system.normal_params) if is_loaded(modes, i, delta) else 0.0


@kernel
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


@kernel
def _claim_touchdown(foot_body: np.ndarray, onset: np.ndarray, i: int) -> None:
    """Mark foot i's touchdown unless another foot of its body is touching or touched down already."""
    for j in range(onset.shape[0]):
        if j != i and foot_body[j] == foot_body[i] and onset[j] > 0:
            return
    onset[i] = TOUCHDOWN


@kernel
def remembered_impact_speed(
    remembered: float, liftoff_time: float, t: float, approach: float, recontact_time: float
) -> float:
    """The impact velocity deltadot^- a foot remembers after touching down at time ``t`` with ``approach``.

    The Hunt-Crossley family (Hunt and Crossley 1975; Lankarani and Nikravesh 1990; Flores et al. 2011)
    takes its hysteresis damping chi K delta^n deltadot / deltadot^- from the restitution e of one impact,
    deltadot^- being the approach velocity at the start of that impact: a property of the impact, not of
    each sign change of delta. A touchdown less than ``recontact_time`` after the same foot's lift-off
    (a rebound of the impact or a micro-separation, far shorter than a swing) continues the impact: the
    foot keeps the larger of the remembered and the new approach velocity (continuous as a rebound
    appears with zero flight and zero approach velocity, and a harder re-impact counts with its own
    speed). After a longer flight, or with ``recontact_time`` = 0 (``contact.impact_memory: touchdown``),
    the touchdown is a new impact and remembers ``approach``.
    """
    if t - liftoff_time < recontact_time and remembered > approach:
        return remembered
    return approach


@kernel
def update_contact_modes(
    t: float, y: np.ndarray, system: ContactSystem, modes: np.ndarray, contact: ContactBuffers
) -> bool:
    """Apply the scuffing guard and contact onset/separation bookkeeping at an event at time ``t`` (MODEL.md 3).

    Reads the feet's penetration, lead and approach velocity from ``contact.gates`` and
    ``contact.approach``. A touchdown remembers the approach velocity deltadot^- (IMPACT_SPEED, by
    :func:`remembered_impact_speed`) and relaxes the foot's LuGre bristles (sets its states
    ``contact.bristles[i]`` of y to 0); a lift-off records its time (LIFTOFF_TIME).
    ``contact.onset[i]`` = TOUCHDOWN marks a touchdown when no other foot of the same body was
    touching or touched down in this update (the feet of one leg land together and make one heel
    strike); 0 otherwise. Returns True when any mode changed (the right-hand side then changes too). The
    feet's modes are the table's first rows (the joint stops' follow: :mod:`biped_sim.contact.stop`).
    """
    nf = system.foot_body.shape[0]
    onset, gates = contact.onset, contact.gates
    changed = False
    guard = system.switches[SCUFFING_GUARD] != 0
    lugre = system.switches[FRICTION_MODEL] == LUGRE
    recontact = system.limits[RECONTACT_TIME]
    for i in range(nf):
        onset[i] = _WAS_TOUCHING if modes[i, TOUCHING] > 0.5 else 0
    for i in range(nf):
        delta = gates[2 * i]
        armed = modes[i, ARMED] > 0.5
        new_armed = guard_arms(guard, armed, delta, gates[2 * i + 1])
        touching = new_armed and delta > 0.0
        was_touching = modes[i, TOUCHING] > 0.5
        if touching and not was_touching:
            modes[i, IMPACT_SPEED] = remembered_impact_speed(
                modes[i, IMPACT_SPEED], modes[i, LIFTOFF_TIME], t, contact.approach[i], recontact
            )
            _claim_touchdown(system.foot_body, onset, i)
            if lugre:
                for k in range(contact.bristles.shape[1]):
                    y[contact.bristles[i, k]] = 0.0
        elif was_touching and not touching:
            modes[i, LIFTOFF_TIME] = t
        if touching != was_touching or new_armed != armed:
            changed = True
        modes[i, ARMED] = 1.0 if new_armed else 0.0
        modes[i, TOUCHING] = 1.0 if touching else 0.0
    for i in range(nf):
        if onset[i] == _WAS_TOUCHING:
            onset[i] = 0
    return changed


@kernel
def body_fall(angle: float, b: int, limits: np.ndarray, body_falls: np.ndarray) -> int:
    """STANDING, or the fall code of body b at ``angle`` from the slope normal: past limits[FALL_LEG_ANGLE]
    (LEG_TOO_FAR) when ``body_falls`` is empty (NO_BODY_FALLS), else past its own row's angle (its row's code)."""
    if body_falls.shape[0] == 0:
        return LEG_TOO_FAR if abs(angle) > limits[FALL_LEG_ANGLE] else STANDING
    return int(body_falls[b, 1]) if abs(angle) > body_falls[b, 0] else STANDING
