"""numba's on-disk cache stays whole when processes write one function's entries at once (the parallel warm-up,
pytest-xdist workers): every entry kept, each pointing at its own code (biped_sim._compiled_cache's lock)."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import pytest
from numba.core.caching import IndexDataCacheFile

WRITERS, ENTRIES = 2, 60

pytestmark = pytest.mark.slow  # two fresh interpreters importing the package: seconds


def _cache_file(directory: str) -> IndexDataCacheFile:
    return IndexDataCacheFile(directory, "function-1.py311", source_stamp=("stamp", 1))


def _write_entries(directory: str, writer: int) -> None:
    """One process (the package imported, as every process of ours) saving its own signatures' entries."""
    import biped_sim  # noqa: F401  (installs the lock, as in every process that compiles the package's code)

    cache_file = _cache_file(directory)
    for entry in range(ENTRIES):
        cache_file.save((writer, entry), f"code of {writer}, {entry}")


def test_concurrent_writers_keep_every_entry_pointing_at_its_own_data(tmp_path: Path) -> None:
    with ProcessPoolExecutor(WRITERS, mp_context=get_context("spawn")) as pool:
        list(pool.map(_write_entries, [str(tmp_path)] * WRITERS, range(WRITERS)))
    cache_file = _cache_file(str(tmp_path))
    kept = {(w, e): cache_file.load((w, e)) for w in range(WRITERS) for e in range(ENTRIES)}
    assert {key: data for key, data in kept.items() if data != f"code of {key[0]}, {key[1]}"} == {}


def test_a_damaged_index_or_data_file_reads_as_missing_and_is_written_anew(tmp_path: Path) -> None:
    """A truncated or overwritten cache file (a disk full, a killed writer) is compiled again, not a failing run."""
    import biped_sim  # noqa: F401  (installs the readers)

    cache_file = _cache_file(str(tmp_path))
    cache_file.save("key", "code")
    data_file = next(p for p in tmp_path.iterdir() if p.suffix == ".nbc")
    data_file.write_bytes(b"garbage")
    assert cache_file.load("key") is None
    index = next(p for p in tmp_path.iterdir() if p.suffix == ".nbi")
    index.write_bytes(b"garbage")
    assert cache_file.load("key") is None
    cache_file.save("key", "code again")
    assert cache_file.load("key") == "code again"
