"""Measurements of ``biped-sim bench``: cost of one simulated second, by method, against a baseline.

Every row simulates the default walker for ``t_end`` seconds in this process and reports the
median wall time of ``repeats`` runs after a warm-up (which loads the cached compiled code), the
RHS evaluations and accepted steps, the cost per evaluation, the real-time factor (simulated /
wall seconds), the worst step-period error against a tight reference (dop853, rtol 1e-12) and
the speed-up over the baseline (solve_ivp RK45 over the plain-Python RHS, :mod:`.baseline`).
Fixed-step rows first search the largest step that keeps every step period within
:data:`PERIOD_TOLERANCE` of the reference. Then: the RHS alone in absolute and in minimal
coordinates (hence the loop overhead), compile and start-up times in fresh processes and sweep
throughput with 1 and 2 workers (:mod:`.startup`), a run, a fit evaluation and an uncertainty sample against
their own integration (:mod:`.run_cost`), and MuJoCo.

:data:`CASES` is the list of rows: another formulation, method or walker is one more entry.
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numba
import numpy as np
import scipy

from biped_sim.bench.baseline import integrate_baseline
from biped_sim.bench.compile import cold_compile_per_group
from biped_sim.bench.fit import fit_bench
from biped_sim.bench.rigid_map import rigid_map_bench
from biped_sim.bench.run_cost import run_cost_bench
from biped_sim.bench.space import space_bench
from biped_sim.bench.startup import startup_times, sweep_throughput
from biped_sim.bench.uncertainty import uncertainty_bench
from biped_sim.config import Config, load_config
from biped_sim.integrate.driver import Integration, integrate_model
from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import make_workspace, system_rhs
from biped_sim.walkers import BuiltModel, build_model

PERIOD_TOLERANCE = 1e-4  # relative step-period error the fixed-step rows must meet
DT_LADDER = (1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6)  # [s] candidate fixed steps
ATOL_PER_RTOL = 1e-3  # atol = 1e-3 rtol for every adaptive row (state entries of order 1e-3..1)
WARM_UP_TIME = 0.05  # [s] simulated by the warm-up run of each row
SLOW_RUN_S = 5.0  # [s] rows slower than this per run are repeated slow_repeats times (keeps make bench < 10 min)
BASELINE = "baseline"


@dataclass(frozen=True)
class BenchCase:
    """One row: an integrator (or the baseline) at a tolerance; fixed-step rows search their dt."""

    label: str
    method: str  # integrator name, or BASELINE
    rtol: float | None = None  # adaptive rows; None for fixed-step rows (dt searched)
    overrides: tuple[str, ...] = ()  # extra config overrides, e.g. another formulation
    same_walker: bool = True  # False: another walker than the reference's (no period error)
    config: str | None = None  # another config file than the bench's, beside it (e.g. another walker)


MINIMAL = "dopri5 rtol 1e-6, minimal coordinates"  # the headline in the minimal formulation (issue 13 targets)
FOUR_LEGGED = "walker.kind=four_legged"  # another walker than the reference's: no period error
KNEED_MINIMAL = "dopri5 1e-6, kneed walker, minimal"  # issue 19: a tree of four bodies with knee stops
CASES: tuple[BenchCase, ...] = (
    BenchCase("baseline: solve_ivp RK45, Python RHS, rtol 1e-6", BASELINE, 1e-6),
    BenchCase("dopri5 rtol 1e-6", "dopri5", 1e-6),
    BenchCase("dopri5 rtol 1e-9", "dopri5", 1e-9),
    BenchCase("dopri5 rtol 1e-6, spatial formulation", "dopri5", 1e-6, ("formulation.kind=spatial",)),
    BenchCase(MINIMAL, "dopri5", 1e-6, ("formulation.kind=minimal",)),
    BenchCase("dopri5 1e-6, four-legged, spatial", "dopri5", 1e-6, (FOUR_LEGGED, "formulation.kind=spatial"), False),
    BenchCase("dopri5 1e-6, four-legged, minimal", "dopri5", 1e-6, (FOUR_LEGGED, "formulation.kind=minimal"), False),
    BenchCase(KNEED_MINIMAL, "dopri5", 1e-6, ("formulation.kind=minimal",), False, "kneed_walker_compliant.yaml"),
    BenchCase("bdf rtol 1e-6 (scipy over the compiled RHS)", "bdf", 1e-6),
    BenchCase("radau rtol 1e-6 (scipy over the compiled RHS)", "radau", 1e-6),
    BenchCase("rk4", "rk4"),
    BenchCase("rk2", "rk2"),
    BenchCase("euler", "euler"),
)
REFERENCE = BenchCase("tight reference: dop853 rtol 1e-12", "dop853", 1e-12)
HEADLINE = "dopri5 rtol 1e-6"  # the row of the summary line and the targets


@dataclass(frozen=True)
class BenchSettings:
    """What to measure and how long."""

    config_path: Path
    t_end: float = 10.0
    repeats: int = 5
    slow_repeats: int = 3  # rows whose first timed run takes over SLOW_RUN_S (the baseline, the smallest dt)
    sweep_runs: int = 32  # 0: no sweep throughput
    basins: bool = True  # the rigid map's basin wall times (minutes; bench.rigid_map)
    fits: bool = True  # the global fit and the 4,000-draw posterior (about 10 minutes; bench.fit)
    uncertainty: bool = (
        True  # the 1,024-sample ensemble, the N = 256 Sobol study, MuJoCo's rollouts (bench.uncertainty)
    )
    compile_time: bool = True  # the cold start-up and the cold compile per group
    space: bool = True  # the walkers in space: 3D rigid steps, the compliant 3D run (and MuJoCo's; bench.space)
    mujoco: bool = True
    quick: bool = False

    @classmethod
    def quick_run(cls, config_path: Path) -> BenchSettings:
        """The reduced benchmark of ``bench --quick``: 2 s simulated, 3 repeats, no sweep, compile, space or MuJoCo."""
        return cls(
            config_path,
            t_end=2.0,
            repeats=3,
            slow_repeats=1,
            sweep_runs=0,
            basins=False,
            fits=False,
            uncertainty=False,
            compile_time=False,
            space=False,
            mujoco=False,
            quick=True,
        )


@dataclass
class Row:
    """Measured figures of one case."""

    label: str
    method: str
    rtol: float | None
    atol: float | None
    dt: float | None
    status: str
    wall_s: float
    walls_s: list[float]
    rhs_evals: int
    accepted_steps: int
    n_strikes: int
    us_per_eval: float
    rtf: float
    period_error: float
    ratio_vs_baseline: float = math.nan
    dt_search: list[dict[str, float]] = field(default_factory=list)
    note: str = ""


def case_config(settings: BenchSettings, case: BenchCase, dt: float | None = None) -> Config:
    """The config of a row: the bench config for ``t_end`` with the row's integrator settings."""
    sets = [f"simulation.t_end={settings.t_end}", *case.overrides]
    method = "dopri5" if case.method == BASELINE else case.method
    sets.append(f"integrator.method={method}")
    if case.rtol is not None:
        sets += [f"integrator.rtol={case.rtol}", f"integrator.atol={case.rtol * ATOL_PER_RTOL}"]
    if dt is not None:
        sets.append(f"integrator.dt={dt}")
    path = settings.config_path if case.config is None else settings.config_path.parent / case.config
    return load_config(path, sets)


def integrate(model: BuiltModel, config: Config, method: str, t_end: float | None = None) -> Integration:
    """One integration of ``model`` (the baseline driver for BASELINE), as ``simulate`` would run it."""
    t_end = config.simulation.t_end if t_end is None else t_end
    if method == BASELINE:
        return integrate_baseline(model, config.integrator, t_end, config.output.sample_rate)
    return integrate_model(
        model.system, model.y0, model.modes0, config.integrator, t_end, config.output.sample_rate,
        max_strikes=config.simulation.max_steps,
    )  # fmt: skip


def step_periods(run: Integration) -> np.ndarray:
    """Periods between consecutive heel strikes."""
    return np.diff(run.strike_t)


def period_error(run: Integration, reference: np.ndarray) -> float:
    """Worst relative step-period error over the steps both runs completed (inf if it did not walk)."""
    periods = step_periods(run)
    n = min(len(periods), len(reference))
    if run.status != "walking" or n == 0 or abs(len(periods) - len(reference)) > 1:
        return math.inf
    return float(np.max(np.abs(periods[:n] - reference[:n]) / reference[:n]))


def timed(
    call: Callable[[], Integration], warm_up: Callable[[], Integration] | None, repeats: int, slow_repeats: int
) -> tuple[float, list[float], Integration]:
    """(median wall time, all wall times, last result) of ``repeats`` calls after an optional warm-up call.

    A row whose first call takes over :data:`SLOW_RUN_S` is run ``slow_repeats`` times in all.
    """
    if warm_up is not None:
        warm_up()
    walls: list[float] = []
    while True:
        start = time.perf_counter()
        run = call()
        walls.append(time.perf_counter() - start)
        wanted = slow_repeats if walls[0] > SLOW_RUN_S else repeats
        if len(walls) >= wanted:
            return statistics.median(walls), walls, run


def make_row(case: BenchCase, config: Config, wall: float, walls: list[float], run: Integration, error: float) -> Row:
    """A table row from a measured run."""
    integrator = config.integrator
    fixed = case.rtol is None
    return Row(
        label=case.label,
        method=case.method,
        rtol=None if fixed else integrator.rtol,
        atol=None if fixed else integrator.atol,
        dt=integrator.dt if fixed else None,
        status=run.status,
        wall_s=wall,
        walls_s=walls,
        rhs_evals=run.rhs_evals,
        accepted_steps=run.accepted_steps,
        n_strikes=len(run.strike_t),
        us_per_eval=wall / run.rhs_evals * 1e6 if run.rhs_evals else math.nan,
        rtf=run.t_final / wall if wall > 0 else math.inf,
        period_error=error,
    )


def search_dt(
    settings: BenchSettings, case: BenchCase, reference: np.ndarray, log: Callable[[str], None]
) -> tuple[float | None, list[dict[str, float]]]:
    """Largest dt of :data:`DT_LADDER` (scanned downwards) that meets :data:`PERIOD_TOLERANCE`.

    Returns (dt, or None if even the smallest fails, and the trials). The trials also serve as
    the row's warm-up: the compiled loop is loaded by the first of them.
    """
    trials: list[dict[str, float]] = []
    for dt in DT_LADDER:
        config = case_config(settings, case, dt)
        start = time.perf_counter()
        run = integrate(build_model(config), config, case.method)
        wall = time.perf_counter() - start
        error = period_error(run, reference)
        trials.append({"dt": dt, "period_error": error, "wall_s": wall})
        log(f"  {case.method} dt={dt:g}: period error {error:.2e} ({wall:.2f} s)")
        if error <= PERIOD_TOLERANCE:
            return dt, trials
    return None, trials


def measure_case(
    settings: BenchSettings, case: BenchCase, reference: np.ndarray, log: Callable[[str], None]
) -> tuple[Row, BuiltModel, Integration]:
    """Measure one row (searching the fixed step first for fixed-step methods); also its model and last run."""
    trials: list[dict[str, float]] = []
    dt = None
    if case.rtol is None:
        dt, trials = search_dt(settings, case, reference, log)
        if dt is None:
            dt = DT_LADDER[-1]
    config = case_config(settings, case, dt)
    model = build_model(config)
    warm_up = None if trials else lambda: integrate(model, config, case.method, min(WARM_UP_TIME, settings.t_end))
    wall, walls, run = timed(
        lambda: integrate(model, config, case.method), warm_up, settings.repeats, settings.slow_repeats
    )
    row = make_row(case, config, wall, walls, run, period_error(run, reference) if case.same_walker else math.nan)
    row.dt_search = trials
    if case.rtol is None and row.period_error > PERIOD_TOLERANCE:
        row.note = f"no dt down to {DT_LADDER[-1]:g} s meets {PERIOD_TOLERANCE:g}"
    log(f"{case.label}: {wall:.3f} s, {run.rhs_evals} evaluations, period error {row.period_error:.2e}")
    return row, model, run


@kernel(reference_counts=False)
def _rhs_loop(system: tuple, work: tuple, ys: np.ndarray, modes: np.ndarray, ydot: np.ndarray, sweeps: int) -> float:
    """Evaluate the compiled RHS on every sampled state ``sweeps`` times; returns a checksum.

    Without reference counts, as the integration loop: the rows ``ys[k]`` and ``modes[k]`` cost no count updates.
    """
    total = 0.0
    for _ in range(sweeps):
        for k in range(ys.shape[0]):
            system_rhs(0.0, ys[k], system, modes[k], work, ydot)
            total += ydot[0]
    return total


def rhs_cost_us(model: BuiltModel, run: Integration, min_evals: int = 500_000) -> float:
    """Mean cost [us] of the compiled RHS alone over the states a run visited (its samples, with their modes)."""
    work = make_workspace(model.system)
    ys = np.ascontiguousarray(run.y)
    modes = np.ascontiguousarray(run.modes)
    ydot = np.zeros(ys.shape[1])
    _rhs_loop(model.system, work, ys[:2], modes[:2], ydot, 1)
    sweeps = max(1, min_evals // len(ys))
    best = math.inf
    for _ in range(3):
        start = time.perf_counter()
        _rhs_loop(model.system, work, ys, modes, ydot, sweeps)
        best = min(best, time.perf_counter() - start)
    return best / (sweeps * len(ys)) * 1e6


def run_bench(settings: BenchSettings, log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Measure everything of ``settings``; returns the bench.json content."""
    base = load_config(settings.config_path, [f"simulation.t_end={settings.t_end}"])
    ref_config = case_config(settings, REFERENCE)
    ref_run = integrate(build_model(ref_config), ref_config, REFERENCE.method)
    reference = step_periods(ref_run)
    log(f"{REFERENCE.label}: {len(ref_run.strike_t)} heel strikes, status {ref_run.status}")
    rows: list[Row] = []
    measured: dict[str, tuple[BuiltModel, Integration]] = {}
    for case in CASES:
        row, model, run = measure_case(settings, case, reference, log)
        rows.append(row)
        measured[case.label] = (model, run)
    baseline = next(r for r in rows if r.method == BASELINE)
    for row in rows:
        row.ratio_vs_baseline = baseline.wall_s / row.wall_s
    headline = next(r for r in rows if r.label == HEADLINE)
    rhs_us, rhs_minimal_us = rhs_cost_us(*measured[HEADLINE]), rhs_cost_us(*measured[MINIMAL])
    rhs_kneed_us = rhs_cost_us(*measured[KNEED_MINIMAL])
    # best-case against best-case: both timings are disturbed by whatever else runs on the machine
    loop_overhead = 1.0 - headline.rhs_evals * rhs_us * 1e-6 / min(headline.walls_s)
    ours, theirs = step_periods(measured[HEADLINE][1]), step_periods(measured[baseline.label][1])
    n = min(len(ours), len(theirs))
    result: dict[str, Any] = {
        "quick": settings.quick,
        "config": str(settings.config_path),
        "config_hash": base.hash(),
        "t_end": settings.t_end,
        "repeats": settings.repeats,
        "slow_repeats": settings.slow_repeats,
        "slow_run_s": SLOW_RUN_S,
        "period_tolerance": PERIOD_TOLERANCE,
        "reference": {
            "method": REFERENCE.method,
            "rtol": ref_config.integrator.rtol,
            "atol": ref_config.integrator.atol,
            "n_strikes": len(ref_run.strike_t),
            "periods": reference.tolist(),
        },
        "rows": [asdict(r) for r in rows],
        "headline": HEADLINE,
        "minimal": MINIMAL,
        "rhs_alone_us": rhs_us,
        "rhs_alone_minimal_us": rhs_minimal_us,
        "rhs_alone_kneed_minimal_us": rhs_kneed_us,  # its tree solve against the compass's arrow solve:
        "kneed_minimal_vs_compass_minimal": rhs_kneed_us / rhs_minimal_us,
        "loop_overhead": loop_overhead,
        "baseline_vs_headline_max_period_difference_s": float(np.max(np.abs(ours[:n] - theirs[:n]))),
    }
    log(f"RHS alone {rhs_us:.3f} us (minimal coordinates {rhs_minimal_us:.3f} us), loop overhead {loop_overhead:.0%}")
    log(f"kneed walker's RHS in minimal coordinates {rhs_kneed_us:.3f} us ({rhs_kneed_us / rhs_minimal_us:.2f}x)")
    result["startup"] = startup_times(settings.config_path, cold=settings.compile_time)
    log(f"start-up: {json.dumps(result['startup'])}")
    if settings.compile_time:
        result["compile"] = cold_compile_per_group()
        log(f"cold compile per group: {json.dumps(result['compile'])}")
    if settings.sweep_runs:
        result["sweep"] = sweep_throughput(settings.config_path, settings.sweep_runs, settings.t_end)
        log(f"sweep: {json.dumps(result['sweep'])}")
    result["run_cost"] = run_cost_bench(base, settings.t_end, settings.repeats)
    log(f"run cost: {json.dumps(result['run_cost'])}")
    result["rigid_map"] = rigid_map_bench(settings.basins)
    log(f"rigid map: {json.dumps(result['rigid_map'])}")
    if settings.space:
        result["space"] = space_bench(settings.repeats, settings.mujoco)
        log(f"walkers in space: {json.dumps(result['space'])}")
    if settings.fits:
        result["fit"] = fit_bench()
        log(f"fit: {json.dumps(result['fit'])}")
    if settings.uncertainty:
        result["uncertainty"] = uncertainty_bench()
        log(f"uncertainty: {json.dumps({k: v for k, v in result['uncertainty'].items() if k != 'sobol'})}")
    if settings.mujoco:
        result["mujoco"] = mujoco_comparison(settings, base, reference, log)
    result["environment"] = environment()
    return result


def mujoco_comparison(
    settings: BenchSettings, base: Config, reference: np.ndarray, log: Callable[[str], None]
) -> dict[str, Any]:
    """MuJoCo's real-time factor and step period for the same walker (or why it was not run)."""
    try:
        from biped_sim.bench.mujoco_walker import run_mujoco_bench  # optional extra (biped-sim[bench])
    except ImportError as exc:
        return {"available": False, "reason": str(exc)}
    try:
        return run_mujoco_bench(base, settings.t_end, settings.repeats, reference, log)
    except ImportError as exc:
        return {"available": False, "reason": f"{exc} (install with make setup-bench)"}


def environment() -> dict[str, Any]:
    """Versions and machine facts printed with the table."""
    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "machine": platform.machine(),
        "cpus": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count(),
        "processor": platform.processor() or platform.machine(),
    }
