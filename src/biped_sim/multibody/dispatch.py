"""The engine interface: what a multibody formulation provides to the integrator loops.

The compiled loops call the ``system_*`` functions below; numba resolves each call at compile
time from the type of ``system`` (a NamedTuple class), so one loop source serves every
formulation (planar now, spatial later) and each specialisation is cached on disk. A new
formulation registers its kernels in ``_KERNELS`` with one line.

Interface of a formulation (all compiled, allocation-free):

* ``rhs(t, y, system, modes, work, ydot)``: state derivative for the current contact modes;
* ``event_functions(y, system, g)``: continuous functions whose sign changes are events;
* ``update_modes(y, system, modes, work) -> bool``: discrete update at an event (sets work.onset);
* ``has_fallen(y, system) -> bool``;
* ``approach_velocity(y, system, foot) -> float`` and ``is_leading(y, system, foot) -> bool``
  (the touchdown of a leading foot is a heel strike);
* Python side: ``make_workspace(system)`` (a NamedTuple with at least an int64 ``onset`` array,
  one entry per foot), ``event_count(system)``, and ``measures``: a :class:`Measures` of the
  per-sample measurements that :mod:`biped_sim.measure` takes of a run (kinematics,
  energy, constraint violation, contact channels), so that post-processing serves every formulation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import overload

from biped_sim.multibody import planar, spatial


class Measures(NamedTuple):
    """What post-processing measures of one state ``y`` of a formulation (Python side, per sample).

    Every callable takes ``(y, system, ...)``; the compiled functions behind them are the ones the
    right-hand side uses (one source per equation).
    """

    contact_x: Callable[..., float]  # (y, system, foot): contact point along the slope [m]
    pitch: Callable[..., tuple[float, float]]  # (y, system, body): sagittal leg angle [rad] and rate [rad/s]
    mechanical_energy: Callable[..., tuple[float, float, float]]  # (y, system, modes): kinetic, potential, elastic
    violation: Callable[..., tuple[float, ...]]  # (y, system): one norm per entry of violation_names
    violation_names: tuple[str, ...]
    contact: Callable[..., tuple[float, ...]]  # (y, system, modes, foot): one value per entry of contact_names
    contact_names: tuple[str, ...]
    hip: Callable[..., tuple[float, ...]]  # (y, system): position of the hip (joint 0) in the slope frame
    attitude: Callable[..., tuple[float, float, float, float]] | None  # (y, system, body): pitch, roll, yaw, omega_z


@njit(cache=True)
def _planar_approach_velocity(y: np.ndarray, system: planar.PlanarSystem, foot: int) -> float:
    return planar.foot_kinematics(y, system, foot)[1]


@njit(cache=True)
def _planar_is_leading(y: np.ndarray, system: planar.PlanarSystem, foot: int) -> bool:
    partner = system.foot_partner[foot]
    if partner < 0:
        return True
    return planar.foot_kinematics(y, system, foot)[3] > planar.foot_kinematics(y, system, partner)[3]


def _planar_pitch(y: np.ndarray, system: planar.PlanarSystem, body: int) -> tuple[float, float]:
    nb = system.body_mass.shape[0]
    return float(y[3 * body + 2]), float(y[3 * nb + 3 * body + 2])


def _planar_contact(y: np.ndarray, system: planar.PlanarSystem, modes: np.ndarray, foot: int) -> tuple[float, ...]:
    f_n, f_t, _, _, _, delta, _, slip, _, _ = planar.foot_forces(y, system, modes, foot)
    return delta, f_n, f_t, slip


def _planar_hip(y: np.ndarray, system: planar.PlanarSystem) -> tuple[float, ...]:
    b = int(system.joint_bodies[0, 0])
    sx, sy = system.joint_points[0, 0], system.joint_points[0, 1]
    c, s = math.cos(y[3 * b + 2]), math.sin(y[3 * b + 2])
    return y[3 * b] + c * sx - s * sy, y[3 * b + 1] + s * sx + c * sy


_CONTACT_NAMES = ("penetration", "normal_force", "friction_force", "slip_velocity")
_NO_JACOBIAN = np.zeros((1, 1))  # constraint_violation evaluates residuals only


def _spatial_pitch(y: np.ndarray, system: spatial.SpatialSystem, body: int) -> tuple[float, float]:
    pitch, _, _, rate = spatial.attitude(y, system.body_mass.shape[0], body)
    return pitch, rate


def _spatial_contact(y: np.ndarray, system: spatial.SpatialSystem, modes: np.ndarray, foot: int) -> tuple[float, ...]:
    f_n, f_x, f_z, _, _, _, _, delta, _, vx, vz, _, _, _ = spatial.foot_forces(y, system, modes, foot)
    return delta, f_n, f_x, vx, f_z, vz


def _spatial_hip(y: np.ndarray, system: spatial.SpatialSystem) -> tuple[float, ...]:
    s_a = (system.con_vecs[0, 0], system.con_vecs[0, 1], system.con_vecs[0, 2])
    return spatial.point_state(y, system.body_mass.shape[0], system.con_bodies[0, 0], s_a)[0]


_KERNELS: dict[type, dict[str, object]] = {
    planar.PlanarSystem: {
        "rhs": planar.rhs,
        "event_functions": planar.event_functions,
        "update_modes": planar.update_modes,
        "has_fallen": planar.has_fallen,
        "approach_velocity": _planar_approach_velocity,
        "is_leading": _planar_is_leading,
        "make_workspace": planar.make_workspace,
        "event_count": lambda system: 2 * system.foot_body.shape[0],
        "measures": Measures(
            contact_x=lambda y, system, foot: planar.foot_kinematics(y, system, foot)[3],
            pitch=_planar_pitch,
            mechanical_energy=planar.mechanical_energy,
            violation=planar.constraint_violation,
            violation_names=("position", "velocity"),
            contact=_planar_contact,
            contact_names=_CONTACT_NAMES,
            hip=_planar_hip,
            attitude=None,
        ),
    },
    spatial.SpatialSystem: {
        "rhs": spatial.rhs,
        "event_functions": spatial.event_functions,
        "update_modes": spatial.update_modes,
        "has_fallen": spatial.has_fallen,
        "approach_velocity": spatial.approach_velocity,
        "is_leading": spatial.is_leading,
        "make_workspace": spatial.make_workspace,
        "event_count": lambda system: 2 * system.foot_body.shape[0],
        "measures": Measures(
            contact_x=lambda y, system, foot: spatial.foot_kinematics(y, system, foot)[4],
            pitch=_spatial_pitch,
            mechanical_energy=spatial.mechanical_energy,
            violation=lambda y, system: spatial.constraint_violation(y, system, _NO_JACOBIAN),
            violation_names=("position", "velocity", "normalization"),
            contact=_spatial_contact,
            contact_names=(*_CONTACT_NAMES, "friction_force_lateral", "slip_velocity_lateral"),
            hip=_spatial_hip,
            attitude=lambda y, system, body: spatial.attitude(y, system.body_mass.shape[0], body),
        ),
    },
}


def measures(system: tuple) -> Measures:
    """The post-processing measurements of ``system``'s formulation."""
    return _KERNELS[type(system)]["measures"]  # type: ignore[return-value]


def make_workspace(system: tuple) -> tuple:
    """Allocate the right-hand-side buffers of ``system`` (Python side of the interface)."""
    return _KERNELS[type(system)]["make_workspace"](system)  # type: ignore[operator]


def event_count(system: tuple) -> int:
    """Number of event functions of ``system``."""
    return int(_KERNELS[type(system)]["event_count"](system))  # type: ignore[operator]


def _kernel(system_type: types.Type, name: str) -> object:
    if isinstance(system_type, types.BaseNamedTuple) and system_type.instance_class in _KERNELS:
        return _KERNELS[system_type.instance_class][name]
    return None


def system_rhs(t, y, system, modes, work, ydot):  # type: ignore[no-untyped-def]
    """ydot = f(t, y) of ``system`` (compiled: resolved by type; Python: looked up)."""
    return _KERNELS[type(system)]["rhs"](t, y, system, modes, work, ydot)  # type: ignore[operator]


def system_event_functions(y, system, g):  # type: ignore[no-untyped-def]
    """Event function values of ``system`` (compiled: resolved by type; Python: looked up)."""
    return _KERNELS[type(system)]["event_functions"](y, system, g)  # type: ignore[operator]


def system_update_modes(y, system, modes, work):  # type: ignore[no-untyped-def]
    """Discrete contact-mode update of ``system`` (compiled: resolved by type; Python: looked up)."""
    return _KERNELS[type(system)]["update_modes"](y, system, modes, work)  # type: ignore[operator]


def system_has_fallen(y, system):  # type: ignore[no-untyped-def]
    """Fall test of ``system`` (compiled: resolved by type; Python: looked up)."""
    return _KERNELS[type(system)]["has_fallen"](y, system)  # type: ignore[operator]


def system_approach_velocity(y, system, foot):  # type: ignore[no-untyped-def]
    """Normal approach velocity of a foot (compiled: resolved by type; Python: looked up)."""
    return _KERNELS[type(system)]["approach_velocity"](y, system, foot)  # type: ignore[operator]


def system_is_leading(y, system, foot):  # type: ignore[no-untyped-def]
    """Whether a foot leads the walker (compiled: resolved by type; Python: looked up)."""
    return _KERNELS[type(system)]["is_leading"](y, system, foot)  # type: ignore[operator]


@overload(system_rhs)
def _ov_rhs(t, y, system, modes, work, ydot):  # type: ignore[no-untyped-def]
    fn = _kernel(system, "rhs")
    if fn is not None:
        return lambda t, y, system, modes, work, ydot: fn(t, y, system, modes, work, ydot)
    return None


@overload(system_event_functions)
def _ov_events(y, system, g):  # type: ignore[no-untyped-def]
    fn = _kernel(system, "event_functions")
    if fn is not None:
        return lambda y, system, g: fn(y, system, g)
    return None


@overload(system_update_modes)
def _ov_update(y, system, modes, work):  # type: ignore[no-untyped-def]
    fn = _kernel(system, "update_modes")
    if fn is not None:
        return lambda y, system, modes, work: fn(y, system, modes, work)
    return None


@overload(system_has_fallen)
def _ov_fallen(y, system):  # type: ignore[no-untyped-def]
    fn = _kernel(system, "has_fallen")
    if fn is not None:
        return lambda y, system: fn(y, system)
    return None


@overload(system_approach_velocity)
def _ov_approach(y, system, foot):  # type: ignore[no-untyped-def]
    fn = _kernel(system, "approach_velocity")
    if fn is not None:
        return lambda y, system, foot: fn(y, system, foot)
    return None


@overload(system_is_leading)
def _ov_leading(y, system, foot):  # type: ignore[no-untyped-def]
    fn = _kernel(system, "is_leading")
    if fn is not None:
        return lambda y, system, foot: fn(y, system, foot)
    return None
