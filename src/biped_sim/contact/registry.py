"""The law registries as the compiled dispatch reads them: law number i is the registry's i-th function.

``normal_force`` and ``friction_force`` loop over these tuples with ``numba.literal_unroll``, which
compiles one direct call per law (as fast as a hand-written if-chain, checked when this was written), so
that a new law is one ``@njit`` function and one registry line: no dispatcher to edit. Numba reaches a
tuple of compiled functions through its first-class-function machinery and says so in an
"experimental" warning at compile time; the calls are resolved statically, so the warning is silenced
here, for these tuples only.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from typing import Any

from numba.core.errors import NumbaExperimentalFeatureWarning

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
