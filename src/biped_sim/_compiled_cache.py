"""Where numba caches the compiled kernels (a directory keyed by a hash of the compiled code's sources),
and which functions a piece of code compiles rather than loads from that cache.

Numba invalidates a cached function only when its own file changes, not when a function it calls (and
inlined) in another file does: an edited force law would otherwise keep running its old compiled code
inside the cached integrator loop. Keying the cache directory on a hash of every source that compiled
code is built from makes any such edit start a fresh cache, while an edit of plain Python (plots, CLI,
reports) keeps it. Those sources are the packages of the compiled core (whose module constants are
frozen into the kernels too) and any other module that imports numba or the kernel decorator. Must run before any
compiled function of the package is defined; ``NUMBA_CACHE_DIR`` set by the user wins.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numba
from numba.core import event

PACKAGE = Path(__file__).resolve().parent
COMPILED_PACKAGES = ("contact", "multibody", "integrate")
_COMPILES = re.compile(r"^\s*(from numba\b|import numba\b|from biped_sim\.kernel import)", re.M)


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


def configure_cache_dir() -> Path | None:
    """Point numba's cache at ~/.cache/biped-sim/numba-<source hash> unless NUMBA_CACHE_DIR is set."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "biped-sim"
    cache_dir = base / f"numba-{source_hash()}"
    numba.config.CACHE_DIR = str(cache_dir)
    return cache_dir


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
