"""Cold compile per group: what warming one group costs a fresh process with an empty numba cache, and where it goes.

Each group of :data:`~biped_sim.simulate.warmup.BUNDLED_GROUPS` is warmed (:func:`~biped_sim.simulate.warmup.warm_up`)
in a new interpreter on a new empty ``NUMBA_CACHE_DIR``, then once more on the cache it filled: the cold row is
what a first run of that group pays, the cached row what the cache saves of it. The child splits the compile
by function and by pass (:func:`~biped_sim._compiled_cache.profiling_compilations`: lowering, i.e. numba's LLVM
IR and LLVM's optimisation and machine code, against numba's front end). Times are CPU seconds (user + system),
which a shared machine inflates less than wall times, reported beside them. ``python -m biped_sim.bench.compile``
prints the rows as JSON.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from biped_sim._compiled_cache import profiling_compilations
from biped_sim.simulate.warmup import BUNDLED_GROUPS, group_config, warm_up


def profile_group(formulation: str, family: str, ground: str) -> dict[str, Any]:
    """Warm one group in this process, profiling numba's compiles (run in a fresh process: :func:`group_row`)."""
    config = group_config(formulation, family, ground)
    start, cpu = time.perf_counter(), time.process_time()
    with profiling_compilations() as profile:
        warm_up(config)
    return {"warm_up_s": time.perf_counter() - start, "warm_up_cpu_s": time.process_time() - cpu, **profile.summary()}


def _child(group: tuple[str, str, str], cache_dir: str) -> dict[str, Any]:
    """Profile ``group`` in a new interpreter on ``cache_dir``: its figures, the process's wall and CPU seconds."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-m", "biped_sim.bench.compile", *group], env=env, capture_output=True, text=True, check=True
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return {"wall_s": wall, "cpu_s": cpu, **json.loads(out.stdout.strip().splitlines()[-1])}


def group_row(group: tuple[str, str, str]) -> dict[str, Any]:
    """The cold and the cached warm-up of ``group``, each in a fresh process (the cached one on the cold cache)."""
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-compile-") as cache_dir:
        cold = _child(group, cache_dir)
        cached = _child(group, cache_dir)
    return {"group": " ".join(group), "cold": cold, "cached": cached}


def cold_compile_per_group() -> list[dict[str, Any]]:
    """A row per bundled group, one after the other (each compile has the machine to itself)."""
    return [group_row(group) for group in BUNDLED_GROUPS]


def cold_first_run(config_path: Path) -> dict[str, Any]:
    """``biped-sim run`` of a config in a fresh process on an empty numba cache: wall and CPU seconds, as a user's
    first run after an install (or after an edit of compiled code) pays them."""
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-run-") as tmp:
        env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / "cache")}
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        command = [sys.executable, "-m", "biped_sim.cli", "run", str(config_path), "--out", str(Path(tmp) / "run")]
        subprocess.run(command, env=env, capture_output=True, check=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return {"config": config_path.name, "wall_s": wall, "cpu_s": cpu}


if __name__ == "__main__":
    if len(sys.argv) == 4:  # a child of _child: one group, profiled
        print(json.dumps(profile_group(*sys.argv[1:])))
    elif sys.argv[1:] == ["runs"]:  # the first run of every bundled config, each on an empty cache
        print(json.dumps([cold_first_run(path) for path in sorted(Path("configs").glob("*.yaml"))], indent=1))
    else:
        print(json.dumps(cold_compile_per_group(), indent=1))
