"""The law registries as the compiled dispatch reads them, and compile-time dispatch on an argument's type.

``normal_force`` and ``friction_force`` loop over the tuples of :func:`registered_functions` (law number i
is the registry's i-th function) with ``numba.literal_unroll``, which compiles one direct call per law (as
fast as a hand-written if-chain), so that a new law is one ``@kernel`` function and one registry line: no
dispatcher to edit. :func:`by_type` makes a function whose compiled calls numba resolves from the type of
one argument (the ground's shape); the numba machinery behind both is in :mod:`biped_sim.kernel`.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from typing import Any

from biped_sim.kernel import overload_by_type


def registered_functions(laws: Mapping[str, Any], *, stateless_only: bool = False) -> tuple[Callable[..., float], ...]:
    """The compiled functions of ``laws`` in number order; the numbers must be 0, 1, 2, ... in registry order.

    With ``stateless_only`` the laws that carry state (LuGre) are left out; they must come last.
    """
    entries = list(laws.items())
    for position, (name, law) in enumerate(entries):
        if law.index != position:
            raise ValueError(f"law {name!r} is number {law.index} but registry entry {position}")
    kept = [law for _, law in entries if not (stateless_only and getattr(law, "stateful", False))]
    if [law.index for law in kept] != list(range(len(kept))):
        raise ValueError("the laws with state must come after every stateless law")
    return tuple(law.function for law in kept)


def by_type(name: str, key: str, implementations: Mapping[type, Any]) -> Callable[..., Any]:
    """A function that calls ``implementations[type(argument key)]``, resolved at compile time when compiled.

    The implementations are compiled functions with the same parameters (``key`` among them) keyed by
    the NamedTuple class of that argument. Compiled, numba picks one from the argument's type (an
    ``@overload``, inlined into its caller's IR: an extra call layer would cost each array argument a
    reference count at every right-hand-side evaluation), so a specialisation contains only its own
    implementation's code; called from Python, the function looks the implementation up by ``type``.
    """
    first = next(iter(implementations.values()))
    parameters = tuple(inspect.signature(first.py_func).parameters)
    for kernel in implementations.values():
        if tuple(inspect.signature(kernel.py_func).parameters) != parameters:
            raise TypeError(f"{name}: the implementations must all take {parameters}")
    signature = inspect.Signature([inspect.Parameter(p, inspect.Parameter.POSITIONAL_OR_KEYWORD) for p in parameters])
    at = parameters.index(key)

    def generic(*args: Any) -> Any:
        kernel = implementations[type(args[at])]
        # its module's current binding: the compiled function, or its .py_func where a test runs the engine as Python
        return kernel.py_func.__globals__[kernel.__name__](*args)

    generic.__name__ = generic.__qualname__ = name
    generic.__doc__ = first.py_func.__doc__  # the first implementation's, unless the caller writes its own
    generic.__signature__ = signature  # type: ignore[attr-defined]
    overload_by_type(generic, key, implementations.get, inline=True)  # inlined: no call layer, no reference counts
    generic.implementations = implementations  # type: ignore[attr-defined]  # read at compile time: share() adds
    return generic


def share(generic: Callable[..., Any], new_type: type, like: type) -> None:
    """Let the :func:`by_type` function ``generic`` call its implementation for ``like`` on arguments of
    ``new_type`` too (a record of the same fields whose own pieces are other by_type functions' implementations:
    a higher layer's variant of a record, e.g. :mod:`biped_sim.multibody.hinge`'s stops). Before any compile."""
    generic.implementations[new_type] = generic.implementations[like]  # type: ignore[attr-defined]


def extend(generic: Callable[..., Any], new_type: type, implementation: Any) -> None:
    """Add ``implementation`` (same parameters) for arguments of ``new_type`` to the :func:`by_type` function
    ``generic`` (a higher layer's variant of a record). Before any compile."""
    expected = tuple(inspect.signature(generic).parameters)
    if tuple(inspect.signature(implementation.py_func).parameters) != expected:
        raise TypeError(f"{generic.__name__}: the implementations must all take {expected}")
    generic.implementations[new_type] = implementation  # type: ignore[attr-defined]
