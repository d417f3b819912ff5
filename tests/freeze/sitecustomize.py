"""Freeze a process at a chosen atomic write, so that a test can kill -9 a sweep at a known point.

Imported at start-up by every interpreter with this directory on PYTHONPATH (``conftest.freezing_env``: the
sweep's CLI process and, through the environment they inherit, its workers). Inert unless
``BIPED_SIM_TEST_FREEZE`` is set to ``MARKERS|NAME@N|NAME@N...``: the N-th ``os.replace`` onto a file named
NAME in a process (the rename that completes an atomic write, its temporary file written) stops that
process, for good, right before the rename, once it has created ``MARKERS/NAME`` holding its pid. Only the
first process to get there stops (the marker is created exclusively); the others carry on.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

FREEZE_VARIABLE = "BIPED_SIM_TEST_FREEZE"


def _install(spec: str) -> None:
    markers, *points = spec.split("|")
    limits = {name: int(count) for name, _, count in (point.rpartition("@") for point in points)}
    seen = dict.fromkeys(limits, 0)
    replace = os.replace

    def freezing_replace(src: object, dst: object, **kwargs: object) -> None:
        name = Path(os.fsdecode(dst)).name  # type: ignore[arg-type]
        if name in limits:
            seen[name] += 1
            if seen[name] == limits[name] and _claim(Path(markers) / name):
                while True:
                    time.sleep(3600)
        replace(src, dst, **kwargs)  # type: ignore[arg-type]

    os.replace = freezing_replace  # type: ignore[assignment]


def _claim(marker: Path) -> bool:
    """Create ``marker`` holding this process's pid (whole: linked in once written); False if another was first."""
    draft = marker.with_name(f".{marker.name}.{os.getpid()}.tmp")
    draft.write_text(str(os.getpid()))
    try:
        os.link(draft, marker)
    except FileExistsError:
        return False
    finally:
        draft.unlink()
    return True


if os.environ.get(FREEZE_VARIABLE):
    _install(os.environ[FREEZE_VARIABLE])
