"""Atomic file writing: write to a temporary file in the target directory, then rename.

A reader (or a resumed sweep) never sees a half-written file: either the old file, the new one,
or none. ``os.replace`` is atomic on POSIX within one file system. Temporary entries are named
``.<target name>.<random>.tmp`` (what :func:`remove_stale_temporaries` clears after a killed write) and
are created with the usual permissions (0666 or 0777 less the umask), not ``mkstemp``'s 0600, so that
the renamed file is as readable as any other the user writes.
"""

from __future__ import annotations

import contextlib
import glob
import json
import math
import os
import secrets
import shutil
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

TEMPORARY_GLOB = ".*.tmp"


def _create_file(path: Path) -> None:
    os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))


def temporary_sibling(target: Path, *, directory: bool = False) -> Path:
    """Create a new, empty temporary file (or directory) beside ``target`` and return its path."""
    create: Callable[[Path], None] = os.mkdir if directory else _create_file
    for _ in range(100):
        path = target.with_name(f".{target.name}.{secrets.token_hex(4)}.tmp")
        try:
            create(path)
        except FileExistsError:
            continue
        return path
    raise FileExistsError(f"no free temporary name beside {target}")


def _remove_temporary(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def remove_stale_temporaries(directory: Path) -> None:
    """Remove the temporary entries a killed write left in ``directory`` (files and staged directories)."""
    for path in directory.glob(TEMPORARY_GLOB):
        _remove_temporary(path)


def remove_temporaries_of(directory: Path, names: Iterable[str]) -> None:
    """Remove the temporary entries of the targets ``names`` in ``directory`` (``.<name>.<random>.tmp``).

    For a writer that owns those targets (e.g. under a lock): whatever temporaries of them exist were left by
    a writer that died, while the directory's other temporaries may belong to other writers, alive.
    """
    for name in names:
        for path in directory.glob(f".{glob.escape(name)}.*.tmp"):
            _remove_temporary(path)


@contextlib.contextmanager
def atomic_path(target: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it onto ``target`` if the block succeeds."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp_path = temporary_sibling(target)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    except OSError as exc:
        if exc.filename is None:  # a failed write names no file: name the one being written
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        raise
    finally:
        tmp_path.unlink(missing_ok=True)


def write_text_atomic(target: str | Path, text: str) -> None:
    """Write text atomically."""
    with atomic_path(target) as tmp:
        tmp.write_text(text)


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float replaced by None, so that summary.json is valid JSON (null, not NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: json_safe(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(item) for item in value]
    return value


def write_json_atomic(target: str | Path, data: Any) -> None:
    """Write JSON (indented, keys in insertion order) atomically; NaN and infinities are written as null."""
    write_text_atomic(target, json.dumps(json_safe(data), indent=2, allow_nan=False) + "\n")


def write_with(target: str | Path, writer: Callable[[Path], None]) -> None:
    """Call ``writer(tmp_path)`` and rename the result onto ``target``."""
    with atomic_path(target) as tmp:
        writer(tmp)
