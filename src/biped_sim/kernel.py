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

Everything the project takes from numba beyond its documented API lives here, so that a numba release
that changes it breaks one module (:func:`missing_numba_internals` names what is gone; ``pyproject.toml``
bounds numba and llvmlite by the versions the tests ran on): the dispatcher subclass and the ``_nrt``
option above; :func:`overload_by_type`, the compile-time dispatch on a NamedTuple argument's class,
which hands numba a kernel's own code as an overload implementation; :func:`inlined`, a kernel's copy
inlined into its callers' IR; and the silenced first-class-function warning of the law registries.
"""

from __future__ import annotations

import inspect
import warnings
from collections.abc import Callable
from types import FunctionType
from typing import Any

import numba
from numba import jit, njit, types
from numba.core import config
from numba.core.dispatcher import Dispatcher
from numba.core.errors import NumbaExperimentalFeatureWarning
from numba.core.registry import CPUDispatcher
from numba.extending import overload

# The law registries are tuples of kernels that numba reaches through its first-class-function machinery
# (``literal_unroll``, resolved statically to one direct call per law): its "experimental" warning at compile
# time says nothing about them.
warnings.filterwarnings(
    "ignore", message="First-class function type feature is experimental", category=NumbaExperimentalFeatureWarning
)

PYTHON_ENTRY_SUFFIX = "_python_entry"  # the twin's qualified name, hence its own cache file
OVERLOAD_SUFFIX = "_overload"  # an overload implementation's qualified name, hence its own cache file


class Kernel(CPUDispatcher):
    """A dispatcher compiled without the CPython wrapper; a call from Python runs its wrapped twin."""

    _python_entry: CPUDispatcher | None = None
    literal_arguments = True  # kernel(literal_arguments=False): constants passed by compiled callers typed by type
    by_symbol = False  # kernel(by_symbol=True): compiled callers call it by symbol (biped_sim._symbol_calls)

    def get_call_template(self, args: tuple, kws: dict) -> Any:
        """numba's typing of a compiled caller's call; without ``literal_arguments``, a constant argument (``True``,
        ``0``) counts as its type, not its value: one specialisation for all calls, not one per constant passed."""
        if not self.literal_arguments:
            args = tuple(types.unliteral(a) for a in args)
            kws = {name: types.unliteral(a) for name, a in kws.items()}
        return super().get_call_template(args, kws)

    @property
    def python_entry(self) -> CPUDispatcher | None:
        """The twin that Python calls reach (compiled with the wrapper), or None before the first such call."""
        return self._python_entry

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.twin()(*args, **kwargs)

    def twin(self) -> CPUDispatcher:
        """The twin Python calls reach (created, not compiled, on first use): compiled for some types in another
        process, it is in the cache when this one's Python calls reach it."""
        if self._python_entry is None:
            self._python_entry = _python_twin(self.py_func, self.targetoptions)
        return self._python_entry

    def entry_for(self, *args: Any) -> Callable[..., Any]:
        """The Python-callable compiled code for the types of ``args`` (compiled or loaded now), called without
        numba's typing of its arguments: the dispatcher types a NamedTuple argument in Python at every call, a
        cost that grows with the arrays it holds. Only for arguments of exactly these types (numba's unboxing checks an
        array's item size, not its dtype, dimensions or layout): a caller that holds them, calling often."""
        return self.twin().compile(tuple(numba.typeof(arg) for arg in args))


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


# an overload implementation's: cached, as numba compiles it even where it inlines it (once, to check that it compiles)
OVERLOAD_OPTIONS = {**kernel_options(), "cache": True}


def kernel(
    function: Callable[..., Any] | None = None,
    *,
    reference_counts: bool = True,
    literal_arguments: bool = True,
    by_symbol: bool = False,
) -> Any:
    """Compile ``function`` as an engine kernel (``@kernel`` or ``@kernel(reference_counts=False)``).

    nopython, cached on disk, no CPython or C wrapper (:class:`Kernel`). With ``reference_counts=False``
    numba's reference counting is off inside it (numba's ``_nrt`` option): for a function that allocates
    nothing and returns no array. With ``literal_arguments=False`` a compiled caller's constant arguments do not
    make specialisations of their own (numba otherwise compiles the kernel, and everything it calls, once per
    constant value: a kernel called with ``True`` and with ``False`` twice). With ``by_symbol=True`` its
    compiled callers call it by symbol however many machine words the call passes (:mod:`biped_sim._symbol_calls`),
    rather than compile it again inside themselves: for a kernel a loop reaches far less often than it steps (a
    check every millisecond of simulated time, an event). Under ``NUMBA_DISABLE_JIT`` the function is returned as
    it is.
    """

    def compile_kernel(python_function: Callable[..., Any]) -> Any:
        if config.DISABLE_JIT:
            return python_function
        dispatcher = Kernel(py_func=python_function, locals={}, targetoptions=kernel_options(reference_counts))
        dispatcher.literal_arguments = literal_arguments
        dispatcher.by_symbol = by_symbol
        dispatcher.enable_caching()
        return dispatcher

    return compile_kernel(function) if function is not None else compile_kernel


def compile_for(kernel: Dispatcher, args: tuple[Any, ...]) -> None:
    """Compile ``kernel`` (or load it from the cache) for the types of ``args``, as a compiled caller passing them
    would (numba's ``typeof`` of each), without calling it."""
    kernel.compile(tuple(numba.typeof(arg) for arg in args))


def implementation_of(kernel: Any) -> FunctionType:
    """The compiled ``kernel``'s Python function (or a plain function's), without its annotations, as an overload
    implementation.

    numba compiles the function an ``@overload`` returns as the implementation of the call, after
    checking that its parameters equal the typing function's, annotations included
    (``numba.core.typing.templates._validate_sigs``). Handing it the kernel's own code (not a
    forwarding wrapper) makes a generic call exactly a call of the kernel: no extra function layer,
    whose arguments would each cost a reference count at every right-hand-side evaluation.
    """
    code = getattr(kernel, "py_func", kernel)  # a plain Python function (over kernels) is its own code
    implementation = FunctionType(code.__code__, code.__globals__, code.__name__, code.__defaults__, code.__closure__)
    implementation.__qualname__ = code.__qualname__ + OVERLOAD_SUFFIX  # not the kernel's cache index (other options)
    return implementation


def overload_implementation(kernel: Any) -> Dispatcher:
    """``kernel`` as :func:`overload_by_type` has numba compile it (its code, name and options, so its cache entries):
    compiled for a caller's argument types (:func:`compile_for`), it is in the cache when another process's compile of
    that caller needs it."""
    return jit(**OVERLOAD_OPTIONS)(implementation_of(kernel))


def overload_by_type(generic: Callable[..., Any], key: str, kernel_for: Callable[[type], Any], inline: bool) -> None:
    """Compile calls of the Python function ``generic`` as calls of ``kernel_for(class of argument key)``.

    ``generic`` carries the parameters in its ``__signature__``; ``kernel_for`` maps a NamedTuple class to a
    kernel with those parameters (or None: not this overload's). numba resolves the call at compile time from
    the argument's type (an ``@overload`` whose implementation is the kernel's own code,
    :func:`implementation_of`), so a specialisation holds only that kernel; with ``inline`` the overload is
    inlined into the caller's IR (no call layer, no reference counts for it).
    """
    signature = inspect.signature(generic)
    at = list(signature.parameters).index(key)

    def typer(*args):  # type: ignore[no-untyped-def]  # typed by __signature__: numba compares it with the kernel's
        value = args[at]
        if isinstance(value, types.BaseNamedTuple):
            found = kernel_for(value.instance_class)
            if found is not None:
                return implementation_of(found)
        return None

    typer.__signature__ = signature  # type: ignore[attr-defined]
    overload(generic, jit_options=OVERLOAD_OPTIONS, **({"inline": "always"} if inline else {}))(typer)


def inlined(kernel: Dispatcher, calls: frozenset[str] = frozenset()) -> Dispatcher:
    """The compiled ``kernel`` (same source) made to be inlined where it is called, with its compiled callees but
    those named in ``calls`` (at any depth), which stay ordinary calls.

    A call of an ordinary kernel passes every array as seven machine words, and numba adds reference counts
    around it; a copy inlined (numba's ``inline="always"``) has neither, but numba types and lowers it again at
    every place it is inlined: a large callee called once per evaluation is cheaper called. The copy runs the
    kernel's own code object, so each equation keeps one source.
    """
    function = kernel.py_func
    names = dict(function.__globals__)
    for name in function.__code__.co_names:
        if isinstance(names.get(name), Dispatcher) and name not in calls:
            names[name] = inlined(names[name], calls)
    code = FunctionType(function.__code__, names, function.__name__, function.__defaults__, function.__closure__)
    return njit(inline="always")(code)


def missing_numba_internals() -> list[str]:
    """What this module relies on in numba that the installed numba lacks (empty: everything is there)."""
    from numba.core import event
    from numba.core.caching import Cache, IndexDataCacheFile
    from numba.core.typing import templates

    options = CPUDispatcher.targetdescr.options
    needs = {
        "CPUDispatcher.enable_caching (Kernel subclasses the dispatcher)": hasattr(CPUDispatcher, "enable_caching"),
        **{f"the {name} target option": hasattr(options, name) for name in kernel_options()},
        "numba.core.config.DISABLE_JIT": hasattr(config, "DISABLE_JIT"),
        "types.BaseNamedTuple (overload_by_type)": hasattr(types, "BaseNamedTuple"),
        "an overload's signature check (templates._OverloadFunctionTemplate._validate_sigs)": hasattr(
            getattr(templates, "_OverloadFunctionTemplate", None), "_validate_sigs"
        ),
        "numba.core.event.install_listener (compile events)": hasattr(event, "install_listener"),
        "numba.config.CACHE_DIR (the cache keyed by source hash)": hasattr(numba.config, "CACHE_DIR"),
        "numba.core.config.reload_config (the optimisation level)": hasattr(config, "reload_config"),
        "IndexDataCacheFile's index and data methods (the cache's write lock, its damaged files read as missing)": all(
            hasattr(IndexDataCacheFile, name)
            for name in ("_load_index", "_save_index", "_save_data", "_data_name", "load")
        ),
        "Cache._index_key and the dispatcher's target context (the cold-cache probe, _compiled_cache.in_cache)": (
            hasattr(Cache, "_index_key") and hasattr(CPUDispatcher.targetdescr, "target_context")
        ),
    }
    return [what for what, present in needs.items() if not present]
