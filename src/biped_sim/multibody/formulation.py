"""The formulation record: what the engine and post-processing take from one multibody formulation.

A formulation (planar absolute coordinates, spatial Euler parameters, ...) is one frozen
:class:`Formulation`: its system NamedTuple type, its compiled kernels (signatures in
``KERNEL_SIGNATURES``), its workspace, its post-processing :class:`Measures`, the names and
:class:`StateLayout` of its ODE state and its capabilities. Each formulation module builds its
record; :mod:`biped_sim.multibody.dispatch` registers it (one line) and generates the compiled
dispatch from the registry. What is the same for every formulation (the event functions, the
contact-mode update, heel-strike tests) is written once over the ``foot_contact`` kernel in
:mod:`biped_sim.multibody.events`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

# capability: TouchdownSection (the compliant limit cycle) can lift and project this formulation's states
COMPLIANT_LIMIT_CYCLE = "compliant_limit_cycle"

# the compiled kernels of a formulation and their parameters (all allocation-free):
KERNEL_SIGNATURES: dict[str, tuple[str, ...]] = {
    # ydot = f(t, y) for the current contact modes; work is the formulation's workspace
    "rhs": ("t", "y", "system", "modes", "work", "ydot"),
    # (penetration delta [m], approach velocity deltadot [m/s], contact point along the slope [m]) of a foot
    "foot_contact": ("y", "system", "foot"),
    # whether the walker fell (stops the integration): STANDING (0), or which limit it passed (contact.response codes)
    "fall": ("y", "system"),
    # (mechanical energy E = kinetic + potential + elastic [J], joint drift ||Phi|| [m]): the loops' blow-up checks
    "audit": ("y", "system", "modes", "work"),
}


# the per-sample measures compiled loops reach through ``dispatch.system_<name>`` (the Measures fields of that name)
MEASURE_SIGNATURES: dict[str, tuple[str, ...]] = {
    "contact": ("y", "system", "modes", "foot"),
    "mechanical_energy": ("y", "system", "modes"),
    "violation": ("y", "system"),
    "hip": ("y", "system"),
    "attitude": ("y", "system", "body"),
}


class Measures(NamedTuple):
    """What post-processing measures of one state ``y`` of a formulation (Python side, per sample).

    Every callable takes ``(y, system, ...)``; the compiled functions behind them are the ones the
    right-hand side uses (one source per equation). Those named in ``MEASURE_SIGNATURES`` are plain Python
    over compiled kernels (or kernels) that numba also compiles into the measure loops (``measure/loops.py``).
    """

    pitch: Callable[..., tuple[float, float]]  # (y, system, body): sagittal leg angle [rad] and rate [rad/s]
    mechanical_energy: Callable[..., tuple[float, float, float]]  # (y, system, modes): kinetic, potential, elastic
    violation: Callable[..., tuple[float, ...]]  # (y, system): one norm per entry of violation_names
    violation_names: tuple[str, ...]
    contact: Callable[..., tuple[float, ...]]  # (y, system, modes, foot): one value per entry of contact_names
    contact_names: tuple[str, ...]
    hip: Callable[..., tuple[float, ...]]  # (y, system): position of the hip (joint 0) in the slope frame
    attitude: Callable[..., tuple[float, float, float, float]] | None  # (y, system, body): pitch, roll, yaw, omega_z
    # (y, system, foot): where a foot's lowest point is in the ground plane, (x, z) [m]; spatial only (the step width)
    foot_point: Callable[..., tuple[float, float]] | None = None


@dataclass(frozen=True)
class StateLayout:
    """Where each quantity of an ODE state y = [q | qd | z | W_normal | W_friction] sits.

    q holds the system's ``base_coordinates`` (a floating base shared by the bodies, e.g. the minimal
    formulation's hip position; none for absolute coordinates), then ``len(coordinates)`` entries per
    body; qd the same rates in the same order; z ``len(bristles)`` friction states per foot, then the
    work dissipated by normal damping and by friction (integrated with the motion: the energy balance
    E(t) - E(0) + W(t) = 0 checks the run).
    """

    coordinates: tuple[str, ...]  # one body's coordinates, e.g. ("x", "y", "phi")
    rates: tuple[str, ...]  # one body's velocities, e.g. ("vx", "vy", "omega")
    bristles: tuple[str, ...]  # one foot's friction states, e.g. ("z",)
    n_bodies: int
    n_feet: int
    base_coordinates: tuple[str, ...] = ()  # the system's own coordinates before the bodies', e.g. ("x_hip", "y_hip")
    base_rates: tuple[str, ...] = ()
    n_stops: int = 0  # joint stops (contact.stop): with any, y ends with the work W_stop their damping dissipated
    n_elements: int = 0  # joint elements (contact.joint_element): with any, W_element (their work) before W_stop

    def __post_init__(self) -> None:
        if len(self.rates) != len(self.coordinates) or len(self.base_rates) != len(self.base_coordinates):
            raise ValueError("a body and the base need one rate per coordinate")

    @property
    def n_coordinates(self) -> int:
        """Length of q (and of qd): the generalized coordinates."""
        return len(self.base_coordinates) + len(self.coordinates) * self.n_bodies

    @property
    def positions(self) -> slice:
        """q: every generalized coordinate in y."""
        return slice(0, self.n_coordinates)

    @property
    def velocities(self) -> slice:
        """qd: every generalized velocity in y."""
        return slice(self.n_coordinates, 2 * self.n_coordinates)

    def position(self, body: int) -> slice:
        """Body ``body``'s coordinates in y."""
        width = len(self.coordinates)
        start = len(self.base_coordinates) + width * body
        return slice(start, start + width)

    def velocity(self, body: int) -> slice:
        """Body ``body``'s velocities in y."""
        width = len(self.rates)
        start = self.n_coordinates + len(self.base_rates) + width * body
        return slice(start, start + width)

    def coordinate(self, body: int, name: str) -> int:
        """Index in y of one named coordinate of a body (e.g. ``"phi"``)."""
        return self.position(body).start + self.coordinates.index(name)

    def rate(self, body: int, name: str) -> int:
        """Index in y of one named velocity of a body (e.g. ``"omega"``)."""
        return self.velocity(body).start + self.rates.index(name)

    @property
    def first_bristle(self) -> int:
        """Index in y of foot 0's first friction state."""
        return 2 * self.n_coordinates

    def bristle(self, foot: int) -> slice:
        """Foot ``foot``'s friction states in y."""
        width = len(self.bristles)
        start = self.first_bristle + width * foot
        return slice(start, start + width)

    def bristle_index(self) -> np.ndarray:
        """(n_feet, len(bristles)) int64: the indices in y of each foot's friction states."""
        rows = [range(self.bristle(foot).start, self.bristle(foot).stop) for foot in range(self.n_feet)]
        return np.array(rows, dtype=np.int64).reshape(self.n_feet, len(self.bristles))

    @property
    def work_normal(self) -> int:
        """Index in y of the work dissipated by normal damping."""
        return self.first_bristle + len(self.bristles) * self.n_feet

    @property
    def work_friction(self) -> int:
        """Index in y of the work dissipated by friction."""
        return self.work_normal + 1

    @property
    def work_element(self) -> int | None:
        """Index in y of the work dissipated by the joint elements (None without elements)."""
        return self.work_friction + 1 if self.n_elements else None

    @property
    def work_stop(self) -> int | None:
        """Index in y of the work dissipated by the joint stops' damping (None without stops): y's last entry."""
        return self.size - 1 if self.n_stops else None

    @property
    def size(self) -> int:
        """Length of y."""
        return self.work_friction + 1 + (1 if self.n_elements else 0) + (1 if self.n_stops else 0)

    def names(self, body_names: list[str], foot_names: list[str]) -> list[str]:
        """Names of the entries of y, in order (``x_stance``, ..., ``W_normal``, ``W_friction``[, ``W_element``]
        [, ``W_stop``])."""
        coords = [*self.base_coordinates, *(f"{axis}_{body}" for body in body_names for axis in self.coordinates)]
        rates = [*self.base_rates, *(f"{axis}_{body}" for body in body_names for axis in self.rates)]
        bristles = [f"{state}_{foot}" for foot in foot_names for state in self.bristles]
        joints = (["W_element"] if self.n_elements else []) + (["W_stop"] if self.n_stops else [])
        return coords + rates + bristles + ["W_normal", "W_friction"] + joints


@dataclass(frozen=True)
class Formulation:
    """One multibody formulation, as the engine interface and post-processing see it.

    The kernel fields are compiled functions with the parameters in ``KERNEL_SIGNATURES``; numba
    dispatches the loops' ``system_*`` calls to them by the type of ``system`` (``system_type``).
    """

    name: str
    system_type: type
    rhs: Callable[..., None]
    foot_contact: Callable[..., tuple[float, float, float]]
    fall: Callable[..., int]
    audit: Callable[..., tuple[float, float]]
    make_workspace: Callable[[Any], tuple]  # (system) -> the right-hand side's buffers (a NamedTuple of arrays)
    measures: Measures
    coordinates: tuple[str, ...]  # see StateLayout
    rates: tuple[str, ...]
    bristles: tuple[str, ...]
    capabilities: frozenset[str] = frozenset()
    base_coordinates: tuple[str, ...] = ()  # see StateLayout
    base_rates: tuple[str, ...] = ()
    # (y, system, impulse) -> the state just after an impulse [px, py] [N s] (slope frame) on the hip: positions
    # unchanged, rates jumped consistently with the constraints (simulation.pushes); None: no pushes
    hip_impulse: Callable[..., np.ndarray] | None = None

    def layout(self, n_bodies: int, n_feet: int, n_stops: int = 0, n_elements: int = 0) -> StateLayout:
        """The state layout of a system of this formulation with ``n_bodies`` bodies, ``n_feet`` feet, ``n_stops``
        joint stops and ``n_elements`` joint elements."""
        return StateLayout(
            self.coordinates, self.rates, self.bristles, n_bodies, n_feet, self.base_coordinates, self.base_rates,
            n_stops, n_elements,
        )  # fmt: skip

    def layout_of(self, system: Any) -> StateLayout:
        """The state layout of ``system``."""
        return self.layout(
            int(system.body_mass.shape[0]), int(system.foot_body.shape[0]), int(system.stops.law.shape[0]),
            int(system.elements.law.shape[0]),
        )  # fmt: skip

    def state_names(self, body_names: list[str], foot_names: list[str]) -> list[str]:
        """Names of the ODE state entries of a walker with these bodies and feet (and no joint stops), in order."""
        return self.layout(len(body_names), len(foot_names)).names(body_names, foot_names)

    def supports(self, capability: str) -> bool:
        """Whether this formulation has ``capability`` (e.g. ``COMPLIANT_LIMIT_CYCLE``)."""
        return capability in self.capabilities


def impulsive_velocity_change(minv: np.ndarray, phi_q: np.ndarray, impulse: np.ndarray) -> np.ndarray:
    """The rate jump dqd of a constrained system under the generalized impulse ``impulse`` (Python side).

    Solves [M Phi_q^T; Phi_q 0] [dqd; mu] = [impulse; 0] by its Schur complement:
    (Phi_q M^-1 Phi_q^T) mu = Phi_q M^-1 impulse, dqd = M^-1 (impulse - Phi_q^T mu). Then Phi_q dqd = 0: the
    constraint velocities Phidot = Phi_q qd are unchanged by the jump (and Phi too: an impulse moves nothing),
    and mu is the joints' impulse. ``minv``: M^-1 (n, n); ``phi_q``: the constraint Jacobian (m, n).
    """
    free = minv @ impulse
    if phi_q.shape[0] == 0:
        return free
    minv_phi_t = minv @ phi_q.T
    mu = np.linalg.solve(phi_q @ minv_phi_t, phi_q @ free)
    return free - minv_phi_t @ mu
