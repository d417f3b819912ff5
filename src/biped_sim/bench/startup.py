"""Start-up and throughput rows of the benchmark: each measured in fresh processes, as a user meets them.

Cold start-up (an empty numba cache: a first run compiles everything it needs) and cached start-up,
from the shell to the end of a first 1 ms integration; a slope sweep's runs per minute with 1 and 2
workers.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path
from typing import Any

from biped_sim.sweep import load_sweep, local_executor, run_sweep

COLD_RUNS = 3  # cold start-ups measured (each compiles everything); the median is reported

_STARTUP_SCRIPT = textwrap.dedent(
    """
    import json, sys, time
    t0 = time.perf_counter()
    from biped_sim import load_config
    from biped_sim.integrate.driver import integrate_model
    from biped_sim.walkers import build_model
    t1 = time.perf_counter()
    config = load_config(sys.argv[1], ["simulation.t_end=0.001"])
    model = build_model(config)
    t2 = time.perf_counter()
    integrate_model(model.system, model.y0, model.modes0, config.integrator, 0.001, config.output.sample_rate)
    t3 = time.perf_counter()
    print(json.dumps({"at": time.time(), "import_s": t1 - t0, "build_s": t2 - t1, "first_integration_s": t3 - t2}))
    """
)


def startup_run(config_path: Path, cache_dir: str | None) -> dict[str, float]:
    """Run a fresh interpreter that integrates 1 ms; wall time from launch to the end of that first integration."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    start = time.time()
    out = subprocess.run(
        [sys.executable, "-c", _STARTUP_SCRIPT, str(config_path)], env=env, capture_output=True, text=True, check=True
    )
    data = json.loads(out.stdout.strip().splitlines()[-1])
    data["to_first_step_s"] = data.pop("at") - start
    return data


def _fresh_cache_run(config_path: Path) -> dict[str, float]:
    """One start-up on a new empty numba cache."""
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-cache-") as tmp:
        return startup_run(config_path, tmp)


def startup_times(config_path: Path, cold: bool) -> dict[str, Any]:
    """Cold (empty numba cache: everything compiles) and cached start-up, each in a new process.

    Cold: the median of COLD_RUNS runs, each with a new empty cache (one compile is a noisy sample on a
    shared machine). Cached: the best of 3 runs on one cache, primed by the first cold run, or without
    ``cold`` by one discarded run on the user's cache (keyed by the package sources, so an edited tree
    starts with an empty one).
    """
    result: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-cache-") as tmp:
        cache_dir = tmp if cold else None
        first = startup_run(config_path, cache_dir)  # cold: compiles into tmp, which the cached runs then load
        if cold:
            runs = [first] + [_fresh_cache_run(config_path) for _ in range(COLD_RUNS - 1)]
            result["cold"] = {
                **sorted(runs, key=lambda data: data["to_first_step_s"])[COLD_RUNS // 2],
                "runs": COLD_RUNS,
            }
        runs = [startup_run(config_path, cache_dir) for _ in range(3)]
        result["cached"] = min(runs, key=lambda data: data["to_first_step_s"])
    return result


_SWEEP_FILE = """\
name: bench_throughput
base: {base}
set:
  simulation.t_end: {t_end}
grid:
  ground.slope: {{from: 0.016, to: 0.024, num: {runs}}}
"""


def sweep_throughput(config_path: Path, runs: int, t_end: float, jobs: tuple[int, ...] = (1, 2)) -> dict[str, Any]:
    """Runs per minute of a ``runs``-run slope sweep (the full run: simulate and write files) per worker count.

    Timed from creating the process pool to the last run written, so worker start-up is included
    (with the compiled code already in the on-disk cache, as in any sweep but the first after an edit).
    """
    result: dict[str, Any] = {"runs": runs, "t_end": t_end, "per_jobs": {}}
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-sweep-") as tmp:
        sweep_file = Path(tmp) / "sweep.yaml"
        sweep_file.write_text(_SWEEP_FILE.format(base=config_path.resolve(), t_end=t_end, runs=runs))
        sweep = load_sweep(sweep_file)
        for n in jobs:
            startup_run(config_path, None)  # the workers load, not compile: the cache is keyed by the sources
            start = time.perf_counter()
            with local_executor(n) as executor:
                outcome = run_sweep(sweep, Path(tmp) / f"jobs{n}", executor, resume=False)
            wall = time.perf_counter() - start
            failed = outcome.progress.failed
            result["per_jobs"][str(n)] = {"wall_s": wall, "runs_per_minute": runs / wall * 60.0, "failed": failed}
    one, two = result["per_jobs"].get("1"), result["per_jobs"].get("2")
    if one and two:
        result["speedup_2_vs_1"] = two["runs_per_minute"] / one["runs_per_minute"]
    return result
