"""Big compiled callees called by a symbol of their own, not compiled again inside every caller.

numba links the whole module of each compiled callee into its caller's and has LLVM optimise and emit the linked
module again (``CPUCodeLibrary.finalize``), so a caller of big kernels pays their compile once more, at every level
of the call tree: most of a first run's LLVM time (docs/architecture.md, "Where a first run's LLVM time goes"). Here a
callee whose module holds at least :data:`MIN_CALLED_BY_SYMBOL` LLVM instructions is not linked: the caller's
declaration of it is renamed to a stable symbol (:func:`stable_symbol`: the callee's module, qualified name and
argument types), which :func:`install`'s hook on numba's ``add_overload`` maps to the callee's machine code
(``llvmlite.binding.add_symbol``) whenever a dispatcher adds it, compiled or loaded from the cache. Small callees stay
linked, so LLVM still inlines them (calling every callee by symbol doubles the default walker's integration), and so
do callees whose call passes many machine words for their size (:data:`INSTRUCTIONS_PER_ARGUMENT`: a system's arrays
at every stage of a step), unless they are kernels marked ``by_symbol`` (:func:`biped_sim.kernel.kernel`), which
a loop reaches far less often than it steps.

numba's own symbol names carry a per-process counter, so a caller cached by one process could not find its callee
compiled by another under them; the stable symbol is the same in every process. A cached caller lists its callees
(:class:`CalledBySymbol`, in numba's ``reload_init``, which numba runs before it loads a cached entry's machine code):
each is loaded (or compiled) first and its symbol checked, and a caller whose callee cannot be had counts as missing
from the cache, so it is compiled again rather than loaded with a symbol LLVM would resolve to address 0.

Only the package's own kernels and overload implementations (importable by their qualified names) are called by
symbol; numba's and closures stay linked. The renames come before any module is linked into the caller, so that a
linked callee's declaration of the same symbol merges with the caller's (LLVM would otherwise rename the second one).
"""

from __future__ import annotations

import hashlib
import importlib
import weakref
from dataclasses import dataclass
from typing import Any

import llvmlite.binding as llvm
from numba import types
from numba.core import caching, codegen, dispatcher

from biped_sim.kernel import OVERLOAD_SUFFIX, overload_implementation

MIN_CALLED_BY_SYMBOL = 600  # LLVM instructions of a callee's module from which callers call it by symbol
INSTRUCTIONS_PER_ARGUMENT = 40  # and at least this many per machine word the call passes (an array: seven)
PACKAGE = "biped_sim."
SYMBOL_PREFIX = "biped_sim_callee_"


class StaleCalleeError(Exception):
    """A cached caller's callee that cannot be loaded, compiled or found under its symbol: the caller is compiled."""


@dataclass(frozen=True)
class CalledBySymbol:
    """A callee a caller calls by :attr:`symbol`: loaded (or compiled) before a cached caller is (numba's
    ``reload_init``)."""

    kind: str  # "kernel" or "overload" (an overload implementation of a kernel's code)
    module: str
    qualname: str
    args: tuple[Any, ...]  # numba types
    symbol: str

    def __call__(self) -> None:
        try:
            _dispatcher(self.kind, self.module, self.qualname).compile(self.args)
        except Exception as error:  # the caller is compiled instead, which reports any error of its own
            raise StaleCalleeError(f"{self.module}.{self.qualname}: {error}") from None
        if not llvm.address_of_symbol(self.symbol):
            raise StaleCalleeError(f"{self.module}.{self.qualname}: no {self.symbol}")


@dataclass
class _Callee:
    """What a caller's finalize needs of a library that may be called by symbol."""

    called: CalledBySymbol
    name: str  # numba's symbol of the function in the library
    marked: bool  # a kernel(by_symbol=True) or its overload implementation: by symbol whatever its calls pass
    size: int | None = None  # LLVM instructions of its module for linking, counted once


_CALLEES: weakref.WeakKeyDictionary[Any, _Callee] = weakref.WeakKeyDictionary()
_OVERLOADS: dict[tuple[str, str], Any] = {}  # an overload implementation's dispatcher, made once per process


def _resolve(module: str, qualname: str) -> Any:
    found: Any = importlib.import_module(module)
    for part in qualname.split("."):
        found = getattr(found, part)
    return found


def _dispatcher(kind: str, module: str, qualname: str) -> Any:
    """The dispatcher that compiles the callee (an overload implementation's: made as numba's template makes it)."""
    if kind == "kernel":
        return _resolve(module, qualname)
    key = (module, qualname)
    if key not in _OVERLOADS:
        _OVERLOADS[key] = overload_implementation(_resolve(module, qualname.removesuffix(OVERLOAD_SUFFIX)))
    return _OVERLOADS[key]


def _origin(py_func: Any) -> tuple[str, str, str] | None:
    """(kind, module, qualname) of a function a dispatcher compiles, when its dispatcher can be found again by name in
    another process; None otherwise (numba's own, closures, Python twins, copies)."""
    module, qualname = py_func.__module__, py_func.__qualname__
    if not module.startswith(PACKAGE) or "<locals>" in qualname:
        return None
    try:
        if qualname.endswith(OVERLOAD_SUFFIX):
            base = _resolve(module, qualname.removesuffix(OVERLOAD_SUFFIX))
            same = getattr(base, "py_func", base).__code__ is py_func.__code__
            return ("overload", module, qualname) if same else None
        found = _resolve(module, qualname)
    except (AttributeError, ImportError):
        return None
    return ("kernel", module, qualname) if getattr(found, "py_func", None) is py_func else None


def _spelled(t: Any) -> str:
    """A numba type as text that is the same in every process (ValueError: a type spelled with an address)."""
    if isinstance(t, types.Dispatcher):
        f = t.dispatcher.py_func
        return f"dispatcher({f.__module__}.{f.__qualname__})"
    if isinstance(t, types.BaseNamedTuple):
        c = t.instance_class
        return f"{c.__module__}.{c.__qualname__}({','.join(_spelled(x) for x in t.types)})"
    if isinstance(t, types.BaseTuple):
        return f"{type(t).__name__}({','.join(_spelled(x) for x in t.types)})"
    text = f"{type(t).__name__}:{t}"
    if " at 0x" in text:
        raise ValueError(text)
    return text


def stable_symbol(kind: str, module: str, qualname: str, args: tuple[Any, ...]) -> str:
    """The symbol a callee is called by: a hash of its kind, module, qualified name and argument types."""
    text = f"{kind}|{module}|{qualname}|{','.join(_spelled(a) for a in args)}"
    return SYMBOL_PREFIX + hashlib.sha1(text.encode(), usedforsecurity=False).hexdigest()


def _add_overload(self: Any, cres: Any) -> None:
    """numba's ``add_overload``, then the function's stable symbol mapped to its machine code."""
    _numba_add_overload(self, cres)
    origin = None if cres.objectmode or cres.library is None else _origin(self.py_func)
    if origin is None:
        return
    args = tuple(cres.signature.args)
    try:
        symbol = stable_symbol(*origin, args)
    except ValueError:
        return
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    if address:
        llvm.add_symbol(symbol, address)
        marked = getattr(_resolve(origin[1], origin[2].removesuffix(OVERLOAD_SUFFIX)), "by_symbol", False)
        _CALLEES[cres.library] = _Callee(CalledBySymbol(*origin, args, symbol), cres.fndesc.llvm_func_name, marked)


def _called_by_symbol(caller: Any, library: Any) -> CalledBySymbol | None:
    """Rename ``caller``'s declaration of ``library``'s function to its stable symbol when it is big enough; what the
    caller then needs loaded first (None: link it as numba does)."""
    callee = _CALLEES.get(library)
    if callee is None:
        return None
    if callee.size is None:
        module = library._get_module_for_linking()
        callee.size = sum(1 for f in module.functions for block in f.blocks for _ in block.instructions)
    module = caller._final_module
    if callee.size < MIN_CALLED_BY_SYMBOL or _defines(module, callee.called.symbol):
        return None
    declared = _function(module, callee.name)
    if declared is None or not declared.is_declaration:
        return None
    if not callee.marked and callee.size < INSTRUCTIONS_PER_ARGUMENT * sum(1 for _ in declared.arguments):
        return None  # a call passing a system's arrays costs more than such a callee saves linked (a loop's stage)
    declared.name = callee.called.symbol
    return callee.called


def _function(module: Any, name: str) -> Any:
    try:
        return module.get_function(name)
    except NameError:
        return None


def _defines(module: Any, name: str) -> bool:
    """Whether ``module`` has a function of that name already (the same callee declared twice: link it instead)."""
    return _function(module, name) is not None


def _finalize(self: Any) -> None:
    """numba's ``CPUCodeLibrary.finalize`` with the big callees called by symbol (module docstring)."""
    codegen.require_global_compiler_lock()
    self._codegen._check_llvm_bugs()
    self._raise_if_finalized()
    linked = []
    for library in dict.fromkeys(self._linking_libraries):  # first every rename: linked declarations merge with them
        self._reload_init.update(library._reload_init)
        called = _called_by_symbol(self, library)
        if called is None:
            linked.append(library)
        else:
            self._reload_init.add(called)
    for library in linked:
        self._final_module.link_in(library._get_module_for_linking(), preserve=True)
    self._optimize_final_module()
    self._final_module.verify()
    self._finalize_final_module()


def _load_overload(self: Any, sig: Any, target_context: Any) -> Any:
    """numba's cache lookup; a cached caller whose callee cannot be had is not in the cache.

    numba's rebuild of a cached entry runs its ``reload_init`` but leaves it off the rebuilt library, so a caller
    compiled in this process that links the entry would not list the entry's callees by symbol: cached, that caller
    would then call a symbol no one mapped (address 0) in a process that had not loaded them otherwise. They are put
    back on the library."""
    try:
        cres = _numba_load_overload(self, sig, target_context)
    except StaleCalleeError:
        return None
    if cres is not None and cres.library is not None and cres.reload_init:
        cres.library._reload_init.update(cres.reload_init)
    return cres


_numba_add_overload = dispatcher.Dispatcher.add_overload
_numba_load_overload = caching.Cache.load_overload


def missing_internals() -> list[str]:
    """What this module relies on in numba and llvmlite that the installed versions lack (empty: all there)."""
    from numba.core import compiler
    from numba.core.registry import cpu_target

    library = cpu_target.target_context.codegen().create_library("probe")
    needs = {
        f"CPUCodeLibrary.{name}": hasattr(library, name)
        for name in (
            "_linking_libraries", "_reload_init", "_final_module", "_get_module_for_linking", "_optimize_final_module",
            "_finalize_final_module", "_raise_if_finalized", "get_pointer_to_function",
        )
    }  # fmt: skip
    needs["Dispatcher.add_overload"] = hasattr(dispatcher.Dispatcher, "add_overload")
    needs["Cache.load_overload"] = hasattr(caching.Cache, "load_overload")
    needs["a cached entry's reload_init run before its code is loaded (CompileResult._rebuild)"] = (
        "reload_init" in compiler.CompileResult._rebuild.__code__.co_varnames
    )
    needs["llvmlite.binding.add_symbol and address_of_symbol"] = all(
        hasattr(llvm, name) for name in ("add_symbol", "address_of_symbol")
    )
    return [what for what, present in needs.items() if not present]


def install() -> None:
    """Call big callees by symbol from now on (idempotent); must run before any compile."""
    dispatcher.Dispatcher.add_overload = _add_overload
    codegen.CPUCodeLibrary.finalize = _finalize
    caching.Cache.load_overload = _load_overload
