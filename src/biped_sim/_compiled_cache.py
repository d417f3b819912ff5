"""Where numba caches the compiled kernels (a directory keyed by a hash of the compiled code's sources),
which functions a piece of code compiles rather than loads from that cache, and the lock that keeps the cache
whole when several processes write it at once.

Numba invalidates a cached function only when its own file changes, not when a function it calls (and
inlined) in another file does: an edited force law would otherwise keep running its old compiled code
inside the cached integrator loop. Keying the cache directory on a hash of every source that compiled
code is built from makes any such edit start a fresh cache, while an edit of plain Python (plots, CLI,
reports) keeps it. Those sources are the packages of the compiled core (whose module constants are
frozen into the kernels too) and any other module that imports numba or the kernel decorator. Must run before any
compiled function of the package is defined; ``NUMBA_CACHE_DIR`` set by the user wins.

The code is compiled at LLVM's optimisation level 1 (:func:`configure_optimisation`), not numba's default 3, and the
cache directory's name carries the level: code compiled at one level is never loaded at another.
"""

from __future__ import annotations

import fcntl
import hashlib
import itertools
import os
import re
import time
from collections import defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numba
from numba.core import event
from numba.core.caching import IndexDataCacheFile

PACKAGE = Path(__file__).resolve().parent
COMPILED_PACKAGES = ("contact", "multibody", "integrate")
LOWERING_PASS = "native_lowering"  # numba's lowering to LLVM IR, with LLVM's optimisation and machine code
OUTSIDE = "(typed outside any function's compile)"  # a pass no compile event encloses
_COMPILES = re.compile(r"^\s*(from numba\b|import numba\b|from biped_sim\.kernel import)", re.M)
LOCK_NAME = ".biped-sim.lock"  # in each of numba's cache directories
OPT_LEVEL = "1"  # LLVM's optimisation level (numba's NUMBA_OPT, default 3): see configure_optimisation


def compiled_sources() -> list[Path]:
    """The source files that compiled code is built from, in path order."""
    paths = []
    for path in sorted(PACKAGE.rglob("*.py")):
        in_core = path.relative_to(PACKAGE).parts[0] in COMPILED_PACKAGES
        if in_core or _COMPILES.search(path.read_text()):
            paths.append(path)
    return paths


def source_hash() -> str:
    """SHA-1 (12 hex digits) of the compiled code's sources (paths and contents)."""
    digest = hashlib.sha1(usedforsecurity=False)
    for path in compiled_sources():
        digest.update(str(path.relative_to(PACKAGE)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def configure_optimisation() -> str:
    """Have numba compile at LLVM's optimisation level :data:`OPT_LEVEL` unless ``NUMBA_OPT`` is set (the user's
    level wins); the level in force. Must run before any function is compiled or jitted (numba reads it when it
    makes its code generator) and before :func:`configure_cache_dir` (numba's reload of its settings resets the
    cache directory).

    Without fastmath LLVM may not reorder floating-point arithmetic at any level, so every result is the same bit
    for bit (the golden tests), while a first run compiles in less time (docs/architecture.md, "Compile time"). Set
    in the environment, so that numba's reload of its settings at each compile keeps it, and the processes this one
    starts (the warm-up's, a sweep's workers) compile alike.
    """
    level = os.environ.setdefault("NUMBA_OPT", OPT_LEVEL)
    numba.core.config.reload_config()
    return level


def configure_cache_dir() -> Path | None:
    """Point numba's cache at ~/.cache/biped-sim/numba-<source hash>-opt<level> unless NUMBA_CACHE_DIR is set."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "biped-sim"
    cache_dir = base / f"numba-{source_hash()}-opt{os.environ.get('NUMBA_OPT', OPT_LEVEL)}"
    numba.config.CACHE_DIR = str(cache_dir)
    return cache_dir


@contextmanager
def _locked(directory: str) -> Iterator[None]:
    """An exclusive lock of ``directory``'s cache files against the other processes (held until the block ends)."""
    descriptor = os.open(os.path.join(directory, LOCK_NAME), os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX)
        yield
    finally:
        os.close(descriptor)  # releases the lock


def _save_locked(cache_file: IndexDataCacheFile, key: Any, data: Any) -> None:
    """numba's ``IndexDataCacheFile.save`` under a lock of the cache directory, the data written before the index.

    numba reads a function's index, picks the first data file name the index does not list, writes the index,
    then the data, with no lock: two processes saving two signatures of one function at once (the parallel
    warm-up, pytest-xdist workers) both pick the same name, the last index written loses the other's entry and
    may point at the other signature's code (numba issues 4807, 10128). Under the lock the read-modify-write is
    whole, and a reader never finds an index entry whose data file is not written yet.
    """
    with _locked(cache_file._cache_path):
        overloads = cache_file._load_index()
        name = overloads.get(key)
        if name is None:
            existing = set(overloads.values())
            name = next(n for n in map(cache_file._data_name, itertools.count(1)) if n not in existing)
        cache_file._save_data(name, data)
        overloads[key] = name
        cache_file._save_index(overloads)


def _index_or_empty(cache_file: IndexDataCacheFile) -> dict[Any, str]:
    """numba's ``_load_index``, a damaged index (truncated, overwritten: it does not unpickle) read as empty, as numba
    reads a stale one: its functions are compiled again and the index written anew, rather than every run failing."""
    try:
        return _numba_load_index(cache_file)
    except Exception:  # pickle raises several kinds at damaged data
        return {}


def _data_or_none(cache_file: IndexDataCacheFile, key: Any) -> Any:
    """numba's ``load``, a damaged data file read as missing (compiled again and saved anew)."""
    try:
        return _numba_load(cache_file, key)
    except Exception:  # pickle raises several kinds at damaged data
        return None


_numba_load_index = IndexDataCacheFile._load_index
_numba_load = IndexDataCacheFile.load


def lock_cache_writes() -> None:
    """Make numba's cache writes go through :func:`_save_locked`, and its reads take a damaged file for a missing one
    (idempotent); must run before any compile."""
    IndexDataCacheFile.save = _save_locked
    IndexDataCacheFile._load_index = _index_or_empty
    IndexDataCacheFile.load = _data_or_none


def in_cache(function: Any, args: tuple[Any, ...]) -> bool:
    """Whether ``function`` (a dispatcher) is compiled for the types of ``args`` in this process or in the on-disk
    cache's index: a lookup, which neither compiles nor loads it (a probe of a cold cache costs milliseconds, not the
    function's compile). numba's own key of the entry (signature, target, the function's bytecode and closure)."""
    signature = tuple(numba.typeof(arg) for arg in args)
    if signature in function.overloads:
        return True
    cache = function._cache
    return cache._index_key(signature, function.targetdescr.target_context.codegen()) in cache._cache_file._load_index()


@contextmanager
def recording_compilations() -> Iterator[list[str]]:
    """Inside the block, the names (module.qualname) of the functions numba compiles, in order.

    A function loaded from the on-disk cache is not compiled and is not listed: an empty list after a
    run means that everything it needed was in the cache. Uses numba's event API ("numba:compile").
    """
    names: list[str] = []

    class _Compilations(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            function = ev.data["dispatcher"].py_func
            names.append(f"{function.__module__}.{function.__qualname__}")

        def on_end(self, ev: event.Event) -> None:
            pass

    with event.install_listener("numba:compile", _Compilations()):
        yield names


@contextmanager
def signalling_lowering(qualname: str, signal: Callable[[], None]) -> Iterator[None]:
    """Inside the block, ``signal()`` when numba starts lowering a function named ``qualname``: its typing is done, so
    every function it calls has been compiled or loaded, and what remains of its compile is its own lowering and
    LLVM's work. Uses numba's event API ("numba:run_pass")."""

    class _Lowering(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            if ev.data["qualname"] == qualname and ev.data["name"].startswith(LOWERING_PASS):
                signal()

        def on_end(self, ev: event.Event) -> None:
            pass

    with event.install_listener("numba:run_pass", _Lowering()):
        yield


class CompileProfile(event.Listener):
    """CPU seconds per compiled function and per compiler pass, each exclusive of the events nested in it.

    numba's events nest: a caller's compile runs its passes, and its typing compiles its callees. A pass is
    charged to the innermost function being compiled, so each function's figure is its own compile only.
    """

    def __init__(self) -> None:
        self._open: list[list[Any]] = []  # [(kind, name), start, CPU seconds of the events nested in it]
        self.functions: dict[str, float] = defaultdict(float)
        self.passes: dict[str, float] = defaultdict(float)
        self.compiled = 0

    def on_start(self, ev: event.Event) -> None:
        if ev.kind == "numba:compile":
            function = ev.data["dispatcher"].py_func
            key = ("function", f"{function.__module__}.{function.__qualname__}")
            self.compiled += 1
        else:
            key = ("pass", ev.data["name"].split(" [")[0])
        self._open.append([key, time.process_time(), 0.0])

    def on_end(self, ev: event.Event) -> None:
        (kind, name), start, nested = self._open.pop()
        spent = time.process_time() - start
        if kind == "pass":
            self.passes[name] += spent - nested
            name = next((key[1] for key, _, _ in reversed(self._open) if key[0] == "function"), OUTSIDE)
        self.functions[name] += spent - nested
        if self._open:
            self._open[-1][2] += spent

    def summary(self, top: int = 8) -> dict[str, Any]:
        """Functions compiled; CPU seconds in lowering (numba's LLVM IR, LLVM's optimisation and machine code)
        and in numba's front end (bytecode, typing, inlining, rewrites); the ``top`` costliest functions."""
        lowering = self.passes.get(LOWERING_PASS, 0.0)
        costliest = sorted(self.functions.items(), key=lambda item: -item[1])[:top]
        return {
            "functions": self.compiled,
            "lowering_cpu_s": lowering,
            "front_end_cpu_s": sum(self.passes.values()) - lowering,
            "top": [{"function": name, "cpu_s": seconds} for name, seconds in costliest],
        }


@contextmanager
def profiling_compilations() -> Iterator[CompileProfile]:
    """Inside the block, where numba's compile time goes (:class:`CompileProfile`); nothing for a cache load."""
    profile = CompileProfile()
    with event.install_listener("numba:compile", profile), event.install_listener("numba:run_pass", profile):
        yield profile
