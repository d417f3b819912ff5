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
  one entry per foot) and ``event_count(system)``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.extending import overload

from biped_sim.multibody import planar


@njit(cache=True)
def _planar_approach_velocity(y: np.ndarray, system: planar.PlanarSystem, foot: int) -> float:
    return planar.foot_kinematics(y, system, foot)[1]


@njit(cache=True)
def _planar_is_leading(y: np.ndarray, system: planar.PlanarSystem, foot: int) -> bool:
    partner = system.foot_partner[foot]
    if partner < 0:
        return True
    return planar.foot_kinematics(y, system, foot)[3] > planar.foot_kinematics(y, system, partner)[3]


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
    },
}


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
