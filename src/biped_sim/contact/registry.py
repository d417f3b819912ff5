"""The law registries as the compiled dispatch reads them: law number i is the registry's i-th function.

``normal_force`` and ``friction_force`` loop over these tuples with ``numba.literal_unroll``, which
compiles one direct call per law (as fast as a hand-written if-chain, checked when this was written), so
that a new law is one ``@kernel`` function and one registry line: no dispatcher to edit. Numba reaches a
tuple of compiled functions through its first-class-function machinery and says so in an
"experimental" warning at compile time; the calls are resolved statically, so the warning is silenced
here, for these tuples only.
"""

from __future__ import annotations

import inspect
import warnings
from collections.abc import Callable, Mapping
from types import FunctionType
from typing import Any

from numba import types
from numba.core.errors import NumbaExperimentalFeatureWarning
from numba.extending import overload

from biped_sim.kernel import kernel_options

warnings.filterwarnings(
    "ignore", message="First-class function type feature is experimental", category=NumbaExperimentalFeatureWarning
)


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


def implementation_of(kernel: Any) -> FunctionType:
    """The compiled ``kernel``'s Python function, without its annotations, as an overload implementation.

    numba compiles the function an ``@overload`` returns as the implementation of the call, after
    checking that its parameters equal the typing function's, annotations included
    (``numba.core.typing.templates._validate_sigs``). Handing it the kernel's own code (not a
    forwarding wrapper) makes a generic call exactly a call of the kernel: no extra function layer,
    whose arguments would each cost a reference count at every right-hand-side evaluation.
    """
    code = kernel.py_func
    return FunctionType(code.__code__, code.__globals__, code.__name__, code.__defaults__, code.__closure__)


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
    at = parameters.index(key)
    signature = inspect.Signature([inspect.Parameter(p, inspect.Parameter.POSITIONAL_OR_KEYWORD) for p in parameters])

    def generic(*args: Any) -> Any:
        kernel = implementations[type(args[at])]
        # its module's current binding: the compiled function, or its .py_func where a test runs the engine as Python
        return kernel.py_func.__globals__[kernel.__name__](*args)

    def typer(*args):  # type: ignore[no-untyped-def]  # typed by __signature__: numba compares it with the kernel's
        value = args[at]
        if isinstance(value, types.BaseNamedTuple) and value.instance_class in implementations:
            return implementation_of(implementations[value.instance_class])
        return None

    typer.__signature__ = signature  # type: ignore[attr-defined]
    # numba IR inlining: no call layer, no reference counts for it
    overload(generic, inline="always", jit_options=kernel_options())(typer)
    generic.__name__ = generic.__qualname__ = name
    generic.__signature__ = signature  # type: ignore[attr-defined]
    return generic
