"""Where numba caches the compiled kernels: a directory keyed by the package's source hash.

Numba invalidates a cached function only when its own file changes, not when a function it
calls (and inlined) in another file does: an edited force law would otherwise keep running
its old compiled code inside the cached integrator loop. Keying the cache directory on a hash
of every source file of the package makes any edit start a fresh cache. Must run before any
``@njit(cache=True)`` function of the package is defined; ``NUMBA_CACHE_DIR`` set by the user wins.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba


def source_hash() -> str:
    """SHA-1 (12 hex digits) of the package's Python sources, in path order."""
    root = Path(__file__).resolve().parent
    digest = hashlib.sha1(usedforsecurity=False)
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
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
