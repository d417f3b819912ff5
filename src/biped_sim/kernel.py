"""How the engine's functions are compiled: :func:`kernel`, numba's ``njit(cache=True)`` without the Python entry.

numba compiles each jitted function with a CPython wrapper (and a C one) that unboxes its arguments
when Python calls it. The engine's kernels are called from compiled code, almost never from Python,
and take the formulation's system and the loop's buffers: NamedTuples of dozens of arrays, whose
unboxing code is large and is compiled, optimised and turned into machine code for every kernel.
A :class:`Kernel` has no wrapper, which costs compiled callers nothing and shortens a first run's
compilation (``make bench``: the cold first run). Python can still call it (a test, the driver, a
user): the call goes through one more Python frame to a twin with the wrapper, compiled on first use
and cached under its own name, so both callers share one source.

``kernel(reference_counts=False)`` also turns numba's reference counting off inside the function, for
a loop that holds many arrays and allocates none (numba refuses to compile an allocation there). The
count updates of every array of every tuple the loop binds are most of its code until LLVM removes
them, and so a large share of its compile time. Called from Python, such a function receives its
arrays without numba's memory-info pointer, and so do the kernels it calls: their own count updates
(an atomic operation per array argument, at entry and exit) become a test of a null pointer, which
makes the integration loop much faster (``make bench``). The caller keeps the arrays alive.
Such a kernel must not return an array.
"""

from __future__ import annotations

from collections.abc import Callable
from types import FunctionType
from typing import Any

from numba import njit
from numba.core import config
from numba.core.registry import CPUDispatcher

PYTHON_ENTRY_SUFFIX = "_python_entry"  # the twin's qualified name, hence its own cache file


class Kernel(CPUDispatcher):
    """A dispatcher compiled without the CPython wrapper; a call from Python runs its wrapped twin."""

    _python_entry: CPUDispatcher | None = None

    @property
    def python_entry(self) -> CPUDispatcher | None:
        """The twin that Python calls reach (compiled with the wrapper), or None before the first such call."""
        return self._python_entry

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        if self._python_entry is None:
            self._python_entry = _python_twin(self.py_func, self.targetoptions)
        return self._python_entry(*args, **kwargs)


def _python_twin(function: FunctionType, options: dict[str, Any]) -> CPUDispatcher:
    """``function`` under another qualified name (so another cache file), compiled with the CPython wrapper."""
    twin = FunctionType(
        function.__code__, function.__globals__, function.__name__, function.__defaults__, function.__closure__
    )
    twin.__qualname__ = function.__qualname__ + PYTHON_ENTRY_SUFFIX
    twin.__module__ = function.__module__
    twin.__doc__ = function.__doc__
    kept = {k: v for k, v in options.items() if k not in ("nopython", "no_cpython_wrapper", "no_cfunc_wrapper")}
    return njit(cache=True, **kept)(twin)


def kernel_options(reference_counts: bool = True) -> dict[str, Any]:
    """numba's options for an engine kernel; also the ``jit_options`` of the overloads that dispatch to kernels.

    Reference counting is always set explicitly: numba otherwise takes it from the caller whose compile
    reaches the kernel first, and every later caller reuses that code, counted or not.
    """
    return {"nopython": True, "no_cpython_wrapper": True, "no_cfunc_wrapper": True, "_nrt": reference_counts}


def kernel(function: Callable[..., Any] | None = None, *, reference_counts: bool = True) -> Any:
    """Compile ``function`` as an engine kernel (``@kernel`` or ``@kernel(reference_counts=False)``).

    nopython, cached on disk, no CPython or C wrapper (:class:`Kernel`). With ``reference_counts=False``
    numba's reference counting is off inside it (numba's ``_nrt`` option): for a function that allocates
    nothing and returns no array. Under ``NUMBA_DISABLE_JIT`` the function is returned as it is.
    """

    def compile_kernel(python_function: Callable[..., Any]) -> Any:
        if config.DISABLE_JIT:
            return python_function
        dispatcher = Kernel(py_func=python_function, locals={}, targetoptions=kernel_options(reference_counts))
        dispatcher.enable_caching()
        return dispatcher

    return compile_kernel(function) if function is not None else compile_kernel
