"""The engine interface: one registry of formulations and the compiled dispatch generated from it.

Every formulation is one :class:`~biped_sim.multibody.formulation.Formulation` record, registered
below with one line. Compiled code calls the generic ``system_*`` kernels (one per entry of
``KERNEL_SIGNATURES``: ``system_rhs``, ``system_foot_contact``, ``system_fall``, ``system_audit``; and one
per measure of ``MEASURE_SIGNATURES``, ``system_contact`` ..., which the measure loops call);
:func:`_generic_kernel` makes each of them and registers a numba ``@overload`` that resolves the call
at compile time from the type of ``system`` (the formulation's NamedTuple class), so one loop source
serves every formulation and each specialisation is cached on disk. Called from Python, the same
functions look the kernel up in the registry. The event functions and the contact-mode update are
written once over ``system_foot_contact`` (:mod:`biped_sim.multibody.events`).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

from biped_sim.contact.response import ContactBuffers, make_contact_buffers
from biped_sim.contact.stop import stop_event_count
from biped_sim.kernel import overload_by_type
from biped_sim.multibody import minimal, planar, spatial_kernels
from biped_sim.multibody.formulation import KERNEL_SIGNATURES, MEASURE_SIGNATURES, Formulation, Measures

FORMULATIONS: dict[type, Formulation] = {}


def register(formulation: Formulation) -> None:
    """Add a formulation to the registry (the compiled dispatch finds it by its system type).

    Its kernels must take exactly the parameters in ``KERNEL_SIGNATURES`` (numba compiles them as
    the implementations of the generic ``system_*`` functions, whose parameters they must match).
    """
    for kernel, parameters in KERNEL_SIGNATURES.items():
        found = tuple(inspect.signature(getattr(formulation, kernel).py_func).parameters)
        if found != parameters:
            raise TypeError(f"{formulation.name}.{kernel} takes {found}, the engine passes {parameters}")
    FORMULATIONS[formulation.system_type] = formulation


def formulation_of(system: tuple) -> Formulation:
    """The registered formulation of ``system``."""
    try:
        return FORMULATIONS[type(system)]
    except KeyError:
        raise TypeError(f"no formulation is registered for {type(system).__name__}") from None


def _generic_kernel(name: str, parameters: tuple[str, ...], of: Callable[[Formulation], Any]) -> Callable[..., Any]:
    """``system_<name>``: calls ``of(formulation)`` for the formulation of its ``system`` argument.

    Compiled, numba resolves the call at compile time from the type of ``system``
    (:func:`~biped_sim.kernel.overload_by_type`) and compiles the formulation's function in its place; in
    Python it looks the function up in the registry. Both show ``parameters``.
    """
    at = parameters.index("system")
    signature = inspect.Signature([inspect.Parameter(p, inspect.Parameter.POSITIONAL_OR_KEYWORD) for p in parameters])

    def generic(*args: Any) -> Any:
        return of(formulation_of(args[at]))(*args)

    def kernel_of(system_type: type) -> Any:
        formulation = FORMULATIONS.get(system_type)
        return None if formulation is None else of(formulation)

    generic.__name__ = generic.__qualname__ = f"system_{name}"
    generic.__doc__ = f"``{name}`` of the formulation of ``system`` (compiled: resolved by type)."
    generic.__signature__ = signature  # type: ignore[attr-defined]
    overload_by_type(generic, "system", kernel_of, inline=False)
    return generic


def _engine_kernel(kernel: str) -> Callable[..., Any]:
    """``system_<kernel>`` of a kernel of ``KERNEL_SIGNATURES`` (the integration loops' calls)."""
    return _generic_kernel(kernel, KERNEL_SIGNATURES[kernel], lambda formulation: getattr(formulation, kernel))


def _measure_kernel(measure: str) -> Callable[..., Any]:
    """``system_<measure>`` of a per-sample measure of ``MEASURE_SIGNATURES`` (the measure loops' calls)."""
    return _generic_kernel(
        measure, MEASURE_SIGNATURES[measure], lambda formulation: getattr(formulation.measures, measure)
    )


system_rhs = _engine_kernel("rhs")
system_foot_contact = _engine_kernel("foot_contact")
system_fall = _engine_kernel("fall")
system_audit = _engine_kernel("audit")
system_contact = _measure_kernel("contact")
system_energy = _measure_kernel("mechanical_energy")
system_violation = _measure_kernel("violation")
system_hip = _measure_kernel("hip")
system_attitude = _measure_kernel("attitude")


def measures(system: tuple) -> Measures:
    """The post-processing measurements of ``system``'s formulation."""
    return formulation_of(system).measures


def make_workspace(system: tuple) -> tuple:
    """Allocate the buffers of ``system``'s right-hand side."""
    return formulation_of(system).make_workspace(system)


def contact_buffers(system: tuple) -> ContactBuffers:
    """Allocate the per-foot buffers of ``system``'s contact-mode update (its feet's bristle states from the layout)."""
    return make_contact_buffers(
        formulation_of(system).layout_of(system).bristle_index(), stop_event_count(system.stops)
    )


register(planar.FORMULATION)
register(spatial_kernels.FORMULATION)
register(minimal.FORMULATION)
