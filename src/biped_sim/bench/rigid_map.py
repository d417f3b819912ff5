"""Benchmark rows of the rigid step map and of basins: compiled against scipy per step, basin wall times.

* Per step: the median wall time of one step from each rigid walker's fixed point, scipy's ``solve_ivp``
  (the reference, :func:`~biped_sim.rigid.stepping.rigid_step`) against the compiled map
  (:func:`~biped_sim.rigid.compiled.rigid_step`, its buffers reused), after a warm-up.
* Basins (full benchmark only): the wall time of ``biped-sim basin``'s computation, the worker pool's start
  included, with 2 workers: the simplest walker's 41 x 41 grid at 30 steps (target < 60 s) and the default
  compliant walker's 21 x 21 grid at 10 steps (target < 10 min).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from biped_sim.config import load_config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import compile_walker
from biped_sim.rigid.compiled import rigid_step as compiled_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.stepping import rigid_step
from biped_sim.studies.basin import BasinSpec, map_basin, parse_axis
from biped_sim.sweep import local_executor

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
STEP_CASES = {  # walker -> (config, overrides)
    "simplest": ("simplest_walker.yaml", ["dynamics=rigid"]),
    "compass": ("compass_goswami.yaml", ["dynamics=rigid"]),
    "rimless_wheel": ("rimless_wheel.yaml", ["dynamics=rigid"]),
    "kneed": ("kneed_walker.yaml", []),  # a described walker: its tree kernels against scipy over the same ones
}
BASINS = {  # name -> (config, x, y, steps, target wall time [s])
    "simplest_41x41x30": ("simplest_walker.yaml", "stance_angle=0.02:0.42:41", "stance_rate=-0.6:0.0:41", 30, 60.0),
    "compliant_21x21x10": (
        "round_foot_walker.yaml",
        "stance_angle=0.15:0.35:21",
        "stance_rate=-2.2:-1.0:21",
        10,
        600.0,
    ),
}
BASIN_WORKERS = 2


def _median_time(func, repeats: int) -> float:  # type: ignore[no-untyped-def]
    walls = []
    for _ in range(repeats):
        clock = time.perf_counter()
        func()
        walls.append(time.perf_counter() - clock)
    return statistics.median(walls)


def per_step_times(repeats: int = 20) -> dict[str, dict[str, float]]:
    """Per walker: scipy's and the compiled step's median wall time [us] from the fixed point, and the ratio."""
    out = {}
    for name, (config_file, overrides) in STEP_CASES.items():
        config = load_config(CONFIGS / config_file, overrides)
        walker = rigid_walker(config)
        x0 = walker.from_section(rigid_limit_cycle(config).section_point)
        cw = compile_walker(walker)
        compiled_step(walker, x0, cw=cw)  # warm-up: loads the compiled code
        scipy_s = _median_time(lambda w=walker, x=x0: rigid_step(w, x), max(3, repeats // 4))
        compiled_s = _median_time(lambda w=walker, x=x0, c=cw: compiled_step(w, x, cw=c), repeats)
        out[name] = {"scipy_us": scipy_s * 1e6, "compiled_us": compiled_s * 1e6, "speedup": scipy_s / compiled_s}
    return out


def basin_time(name: str) -> dict[str, Any]:
    """Wall time of one of :data:`BASINS` on a fresh pool of :data:`BASIN_WORKERS` (files in a temporary directory),
    after an untimed pass of one step per cell (as the other rows, it times running, not compiling)."""
    config_file, x, y, steps, target = BASINS[name]
    spec = BasinSpec(load_config(CONFIGS / config_file), parse_axis("x", x), parse_axis("y", y), steps)
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-basin-") as tmp:
        with local_executor(BASIN_WORKERS) as pool:  # untimed: one step per cell compiles what the cells run
            map_basin(replace(spec, steps=1), Path(tmp) / "warm-up", pool)
        clock = time.perf_counter()
        with local_executor(BASIN_WORKERS) as pool:
            basin = map_basin(spec, Path(tmp), pool)
        wall = time.perf_counter() - clock
    doc = basin.to_json()
    return {
        "cells": doc["n_cells"],
        "steps": steps,
        "workers": BASIN_WORKERS,
        "wall_s": wall,
        "target_s": target,
        "fraction_walking": doc["fraction_walking"],
    }


def rigid_map_bench(basins: bool) -> dict[str, Any]:
    """The bench.json section ``rigid_map``: per-step times, and the basin wall times when ``basins``."""
    result: dict[str, Any] = {"per_step": per_step_times()}
    if basins:
        result["basins"] = {name: basin_time(name) for name in BASINS}
    return result
