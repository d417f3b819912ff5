"""One sweep at a time per sweep directory: an exclusive lock on ``SWEEP_DIR/.sweep.lock`` while a sweep writes it.

Two sweeps into one directory would run the same runs twice and overwrite each other's table. The lock
is an advisory ``flock`` on a file that holds the holder's pid and host, so that the second sweep can
say who holds it; the kernel releases it when the holder ends, however it ends (no stale lock after a
``kill -9``). The file itself stays (removing it would let two sweeps lock two different files).

The holder is the only writer of the files it owns (``owned``: the sweep's table and manifest), so on
taking the lock it removes their temporaries: a sweep killed while writing one left them, and no one else
will (the directory's other temporaries, e.g. a report being staged, are left to their writers).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import socket
from collections.abc import Iterable, Iterator
from pathlib import Path

from biped_sim.errors import ConfigError
from biped_sim.io.atomic import remove_temporaries_of

LOCK_NAME = ".sweep.lock"


@contextlib.contextmanager
def sweep_lock(sweep_dir: Path, owned: Iterable[str] = ()) -> Iterator[None]:
    """Hold the lock of ``sweep_dir`` (an existing directory) for the block; ConfigError naming the holder if taken.

    Once held, the temporaries dead writers left of the files ``owned`` (names in ``sweep_dir``) are removed.
    """
    fd = os.open(sweep_dir / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 256, 0).decode(errors="replace").strip() or "holder unknown"
            reason = f"another sweep is writing this directory ({holder}); wait for it or write elsewhere"
            raise ConfigError(str(sweep_dir), reason) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on host {socket.gethostname()}\n".encode(), 0)
        remove_temporaries_of(sweep_dir, owned)
        yield
    finally:
        os.close(fd)  # releases the lock
