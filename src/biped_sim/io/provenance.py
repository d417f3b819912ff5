"""Provenance recorded with every output: package version, git commit, library versions."""

from __future__ import annotations

import subprocess
from datetime import UTC, datetime
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path


@lru_cache(maxsize=1)
def package_version() -> str:
    """Installed version of biped-sim (read once per process: importlib.metadata scans sys.path)."""
    try:
        return version("biped-sim")
    except PackageNotFoundError:
        return "0+unknown"


@lru_cache(maxsize=1)
def git_commit() -> tuple[str, bool]:
    """(commit hash, dirty flag) of the source tree, or ("unknown", False) outside a git checkout."""
    src = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=src, capture_output=True, text=True, check=True, timeout=10
        ).stdout.strip()
        status = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=src, capture_output=True, text=True, check=True, timeout=10,
        ).stdout  # fmt: skip
        return commit, bool(status.strip())
    except (OSError, subprocess.SubprocessError):
        return "unknown", False


@lru_cache(maxsize=1)
def _library_versions() -> tuple[tuple[str, str], ...]:
    """(name, version) of the numerical libraries, read once per process."""
    out = []
    for name in ("numpy", "scipy", "numba", "h5py"):
        try:
            out.append((name, version(name)))
        except PackageNotFoundError:
            out.append((name, "missing"))
    return tuple(out)


def library_versions() -> dict[str, str]:
    """Versions of the numerical libraries that shape the results."""
    return dict(_library_versions())


def provenance() -> dict[str, str]:
    """Everything an output file records about how it was made."""
    commit, dirty = git_commit()
    info = {
        "version": package_version(),
        "git_commit": commit,
        "git_dirty": str(dirty).lower(),
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
    }
    info.update({f"{name}_version": v for name, v in library_versions().items()})
    return info
