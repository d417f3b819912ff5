"""Fitting config parameters to a reference's step periods: bounded least squares from several starts.

A :class:`FitProblem` names numeric config keys with bounds (:class:`FitParameter`), a step-period
reference and the model steps to skip. Each evaluation simulates the config with the parameters set,
only as far as the last reference step (``simulation.max_steps``), and gives one residual per reference
step, ``r_k = (T_model_k - T_ref_k) / sigma_k`` (sigma: the reference's std, else 1 s). A walker that
falls, diverges or times out before reference step k has no period there: its residual is the finite
penalty ``PENALTY_PERIODS * T_ref_k * (2 - reached) / sigma_k``, where ``reached`` in [0, 1] is how far
(in time) it got towards that step, so the penalty shrinks as the walker gets further.

The optimizer (:func:`scipy.optimize.least_squares`, trust-region reflective) works in variables
normalised to [0, 1] over the bounds, logarithmically for positive bounds spanning a decade or more
(stiffness-like scales). Its Jacobian is forward differences with a step of ``FD_STEP`` of the
normalised range (backwards at the upper bound): well above the integrator's noise (the default rtol
1e-8 moves a period by ~1e-8 s, i.e. ~1e-5 s per unit of a normalised variable at this step) and small
against the parameters' ranges. The p difference runs go to an :class:`~concurrent.futures.Executor`
as one batch when one is given (the sweep layer's local pool or Dask), else run here one by one.
Several starts (``starts > 1``) add a Latin hypercube design (:mod:`scipy.stats.qmc`, seed ``QMC_SEED``)
to the config's own values; the best fit wins. Statistics are in :mod:`biped_sim.studies.fit_stats`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import yaml
from pydantic import ValidationError
from scipy.optimize import least_squares
from scipy.stats import qmc

from biped_sim.config import Config, apply_override, config_from_dict
from biped_sim.errors import ConfigError
from biped_sim.io.references import Reference
from biped_sim.simulate import simulate
from biped_sim.studies.compare import model_step_periods

FD_STEP = 1e-3  # forward-difference step, in normalised variables (see the module docstring)
PENALTY_PERIODS = 2.0  # a missing step costs 2 to 4 of its reference periods (see the module docstring)
LOG_SPAN = 10.0  # bounds 0 < LO with HI / LO >= LOG_SPAN are fitted in log(value)
QMC_SEED = 11  # the multistart design's seed (recorded in fit.json)
MAX_RESIDUAL_EVALUATIONS = 40  # least_squares' max_nfev per start (each Jacobian costs p more runs)
TOLERANCES = {"ftol": 1e-8, "xtol": 1e-6, "gtol": 1e-8}
EVALUATION_SAMPLE_RATE = 10.0  # Hz: a fit reads only the strike times, which do not depend on sampling
REACH_MARGIN = 2.0  # an evaluation may run for this many times the reference's duration before giving up


@dataclass(frozen=True)
class FitParameter:
    """A config key fitted within [low, high], from ``start`` (the config's own value)."""

    key: str
    low: float
    high: float
    start: float

    @property
    def log(self) -> bool:
        """Whether the key is fitted in log(value): positive bounds spanning a decade or more."""
        return self.low > 0 and self.high / self.low >= LOG_SPAN

    def to_unit(self, value: float) -> float:
        """The value as a normalised variable in [0, 1] over the bounds."""
        if self.log:
            return math.log(value / self.low) / math.log(self.high / self.low)
        return (value - self.low) / (self.high - self.low)

    def from_unit(self, u: float) -> float:
        """The value of normalised variable ``u`` (clipped to the bounds)."""
        u = min(max(u, 0.0), 1.0)
        if self.log:
            return self.low * (self.high / self.low) ** u
        return self.low + u * (self.high - self.low)

    def slope(self, u: float) -> float:
        """d value / d u at ``u`` (to carry a covariance from normalised to the parameter's units)."""
        if self.log:
            return self.from_unit(u) * math.log(self.high / self.low)
        return self.high - self.low


def numeric_value(data: dict[str, Any], key: str) -> float:
    """The real-valued entry ``key`` (dotted) of a resolved config dict; ConfigError if unknown or not a real."""
    node: Any = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise ConfigError("--param", f"unknown config key {key!r}")
        node = node[part]
    if node is None:
        raise ConfigError("--param", f"{key} has no value in the config to start from: give one with --set")
    if isinstance(node, bool) or not isinstance(node, float):
        raise ConfigError("--param", f"{key} is not a real-valued parameter (its value is {node!r})")
    return node


def parse_parameter(text: str, config: Config) -> FitParameter:
    """``KEY=LO:HI`` against the resolved ``config`` (start: its value of KEY); ConfigError naming the fault."""
    key, sep, bounds = text.partition("=")
    low_text, colon, high_text = bounds.partition(":")
    if not sep or not colon or not key.strip():
        raise ConfigError("--param", f"expected KEY=LO:HI, got {text!r}")
    key = key.strip()
    try:
        low, high = float(low_text), float(high_text)
    except ValueError:
        raise ConfigError("--param", f"{key}: bounds {bounds!r} are not two numbers LO:HI") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise ConfigError("--param", f"{key}: bounds must be finite")
    if low >= high:
        raise ConfigError("--param", f"{key}: LO ({low:g}) must be below HI ({high:g})")
    data = config.model_dump(mode="json")
    start = numeric_value(data, key)
    if not low <= start <= high:
        raise ConfigError("--param", f"{key}: start {start:g} (the config's value) is outside [{low:g}, {high:g}]")
    for bound in (low, high):
        try:
            config_from_dict(data, [f"{key}={bound!r}"])
        except ConfigError as exc:
            raise ConfigError("--param", f"{key}: bound {bound:g} is not a valid config ({exc})") from None
    return FitParameter(key, low, high, start)


def reference_sigma(reference: Reference) -> np.ndarray:
    """Residual weights: the reference's std per step, else 1 s; ConfigError for a step with std 0."""
    if reference.spec.std is None:
        return np.ones(len(reference.values))
    std = np.asarray(reference.spec.std, dtype=float)
    zero = np.flatnonzero(std == 0)
    if len(zero):
        raise ConfigError(f"{reference.path}: std", f"entry {zero[0] + 1} is 0; a fit weights each step by 1/std")
    return std


@dataclass(frozen=True)
class Outcome:
    """What one evaluation needs from a run: the strike times, how it ended, and how far it got [s]."""

    step_times: tuple[float, ...]
    status: str
    t_reached: float


def simulate_strikes(config_data: dict[str, Any]) -> Outcome:
    """Simulate a resolved config (plain data, so it pickles to a worker); a config the schema refuses (a value
    inside the bounds that another rule forbids) is an outcome that got nowhere, never an exception."""
    try:
        result = simulate(Config.model_validate(config_data))
    except (ConfigError, ValidationError) as exc:
        return Outcome((), f"invalid: {str(exc).splitlines()[0]}", 0.0)
    summary = result.summary
    return Outcome(tuple(summary["step_times"]), summary["status"], float(summary["t_end"]))


@dataclass(frozen=True)
class FitProblem:
    """Fit ``parameters`` of ``config`` to ``reference``'s step periods (model steps ``skip`` + k meet step k)."""

    config: Config
    reference: Reference
    parameters: tuple[FitParameter, ...]
    skip: int = 0

    def __post_init__(self) -> None:
        if not self.reference.is_periods:
            raise ConfigError(str(self.reference.path), "a fit needs a step_period reference")
        if not self.parameters:
            raise ConfigError("--param", "give at least one KEY=LO:HI to fit")
        if self.skip < 0:
            raise ConfigError("--skip-steps", "must be at least 0")
        reference_sigma(self.reference)

    @property
    def sigma(self) -> np.ndarray:
        return reference_sigma(self.reference)

    @property
    def model_steps(self) -> int:
        """Heel strikes an evaluation simulates: as far as the last reference step."""
        return self.skip + max(self.reference.steps)

    def due_times(self) -> np.ndarray:
        """When each reference step would end at the reference's mean period, from the release [s]."""
        mean_period = float(np.mean(self.reference.values))
        return (self.skip + np.asarray(self.reference.steps, dtype=float)) * mean_period

    def values(self, u: Sequence[float]) -> dict[str, float]:
        """Parameter values at normalised point ``u``."""
        return {p.key: p.from_unit(float(x)) for p, x in zip(self.parameters, u, strict=True)}

    def config_at(self, values: dict[str, float]) -> Config:
        """The config with ``values`` set (what fitted.yaml holds)."""
        return config_from_dict(self.config.model_dump(mode="json"), [f"{k}={v!r}" for k, v in values.items()])

    def evaluation_data(self, u: Sequence[float]) -> dict[str, Any]:
        """The config an evaluation runs (plain data): values set, stopping at the last reference step."""
        data = self.config.model_dump(mode="json")
        t_end = max(self.config.simulation.t_end, REACH_MARGIN * float(self.due_times()[-1]))
        overrides = [f"{k}={v!r}" for k, v in self.values(u).items()] + [
            f"simulation.max_steps={self.model_steps}",
            f"simulation.t_end={t_end!r}",
            f"output.sample_rate={EVALUATION_SAMPLE_RATE!r}",
        ]
        for assignment in overrides:
            apply_override(data, assignment)
        return data

    def residuals(self, outcome: Outcome) -> np.ndarray:
        """Weighted residuals per reference step; finite penalties for the steps the walker never reached."""
        periods = model_step_periods(outcome.step_times, self.skip)
        sigma, due = self.sigma, self.due_times()
        out = np.empty(len(self.reference.values))
        for i, (step, period) in enumerate(zip(self.reference.steps, self.reference.values, strict=True)):
            if step <= len(periods):
                out[i] = (periods[step - 1] - period) / sigma[i]
            else:
                reached = min(max(outcome.t_reached / due[i], 0.0), 1.0)
                out[i] = PENALTY_PERIODS * period * (2.0 - reached) / sigma[i]
        return out


@dataclass
class Evaluator:
    """Runs evaluations (cached by point, counted), serially or as batches on an executor."""

    problem: FitProblem
    executor: Executor | None = None
    cache: dict[bytes, Outcome] = field(default_factory=dict)
    evaluations: int = 0

    def outcomes(self, points: Sequence[np.ndarray]) -> list[Outcome]:
        """The outcome at each point; the points not yet run are run together (in parallel on the executor)."""
        todo: dict[bytes, np.ndarray] = {}
        for u in points:
            key = np.asarray(u, dtype=float).tobytes()
            if key not in self.cache:
                todo[key] = np.asarray(u, dtype=float)
        tasks = [self.problem.evaluation_data(u) for u in todo.values()]
        if self.executor is None or len(tasks) < 2:
            results = [simulate_strikes(task) for task in tasks]
        else:
            futures = [self.executor.submit(simulate_strikes, task) for task in tasks]
            results = [future.result() for future in futures]
        self.cache.update(zip(todo, results, strict=True))
        self.evaluations += len(tasks)
        return [self.cache[np.asarray(u, dtype=float).tobytes()] for u in points]

    def residuals(self, u: np.ndarray) -> np.ndarray:
        return self.problem.residuals(self.outcomes([u])[0])

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """Forward differences (backwards at the upper bound), the p shifted runs as one batch."""
        u = np.asarray(u, dtype=float)
        steps = np.where(u + FD_STEP <= 1.0, FD_STEP, -FD_STEP)
        shifted = [u + steps[j] * np.eye(len(u))[j] for j in range(len(u))]
        outcomes = self.outcomes([u, *shifted])
        base = self.problem.residuals(outcomes[0])
        columns = [(self.problem.residuals(o) - base) / steps[j] for j, o in enumerate(outcomes[1:])]
        return np.column_stack(columns)


@dataclass
class StartResult:
    """One start's least-squares solution (normalised variables) and scipy's verdict."""

    start: np.ndarray
    u: np.ndarray
    residuals: np.ndarray
    jacobian: np.ndarray
    cost: float
    status: int
    message: str
    residual_evaluations: int


def start_points(problem: FitProblem, starts: int) -> np.ndarray:
    """The config's own values, then ``starts - 1`` points of a seeded Latin hypercube over the bounds."""
    first = np.array([[p.to_unit(p.start) for p in problem.parameters]])
    if starts <= 1:
        return first
    design = qmc.LatinHypercube(d=len(problem.parameters), seed=QMC_SEED).random(starts - 1)
    return np.vstack([first, design])


def fit_from(evaluator: Evaluator, start: np.ndarray) -> StartResult:
    """Bounded least squares from one start."""
    solution = least_squares(
        evaluator.residuals,
        start,
        jac=evaluator.jacobian,
        bounds=(0.0, 1.0),
        method="trf",
        x_scale=1.0,
        max_nfev=MAX_RESIDUAL_EVALUATIONS,
        **TOLERANCES,
    )
    return StartResult(
        start=start,
        u=solution.x,
        residuals=solution.fun,
        jacobian=evaluator.jacobian(solution.x),
        cost=float(solution.cost),
        status=int(solution.status),
        message=str(solution.message),
        residual_evaluations=int(solution.nfev),
    )


@dataclass
class FitRun:
    """Every start's solution, the best one, and the evaluations (simulations) used."""

    problem: FitProblem
    starts: list[StartResult]
    evaluations: int
    start_outcome: Outcome
    best_outcome: Outcome
    wall_time_s: float

    @property
    def best(self) -> StartResult:
        return min(self.starts, key=lambda s: s.cost)


def run_fit(
    problem: FitProblem,
    starts: int = 1,
    executor: Executor | None = None,
    progress: Callable[[int, StartResult], None] | None = None,
) -> FitRun:
    """Fit ``problem`` from ``starts`` starts; ``executor`` runs each Jacobian's p difference runs in parallel."""
    clock = time.perf_counter()
    evaluator = Evaluator(problem, executor)
    results = []
    for i, start in enumerate(start_points(problem, starts)):
        results.append(fit_from(evaluator, start))
        if progress is not None:
            progress(i, results[-1])
    best = min(results, key=lambda s: s.cost)
    start_outcome, best_outcome = evaluator.outcomes([start_points(problem, 1)[0], best.u])
    elapsed = time.perf_counter() - clock
    return FitRun(problem, results, evaluator.evaluations, start_outcome, best_outcome, elapsed)


def synthetic_reference_data(config: Config, steps: int, noise_s: float, seed: int, skip: int = 0) -> dict[str, Any]:
    """A reference file's content: ``config``'s own step periods plus Gaussian noise of std ``noise_s``.

    For tests, validation and worked examples of a fit: every text field says it was generated by biped-sim
    from the config's values, never measured. ``std`` is ``noise_s`` per step (when > 0).
    """
    data = config.model_dump(mode="json")
    data["simulation"]["max_steps"] = skip + steps
    outcome = simulate_strikes(data)
    periods = model_step_periods(outcome.step_times, skip)
    if len(periods) < steps:
        raise ConfigError("simulation", f"the walker {outcome.status} after {len(periods)} of {steps} steps")
    noisy = np.asarray(periods) + np.random.default_rng(seed).normal(0.0, noise_s, steps)
    origin = f"generated by biped-sim from config {config.hash()}, Gaussian noise std {noise_s:g} s, seed {seed}"
    return {
        "experiment": "synthetic_" + config.walker.kind,
        "description": f"SYNTHETIC step periods, {origin}; not measured data.",
        "citation": {
            "authors": ["biped-sim-synthetic"],
            "title": "Synthetic step periods (not measured)",
            "year": 2026,
        },
        "source": {"kind": "text", "label": None, "details": origin},
        "quantity": {"name": "step_period", "unit": "s", "statistic": "single", "n_trials": 1},
        "values": [round(float(v), 9) for v in noisy],
        **({"std": [noise_s] * steps} if noise_s > 0 else {}),
        "notes": f"Model steps {skip + 1}..{skip + steps} of a simulation; see docs/experiments.md.",
    }


def synthetic_reference(config: Config, steps: int, noise_s: float, seed: int, skip: int = 0) -> str:
    """:func:`synthetic_reference_data` as a reference file's text, with a header saying it is synthetic."""
    doc = synthetic_reference_data(config, steps, noise_s, seed, skip)
    header = f"# SYNTHETIC reference: {doc['source']['details']}.\n# Not measured data.\n"
    return header + yaml.safe_dump(doc, sort_keys=False)
