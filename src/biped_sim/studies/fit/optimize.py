"""The optimizer of a fit: a bounded global stage, then continued least-squares polishes from its best basins.

The objective, half the sum of squared weighted residuals, is piecewise smooth in contact parameters (a
rebound or a slip that appears moves the gait) and has cliffs where the walker falls; and a gait started
from a fixed state is a transient whose later steps amplify a parameter's change, so over seven steps the
truth's basin is a needle (issue 27: 0.01 wide in restitution) while over the first three it is wide. One
CMA-ES run converges on the basin it meets first; a local method from one start walks into the nearest
step. The default global stage, ``multistart``, is therefore:

1. a scrambled Sobol design (``scipy.stats.qmc.Sobol``, seeded) of ``2^ceil(log2(SOBOL_PER_PARAMETER p))``
   points over the box (normalised variables), one batch on the executor, scored on the targets of the
   continuation's first level (below), each run only as far as they go;
2. the design's basins: a point is a basin's lowest point when no lower design point lies within
   ``BASIN_RADIUS`` of it; the best ``POLISH_STARTS`` of them are each polished by continuation over the
   steps (:func:`step_levels`: the targets up to the first model step with more targets than parameters,
   then one step more at a time, each level polished from the last one's optimum, the last on every target;
   a level's runs stop at its last step, so that the early levels cost a fraction of a full run);
3. when the best polished basin still misses the data (a reference with std: chi2 beyond its
   ``1 - MISFIT_P_VALUE`` quantile), IPOP-CMA-ES restarts (``cma.fmin2``, the population doubled at each
   restart, each generation one batch) within ``IPOP_SETTINGS["maxfevals"]`` evaluations in all; their best
   point is polished too. Without a std there is no noise level to miss, and the budget is not spent.

The polished basins are all kept (:attr:`FitRun.basins`, best first): two of them at equal cost within the
noise mean the data do not pick one (:mod:`.alternatives`). The choice of this stage over one CMA-ES run or
differential evolution (``cma``, ``de``, kept for comparison) is measured in docs/experiments.md. A
one-parameter fit scans a grid of ``GRID_POINTS`` instead of the design (in one dimension a grid is the
robust answer), and polishes its basins the same way. The polish is ``least_squares`` (trust-region
reflective, bounded to [0, 1]) with forward differences of ``FD_STEP`` of the normalised range, its p
difference runs one batch. Everything runs through one :class:`~biped_sim.studies.fit.evaluate.Evaluator`,
so points are never simulated twice and a checkpoint resumes an interrupted fit.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import cma
import numpy as np
from scipy.optimize import differential_evolution, least_squares
from scipy.stats import chi2 as chi2_distribution
from scipy.stats import qmc

from biped_sim.errors import ConfigError
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.problem import FitProblem, Outcome

FD_STEP = 1e-3  # forward-difference step of the polish, in normalised variables
GLOBAL_METHODS = ("multistart", "cma", "de")
SOBOL_PER_PARAMETER = 16  # design points per parameter (rounded up to a power of two: 32 for two parameters)
BASIN_RADIUS = 0.15  # normalised distance within which a lower design point claims a point's basin
POLISH_STARTS = 3  # the best basins of the design polished
SAME_POINT = 1e-3  # polishes ending this close (normalised, in every variable) found the same basin
IPOP_SETTINGS = {"sigma0": 0.25, "popsize": 8, "incpopsize": 2, "restarts": 4, "maxfevals": 240, "tolx": 1e-4}
MISFIT_P_VALUE = 1e-3  # chi2 above its 99.9th percentile: the data are not matched
DE_SETTINGS = {"popsize": 8, "maxiter": 40, "tol": 1e-3, "atol": 1e-9, "mutation": (0.5, 1.0), "recombination": 0.7}
CMA_SETTINGS = {"sigma0": 0.25, "popsize": 8, "maxfevals": 640, "tolx": 1e-4}
POLISH_EVALUATIONS = 30  # least_squares' max_nfev (each Jacobian costs p more runs)
LEVEL_EVALUATIONS = 10  # ... on each level of the continuation before the last
TOLERANCES = {"ftol": 1e-8, "xtol": 1e-6, "gtol": 1e-8}
SEED = 11  # the global stage's seed (recorded in fit.json)
GRID_POINTS = 41  # the global stage of a one-parameter fit


@dataclass
class Stage:
    """What one stage found: its point (normalised), cost, evaluations it asked for, and its own verdict."""

    name: str
    u: np.ndarray
    cost: float
    evaluations: int
    success: bool
    message: str


@dataclass
class FitRun:
    """The global stage and the polish, the residuals and Jacobian at the optimum, and the evaluations used."""

    problem: FitProblem
    global_stage: Stage
    polish: Stage
    residuals: np.ndarray
    jacobian: np.ndarray
    start_outcome: Outcome
    best_outcome: Outcome
    evaluations: int
    replayed: int
    wall_time_s: float
    global_method: str
    seed: int
    basins: list[Stage]  # every polished basin, best first (the first is ``polish``)

    @property
    def u(self) -> np.ndarray:
        return self.polish.u

    @property
    def cost(self) -> float:
        return self.polish.cost


def _de(evaluator: Evaluator, dimension: int, seed: int) -> Stage:
    before = evaluator.evaluations + evaluator.replayed
    evaluator.stage = "global (differential evolution)"
    result = differential_evolution(
        lambda u: evaluator.costs([u])[0],
        [(0.0, 1.0)] * dimension,
        seed=seed,
        init="sobol" if dimension > 1 else "latinhypercube",
        updating="deferred",
        workers=evaluator.cost_map,
        polish=False,
        **DE_SETTINGS,
    )
    used = evaluator.evaluations + evaluator.replayed - before
    return Stage("differential_evolution", result.x, float(result.fun), used, bool(result.success), str(result.message))


def _cma(evaluator: Evaluator, dimension: int, seed: int) -> Stage:
    before = evaluator.evaluations + evaluator.replayed
    evaluator.stage = "global (CMA-ES)"
    options = {
        "bounds": [0.0, 1.0], "seed": seed, "popsize": CMA_SETTINGS["popsize"], "maxfevals": CMA_SETTINGS["maxfevals"],
        "tolx": CMA_SETTINGS["tolx"], "verbose": -9,
    }  # fmt: skip
    strategy = cma.CMAEvolutionStrategy([0.5] * dimension, CMA_SETTINGS["sigma0"], options)
    while not strategy.stop():
        points = strategy.ask()
        strategy.tell(points, evaluator.costs(points))
    best = np.asarray(strategy.result.xbest, dtype=float)
    used = evaluator.evaluations + evaluator.replayed - before
    return Stage("cma", best, float(strategy.result.fbest), used, True, str(dict(strategy.stop())))


def _design(evaluator: Evaluator, dimension: int, seed: int, rows: np.ndarray) -> tuple[Stage, np.ndarray, np.ndarray]:
    """The space-filling start in one batch of runs as far as the targets ``rows``: a scrambled Sobol design, or in
    one dimension a grid of GRID_POINTS; (its best point over ``rows``, with its cost over every target, the
    points, their costs over ``rows``)."""
    if dimension == 1:
        points = np.linspace(0.0, 1.0, GRID_POINTS)[:, None]
        name, text = "grid", f"{GRID_POINTS} grid points"
    else:
        m = math.ceil(math.log2(SOBOL_PER_PARAMETER * dimension))
        points = qmc.Sobol(dimension, scramble=True, seed=np.random.default_rng(seed)).random_base2(m)
        name, text = "sobol", f"{len(points)} scrambled Sobol points"
    evaluator.stage = f"global ({text})"
    outcomes = evaluator.outcomes(list(points), evaluator.problem.steps_for(rows))  # only as far as the rows
    residuals = [evaluator.problem.residuals(o)[rows] for o in outcomes]
    costs = np.array([0.5 * float(r @ r) for r in residuals])
    best = int(np.argmin(costs))
    full = evaluator.costs([points[best]])[0]
    return Stage(name, points[best], full, len(points), True, f"best of {text}"), points, costs


def step_levels(problem: FitProblem) -> list[np.ndarray]:
    """The targets of the continuation, as row masks: those up to model step k, for each k from the first with more
    targets than parameters to the last (the last mask: every target)."""
    model_steps = np.array([t.model_step for t in problem.targets])
    p = len(problem.parameters)
    levels = [model_steps <= k for k in sorted(set(model_steps.tolist())) if np.count_nonzero(model_steps <= k) > p]
    return levels or [np.ones(len(model_steps), dtype=bool)]


def basin_starts(points: np.ndarray, costs: np.ndarray, radius: float, count: int) -> list[int]:
    """The lowest points of up to ``count`` distinct basins of a design, best first: the points with no lower
    design point within ``radius``."""
    order = np.argsort(costs, kind="stable")
    starts: list[int] = []
    for rank, i in enumerate(order):
        if not np.any(np.linalg.norm(points[order[:rank]] - points[i], axis=1) <= radius):
            starts.append(int(i))
        if len(starts) == count:
            break
    return starts


def misfit_p_value(problem: FitProblem, cost: float) -> float | None:
    """The chance of a chi2 (twice ``cost``) this large from the reference's noise alone (None without a std)."""
    n, p = len(problem.targets), len(problem.parameters)
    if not problem.weighted or n <= p:
        return None
    return float(chi2_distribution.sf(2.0 * cost, n - p))


def _ipop(evaluator: Evaluator, dimension: int, seed: int) -> Stage | None:
    """IPOP-CMA-ES from the box's centre: restarts with the population doubled, within the stated budget."""
    budget = IPOP_SETTINGS["maxfevals"]
    if budget <= 0 or dimension < 2:
        return None
    before = evaluator.evaluations + evaluator.replayed
    evaluator.stage = "global (IPOP-CMA-ES)"
    options = {
        "bounds": [0.0, 1.0], "seed": seed, "popsize": IPOP_SETTINGS["popsize"], "maxfevals": budget,
        "tolx": IPOP_SETTINGS["tolx"], "verbose": -9, "verb_log": 0, "verb_disp": 0,
    }  # fmt: skip
    best, strategy = cma.fmin2(
        None, [0.5] * dimension, IPOP_SETTINGS["sigma0"], options, parallel_objective=evaluator.costs,
        restarts=IPOP_SETTINGS["restarts"], incpopsize=IPOP_SETTINGS["incpopsize"],
    )  # fmt: skip
    used = evaluator.evaluations + evaluator.replayed - before
    return Stage("ipop_cma", np.asarray(best, dtype=float), float(strategy.result.fbest), used, True, "IPOP-CMA-ES")


def _polish(
    evaluator: Evaluator, start: np.ndarray, rows: np.ndarray | None = None, evaluations: int = POLISH_EVALUATIONS
) -> Stage:
    """``least_squares`` from ``start`` on the targets ``rows`` (all by default), at most ``evaluations`` steps."""
    before = evaluator.evaluations + evaluator.replayed
    evaluator.stage = "polish (least squares)"
    kept, steps = slice(None) if rows is None else rows, evaluator.problem.steps_for(rows)
    solution = least_squares(
        lambda u: evaluator.residuals(u, steps)[kept],
        start,
        jac=lambda u: evaluator.jacobian(u, FD_STEP, steps)[kept],
        bounds=(0.0, 1.0),
        method="trf",
        x_scale=1.0,
        max_nfev=evaluations,
        **TOLERANCES,
    )
    used = evaluator.evaluations + evaluator.replayed - before
    return Stage("least_squares", solution.x, float(solution.cost), used, solution.status > 0, str(solution.message))


def _polished(evaluator: Evaluator, start: Stage, levels: list[np.ndarray] | None = None) -> Stage:
    """The polish from ``start``'s point, or that point itself if the polish ends higher (never worse); with
    ``levels``, continued through them: each level's targets polished from the previous level's optimum."""
    u, used = start.u, 0
    for rows in (levels or [])[:-1]:
        stage = _polish(evaluator, u, rows, LEVEL_EVALUATIONS)
        u, used = stage.u, used + stage.evaluations
    polish = _polish(evaluator, u)
    polish.evaluations += used
    if polish.cost > start.cost:
        return Stage("least_squares", start.u, start.cost, polish.evaluations, False, f"kept the {start.name} point")
    return polish


def _multistart(evaluator: Evaluator, dimension: int, seed: int) -> tuple[Stage, list[Stage]]:
    """The design, the polishes of its best basins and of the IPOP restarts' best: (the best global point, the
    distinct polished basins, best first)."""
    levels = step_levels(evaluator.problem)
    design, points, costs = _design(evaluator, dimension, seed, levels[0])
    chosen = basin_starts(points, costs, BASIN_RADIUS, POLISH_STARTS)
    starts = [Stage(design.name, points[i], evaluator.costs([points[i]])[0], 0, True, "") for i in chosen]
    polished = _polish_distinct(evaluator, starts, levels)
    p_value = misfit_p_value(evaluator.problem, polished[0].cost)
    restarts = _ipop(evaluator, dimension, seed) if p_value is not None and p_value < MISFIT_P_VALUE else None
    if restarts is not None:
        polished = _polish_distinct(evaluator, [restarts], levels, polished)
    best_global = design if restarts is None or design.cost <= restarts.cost else restarts
    return best_global, polished


def _polish_distinct(
    evaluator: Evaluator, starts: list[Stage], levels: list[np.ndarray], polished: list[Stage] | None = None
) -> list[Stage]:
    """``polished`` with the continued polish of each start that ends in a basin not yet among them, best first."""
    out = list(polished or [])
    for start in starts:
        stage = _polished(evaluator, start, levels)
        if all(np.max(np.abs(stage.u - other.u)) > SAME_POINT for other in out):
            out.append(stage)
    return sorted(out, key=lambda stage: stage.cost)


def run_fit(evaluator: Evaluator, global_method: str = "multistart", seed: int = SEED) -> FitRun:
    """Fit ``evaluator.problem``: the global stage, the polishes of its basins, the Jacobian at the best."""
    if global_method not in GLOBAL_METHODS:
        raise ConfigError("global_method", f"unknown method {global_method!r}; expected one of {GLOBAL_METHODS}")
    clock = time.perf_counter()
    problem = evaluator.problem
    p = len(problem.parameters)
    start = np.array([q.to_unit(q.start) for q in problem.parameters])
    (start_outcome,) = evaluator.outcomes([start])
    if global_method == "multistart" or p == 1:
        stage, basins = _multistart(evaluator, p, seed)
    else:
        stage = (_de if global_method == "de" else _cma)(evaluator, p, seed)
        basins = [_polished(evaluator, stage)]
    polish = basins[0]
    evaluator.stage = "Jacobian at the optimum"
    jacobian = evaluator.jacobian(polish.u, FD_STEP)
    (best_outcome,) = evaluator.outcomes([polish.u])
    evaluator.save()
    return FitRun(
        problem, stage, polish, problem.residuals(best_outcome), jacobian, start_outcome, best_outcome,
        evaluator.evaluations, evaluator.replayed, time.perf_counter() - clock, global_method, seed, basins,
    )  # fmt: skip
