"""Benchmark rows of the rigid step map and of basins: compiled against scipy per step, basin wall times.

* Per step: the median wall time of one step from each rigid walker's fixed point, the compiled map
  (:func:`~biped_sim.rigid.compiled.rigid_step`, its buffers reused, after a warm-up) against scipy's
  ``solve_ivp`` DOP853 integrating the same compiled equations phase by phase to the same guards (the baseline:
  :func:`scipy_step`, no falls, no polish); and a run's step of the kneed walker (``kneed_run_step``: a push on the
  hip, a step down ahead, samples at 1 kHz) against its plain step.
* Basins (full benchmark only): the wall time of ``biped-sim basin``'s computation, the worker pool's start
  included, with 2 workers: the simplest walker's 41 x 41 grid at 30 steps (target < 60 s) and the default
  compliant walker's 21 x 21 grid at 10 steps (target < 10 min).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import load_config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import compile_walker, rigid_step
from biped_sim.rigid.ground import Footing, ProfileStrike, rigid_ground
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.step import ATOL, RTOL
from biped_sim.rigid.tree import RigidWalker
from biped_sim.studies.basin import BasinSpec, map_basin, parse_axis
from biped_sim.sweep import local_executor

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
# the kneed walker's run step: a push on the hip, a step down of 5 mm ahead, samples at 1 kHz
RUN_STEP_PUSHES = [(0.2, np.array([0.02, 0.0]))]
RUN_STEP_PROFILE = "ground.profile={kind: steps, steps: [{at: 0.3, height: -0.005}]}"
RUN_STEP_RATE = 1000.0
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


def median_time(func, repeats: int) -> float:  # type: ignore[no-untyped-def]
    """The median wall time [s] of ``repeats`` calls of ``func``."""
    walls = []
    for _ in range(repeats):
        clock = time.perf_counter()
        func()
        walls.append(time.perf_counter() - clock)
    return statistics.median(walls)


def scipy_step(walker: RigidWalker, x: np.ndarray) -> np.ndarray:
    """The baseline: the post-impact state after one step by scipy's DOP853 (rtol = atol = 1e-12) over the walker's
    compiled flow, each phase ended by its guard (scipy's event location), the stop strikes and the heel strike."""
    from scipy.integrate import solve_ivp  # here: scipy.integrate adds 0.3 s to start-up

    walker.begin_step()
    for phase, (_, guard) in enumerate(walker.guard_phases()):
        if walker.skip_phase(phase, x):
            continue
        event = lambda _t, y, g=guard: g(y)  # noqa: E731
        event.terminal, event.direction = True, -1.0  # type: ignore[attr-defined]
        span = (0.0, 20.0 * np.sqrt(walker.leg_length / walker.gravity))
        sol = solve_ivp(lambda _t, y: walker.rhs(y), span, x, method="DOP853", rtol=RTOL, atol=ATOL, events=event)
        x = walker.after_phase(phase, sol.y[:, -1])
    return walker.impact(x)


def per_step_times(repeats: int = 20) -> dict[str, dict[str, float]]:
    """Per walker: scipy's and the compiled step's median wall time [us] from the fixed point, and the ratio."""
    out = {}
    for name, (config_file, overrides) in STEP_CASES.items():
        config = load_config(CONFIGS / config_file, overrides)
        walker = rigid_walker(config)
        x0 = walker.from_section(rigid_limit_cycle(config).section_point)
        cw = compile_walker(walker)
        out[name] = _step_times(
            lambda w=walker, x=x0: scipy_step(w, x), lambda w=walker, x=x0, c=cw: rigid_step(w, x, cw=c), repeats
        )
    out["kneed_run_step"] = _run_step_times(repeats)
    return out


def _run_step_times(repeats: int) -> dict[str, float]:
    """The kneed walker's step from its fixed point with RUN_STEP_PUSHES, on RUN_STEP_PROFILE, sampled, against its
    plain step (the extras' cost, as a ratio)."""
    config = load_config(CONFIGS / "kneed_walker.yaml")
    walker = rigid_walker(config)
    x0 = walker.from_section(rigid_limit_cycle(config).section_point)
    ground = rigid_ground(load_config(CONFIGS / "kneed_walker.yaml", [RUN_STEP_PROFILE]))
    assert ground is not None
    profile = ProfileStrike(walker, ground, Footing(0.0, 0.0))
    cw = compile_walker(walker)
    rigid_step(walker, x0, RUN_STEP_RATE, RUN_STEP_PUSHES, profile, cw=cw)  # warm-up
    run_s = median_time(lambda: rigid_step(walker, x0, RUN_STEP_RATE, RUN_STEP_PUSHES, profile, cw=cw), repeats)
    plain_s = median_time(lambda: rigid_step(walker, x0, cw=cw), repeats)
    return {"compiled_us": run_s * 1e6, "plain_us": plain_s * 1e6, "over_plain": run_s / plain_s}


def _step_times(reference: Callable[[], object], compiled: Callable[[], object], repeats: int) -> dict[str, float]:
    """Median wall times [us] of a step by the scipy baseline and compiled (after a warm-up that loads the code)."""
    compiled()
    scipy_s = median_time(reference, max(3, repeats // 4))
    compiled_s = median_time(compiled, repeats)
    return {"scipy_us": scipy_s * 1e6, "compiled_us": compiled_s * 1e6, "speedup": scipy_s / compiled_s}


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
