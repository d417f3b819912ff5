"""Output locations: checked before any work is done, and whole output directories replaced in one step.

A command's output location is refused up front (a :class:`~biped_sim.errors.ConfigError`, one line and
exit code 2) when it is a file, lies under a file, or cannot be written (read-only file system, no
permission): no simulation or figure is computed only to fail when it is saved.

``report``, ``plot`` and ``compare`` own their output directory: :func:`staged_directory` has them write
into a temporary directory beside it, which replaces the old directory only once everything is written.
A failure leaves the old output untouched and nothing partial, and old figures are never left mixed
with new ones. Because the whole directory is replaced, an existing one is taken over only when it holds
nothing but files the command writes; anything else is refused, so that ``--out`` pointed at a directory
of the user's own never deletes it.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass
from fnmatch import fnmatch
from pathlib import Path

from biped_sim.errors import ConfigError
from biped_sim.io.atomic import temporary_sibling


@dataclass(frozen=True)
class OutputKind:
    """A command that owns its output directory, and the files (globs relative to it) that it writes there."""

    command: str
    patterns: tuple[str, ...]

    def owns(self, directory: Path) -> bool:
        """True when ``directory`` holds only files this command writes (or nothing)."""
        for path in directory.rglob("*"):
            relative = path.relative_to(directory).as_posix()
            if not path.is_dir() and not any(fnmatch(relative, pattern) for pattern in self.patterns):
                return False
        return True


def check_writable_dir(path: Path) -> None:
    """``path`` is a directory, or can be created as one, and this process can write in it (ConfigError if not).

    Writability is probed by creating (and removing) a temporary directory in ``path`` or in its nearest
    existing ancestor: that answers for read-only mounts and for the superuser too, where permission bits
    do not.
    """
    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        reason = "is a file, not a directory" if existing == path else f"cannot be created: {existing} is a file"
        raise ConfigError(str(path), reason)
    try:
        temporary_sibling(existing / "write-probe", directory=True).rmdir()
    except OSError as exc:
        raise ConfigError(str(path), f"cannot write in {existing}: {exc.strerror or exc}") from None


def check_output_dir(target: Path, kind: OutputKind) -> None:
    """``target`` can become ``kind``'s output directory (ConfigError if not): see the module docstring."""
    if not (target.exists() or target.is_symlink()):
        check_writable_dir(target)  # its nearest existing ancestor, where it and the staging directory will go
        return
    if not target.is_dir():
        raise ConfigError(str(target), "is a file, not a directory")
    if not kind.owns(target):
        raise ConfigError(
            str(target),
            f"holds files that biped-sim {kind.command} did not write; give a new or empty output directory",
        )
    check_writable_dir(target.parent)  # the staging directory goes beside it, the old one is renamed there


def _swap_into_place(stage: Path, target: Path) -> None:
    """Rename ``stage`` to ``target``, moving an old ``target`` aside first and removing it after."""
    if not target.exists():
        os.rename(stage, target)
        return
    old = temporary_sibling(target, directory=True)
    os.rename(target, old)  # onto the empty placeholder
    os.rename(stage, target)
    shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def staged_directory(target: Path, kind: OutputKind) -> Iterator[Path]:
    """Yield an empty temporary directory beside ``target``; it replaces ``target`` when the block succeeds.

    A write error names ``target`` rather than the temporary path; on any failure the temporary
    directory is removed and ``target`` is left as it was.
    """
    check_output_dir(target, kind)
    target.parent.mkdir(parents=True, exist_ok=True)
    stage = temporary_sibling(target, directory=True)
    try:
        yield stage
        _swap_into_place(stage, target)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
    finally:
        shutil.rmtree(stage, ignore_errors=True)
