"""The optimizer of a fit: a bounded global stage, then a local least-squares polish from its best point.

The objective, half the sum of squared weighted residuals, is piecewise smooth in contact parameters (a
rebound or a slip that appears moves the gait) and has cliffs where the walker falls: a local method from
one start walks into the nearest step. The global stage is scipy's ``differential_evolution`` (seeded,
``updating="deferred"`` so that each generation is one batch of simulations on the executor through its
``workers`` map) or CMA-ES from ``cma`` (each generation one batch), over the normalised variables. CMA-ES
is the default, chosen by measurement (docs/experiments.md: it recovered more hidden restitutions for the
same evaluations); a one-parameter fit scans a grid of ``GRID_POINTS`` instead (CMA-ES needs two
dimensions, and in one a grid is the robust answer). The polish is
``least_squares`` (trust-region reflective, bounded to [0, 1]) with forward differences of
``FD_STEP`` of the normalised range, its p difference runs one batch. Everything runs through one
:class:`~biped_sim.studies.fit.evaluate.Evaluator`, so points are never simulated twice and a checkpoint
resumes an interrupted fit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cma
import numpy as np
from scipy.optimize import differential_evolution, least_squares

from biped_sim.errors import ConfigError
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.problem import FitProblem, Outcome

FD_STEP = 1e-3  # forward-difference step of the polish, in normalised variables
GLOBAL_METHODS = ("de", "cma")
DE_SETTINGS = {"popsize": 8, "maxiter": 40, "tol": 1e-3, "atol": 1e-9, "mutation": (0.5, 1.0), "recombination": 0.7}
CMA_SETTINGS = {"sigma0": 0.25, "popsize": 8, "maxfevals": 640, "tolx": 1e-4}
POLISH_EVALUATIONS = 30  # least_squares' max_nfev (each Jacobian costs p more runs)
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


def _grid(evaluator: Evaluator, dimension: int, seed: int) -> Stage:
    """One parameter: a grid of GRID_POINTS over the bounds in one batch (CMA-ES needs two dimensions)."""
    evaluator.stage = "global (grid)"
    points = [np.array([u]) for u in np.linspace(0.0, 1.0, GRID_POINTS)]
    costs = evaluator.costs(points)
    best = int(np.argmin(costs))
    return Stage("grid", points[best], costs[best], len(points), True, f"best of {GRID_POINTS} grid points")


def _polish(evaluator: Evaluator, start: np.ndarray) -> Stage:
    before = evaluator.evaluations + evaluator.replayed
    evaluator.stage = "polish (least squares)"
    solution = least_squares(
        evaluator.residuals,
        start,
        jac=lambda u: evaluator.jacobian(u, FD_STEP),
        bounds=(0.0, 1.0),
        method="trf",
        x_scale=1.0,
        max_nfev=POLISH_EVALUATIONS,
        **TOLERANCES,
    )
    used = evaluator.evaluations + evaluator.replayed - before
    return Stage("least_squares", solution.x, float(solution.cost), used, solution.status > 0, str(solution.message))


def run_fit(evaluator: Evaluator, global_method: str = "cma", seed: int = SEED) -> FitRun:
    """Fit ``evaluator.problem``: the global stage, the polish from its best point, the Jacobian there."""
    if global_method not in GLOBAL_METHODS:
        raise ConfigError("global_method", f"unknown method {global_method!r}; expected one of {GLOBAL_METHODS}")
    clock = time.perf_counter()
    problem = evaluator.problem
    p = len(problem.parameters)
    start = np.array([q.to_unit(q.start) for q in problem.parameters])
    (start_outcome,) = evaluator.outcomes([start])
    stage = (_grid if p == 1 else _de if global_method == "de" else _cma)(evaluator, p, seed)
    polish = _polish(evaluator, stage.u)
    if polish.cost > stage.cost:  # the polish never makes it worse
        polish = Stage("least_squares", stage.u, stage.cost, polish.evaluations, False, "kept the global stage's point")
    evaluator.stage = "Jacobian at the optimum"
    jacobian = evaluator.jacobian(polish.u, FD_STEP)
    (best_outcome,) = evaluator.outcomes([polish.u])
    evaluator.save()
    return FitRun(
        problem, stage, polish, problem.residuals(best_outcome), jacobian, start_outcome, best_outcome,
        evaluator.evaluations, evaluator.replayed, time.perf_counter() - clock, global_method, seed,
    )  # fmt: skip
