"""The Bayesian mode of a fit: posterior samples of the fitted keys by emcee's affine-invariant ensemble sampler.

Likelihood: independent Gaussians per target, ``log L = -|r|^2 / 2`` with the residuals of the fit
(model minus measured mean, over the mean's standard error ``std / sqrt(n_trials)``): it needs the
reference's std. Priors: uniform over the bounds in the fit's variable (uniform in value, or in log
value for a key fitted on a log scale), or a given normal prior on the value, truncated to the bounds.
The walkers start in a small ball around the least-squares optimum; the sampler's pool is a ``map`` that
runs each half-ensemble as one batch on the fit's :class:`~biped_sim.studies.fit.evaluate.Evaluator`
(the executor, the cache and the checkpoint: an interrupted sampler replays its finished evaluations,
seeded, along the same chain). ``draws`` is the chain's length in evaluations (walkers x steps); the
burn-in (twice the longest autocorrelation time) is discarded and the rest thinned by half the shortest.
A chain shorter than ``TAU_FACTOR`` autocorrelation times gets a warning (emcee's advice: 50).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import emcee
import numpy as np

from biped_sim.errors import ConfigError
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.parameters import FitParameter, same_key
from biped_sim.studies.fit.problem import FitProblem

TAU_FACTOR = 50
BALL_SD = 1e-3  # the walkers' initial spread around the optimum, in normalised units (at most)
INTERVAL = (0.05, 0.5, 0.95)  # the 90 % credible interval and the median
CORRELATION_FLAG = 0.99  # posterior correlations beyond this: the data hardly separate the two (as the fit's)
PRIOR_DOMINATED = 0.5  # a 90 % interval wider than this fraction of the bound range: barely constrained
PREDICTIVE_DRAWS = 200
MIN_ACCEPTANCE = 0.15
SAMPLER_SEED = 7


@dataclass(frozen=True)
class Prior:
    """A prior on one fitted key: ``bounds`` (uniform in the fit's variable) or ``normal`` (mean, sd, in value)."""

    key: str
    kind: str = "bounds"
    mean: float = math.nan
    sd: float = math.nan

    def log_density(self, parameter: FitParameter, u: float) -> float:
        """log prior density of the normalised variable ``u`` (the Jacobian of the map included)."""
        if not 0.0 <= u <= 1.0:
            return -math.inf
        if self.kind == "bounds":
            return 0.0
        value = parameter.from_unit(u)
        return -0.5 * ((value - self.mean) / self.sd) ** 2 + math.log(abs(parameter.slope(u)))


def parse_prior(text: str) -> Prior:
    """``KEY=normal:MEAN:SD`` or ``KEY=bounds``."""
    key, sep, spec = text.partition("=")
    parts = spec.split(":")
    if not sep or not key.strip():
        raise ConfigError("priors", f"expected KEY=normal:MEAN:SD or KEY=bounds, got {text[:60]!r}")
    key = key.strip()
    if parts == ["bounds"]:
        return Prior(key)
    if parts[0] != "normal" or len(parts) != 3:
        raise ConfigError(key, f"prior {spec[:40]!r}: expected normal:MEAN:SD or bounds")
    try:
        mean, sd = float(parts[1]), float(parts[2])
    except ValueError:
        raise ConfigError(key, f"prior {spec[:40]!r}: MEAN and SD must be numbers") from None
    if not (math.isfinite(mean) and math.isfinite(sd) and sd > 0):
        raise ConfigError(key, "prior: MEAN must be finite and SD finite and > 0")
    return Prior(key, "normal", mean, sd)


def priors_for(parameters: tuple[FitParameter, ...], given: tuple[Prior, ...] = ()) -> tuple[Prior, ...]:
    """One prior per parameter: the given ones (each for a fitted key, once), bounds for the rest."""
    keys = [p.key for p in parameters]
    fitted = [same_key(k) for k in keys]
    for prior in given:
        if same_key(prior.key) not in fitted:
            raise ConfigError(prior.key, f"a prior for a key that is not fitted (fitted: {', '.join(keys)})")
    named = {same_key(p.key): p for p in given}
    if len(named) != len(given):
        raise ConfigError("priors", "a key has two priors")
    return tuple(replace(named[f], key=k) if f in named else Prior(k) for k, f in zip(keys, fitted, strict=True))


@dataclass
class PosteriorRun:
    """The chain, the retained draws (values), their log posterior, intervals, diagnostics and warnings."""

    keys: tuple[str, ...]
    chain: np.ndarray  # (steps, walkers, p) in values
    chain_log_probability: np.ndarray  # (steps, walkers)
    samples: np.ndarray  # (n, p) retained, in values
    log_probability: np.ndarray  # (n,)
    samples_u: np.ndarray  # (n, p) retained, normalised
    acceptance: float
    autocorrelation: list[float]
    discard: int
    thin: int
    seed: int
    evaluations: int
    intervals: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    correlation: np.ndarray | None = None
    warnings: list[str] = field(default_factory=list)
    priors: tuple[Prior, ...] = ()


class _BatchPool:
    """emcee's pool: ``map(log_prob, walkers)`` as one batch of the evaluator (in parallel on its executor)."""

    def __init__(self, log_posterior: Any) -> None:
        self.log_posterior = log_posterior

    def map(self, _func: Any, points: Any) -> list[float]:
        return self.log_posterior(list(points))


def _log_posterior(evaluator: Evaluator, priors: tuple[Prior, ...]) -> Any:
    problem = evaluator.problem

    def batch(points: list[np.ndarray]) -> list[float]:
        out = [sum(pr.log_density(pa, float(x)) for pr, pa, x in zip(priors, problem.parameters, u, strict=True))
               for u in points]  # fmt: skip
        inside = [i for i, lp in enumerate(out) if math.isfinite(lp)]
        for i, outcome in zip(inside, evaluator.outcomes([points[i] for i in inside]), strict=True):
            out[i] -= evaluator.cost_of(outcome)
        return out

    return batch


def _ball(problem: FitProblem, u0: np.ndarray, se_u: np.ndarray, walkers: int, rng: np.random.Generator) -> np.ndarray:
    spread = np.where(np.isfinite(se_u) & (se_u > 0), np.minimum(se_u, BALL_SD), BALL_SD)
    ball = u0 + spread * rng.standard_normal((walkers, len(u0)))
    return np.clip(ball, 1e-9, 1 - 1e-9)


def _diagnose(run: PosteriorRun, steps: int, parameters: tuple[FitParameter, ...]) -> None:
    tau = max(run.autocorrelation) if run.autocorrelation else math.inf
    if not steps >= TAU_FACTOR * tau:
        run.warnings.append(
            f"chain too short: {steps} steps per walker < {TAU_FACTOR} autocorrelation times ({tau:.1f}); "
            "the intervals are rough (sample more)"
        )
    if run.acceptance < MIN_ACCEPTANCE:
        run.warnings.append(f"acceptance fraction {run.acceptance:.2f} below {MIN_ACCEPTANCE}: the walkers are stuck")
    p = len(run.keys)
    if p > 1 and len(run.samples) > p:
        run.correlation = np.corrcoef(run.samples.T)
        for i in range(p):
            for j in range(i + 1, p):
                if abs(run.correlation[i, j]) > CORRELATION_FLAG:
                    c = run.correlation[i, j]
                    run.warnings.append(f"{run.keys[i]} and {run.keys[j]} correlate at {c:+.3f}: hardly separable")
    for parameter in parameters:
        lo, _, hi = run.intervals[parameter.key]
        span = parameter.to_unit(hi) - parameter.to_unit(lo)
        if span > PRIOR_DOMINATED:
            run.warnings.append(
                f"{parameter.key}: the 90 % interval spans {span:.0%} of its bounds: barely constrained"
            )


def sampler_size(problem: FitProblem, draws: int, walkers: int | None) -> tuple[int, int]:
    """(walkers, steps) of the sampler for ``draws`` posterior draws; ConfigError naming the argument at fault
    (checked before a fit starts, so that no fit runs only to be refused at its posterior)."""
    if not problem.weighted:
        raise ConfigError(str(problem.reference.path), "a Bayesian fit needs a std for every measured quantity")
    p = len(problem.parameters)
    walkers = max(16, 4 * p) if walkers is None else walkers
    if walkers < 2 * p or walkers % 2:
        raise ConfigError("walkers", f"must be even and at least {2 * p} (twice the parameters)")
    steps = math.ceil(draws / walkers)
    if steps < 10:
        raise ConfigError("draws", f"at least {10 * walkers} ({walkers} walkers x 10 steps)")
    return walkers, steps


def sample_posterior(
    evaluator: Evaluator,
    u0: np.ndarray,
    se_u: np.ndarray,
    draws: int = 4000,
    walkers: int | None = None,
    priors: tuple[Prior, ...] = (),
    seed: int = SAMPLER_SEED,
) -> PosteriorRun:
    """Sample the posterior of ``evaluator.problem`` from around the optimum ``u0`` (normalised)."""
    problem = evaluator.problem
    walkers, steps = sampler_size(problem, draws, walkers)
    p = len(problem.parameters)
    priors = priors_for(problem.parameters, priors)
    before = evaluator.evaluations + evaluator.replayed
    evaluator.stage = "posterior (emcee)"
    sampler = emcee.EnsembleSampler(walkers, p, lambda u: 0.0, pool=_BatchPool(_log_posterior(evaluator, priors)))
    sampler.random_state = np.random.RandomState(seed).get_state()
    sampler.run_mcmc(_ball(problem, u0, se_u, walkers, np.random.default_rng(seed)), steps, progress=False)
    evaluator.save()
    tau = [float(t) for t in np.atleast_1d(sampler.get_autocorr_time(tol=0, quiet=True))]
    discard = min(math.ceil(2 * max(tau)) if all(map(math.isfinite, tau)) else steps // 2, steps // 2)
    thin = max(1, int(min(tau) / 2)) if all(map(math.isfinite, tau)) else 1
    flat_u = sampler.get_chain(discard=discard, thin=thin, flat=True)
    to_values = np.vectorize(lambda j, u: problem.parameters[j].from_unit(u))
    columns = np.arange(p)[None, :]
    chain_u = sampler.get_chain()
    run = PosteriorRun(
        keys=tuple(q.key for q in problem.parameters),
        chain=to_values(np.broadcast_to(columns[None], chain_u.shape), chain_u),
        chain_log_probability=sampler.get_log_prob(),
        samples=to_values(np.broadcast_to(columns, flat_u.shape), flat_u),
        log_probability=sampler.get_log_prob(discard=discard, thin=thin, flat=True),
        samples_u=flat_u,
        acceptance=float(np.mean(sampler.acceptance_fraction)),
        autocorrelation=tau,
        discard=discard,
        thin=thin,
        seed=seed,
        evaluations=evaluator.evaluations + evaluator.replayed - before,
        priors=priors,
    )
    for j, key in enumerate(run.keys):
        run.intervals[key] = tuple(float(q) for q in np.quantile(run.samples[:, j], INTERVAL))  # type: ignore[assignment]
    _diagnose(run, steps, problem.parameters)
    return run


def predictive_band(evaluator: Evaluator, run: PosteriorRun, seed: int = SAMPLER_SEED) -> dict[str, np.ndarray]:
    """Per target, the 5/50/95 % quantiles of the model over posterior draws (``model``) and of a new measured
    mean (``predictive``: the model plus the mean's noise); the draws were evaluated by the chain already."""
    problem = evaluator.problem
    rng = np.random.default_rng(seed)
    picks = rng.choice(len(run.samples_u), size=min(PREDICTIVE_DRAWS, len(run.samples_u)), replace=False)
    model = np.array([problem.model_values(o) for o in evaluator.outcomes([run.samples_u[i] for i in picks])])
    noisy = model + problem.sigma[None, :] * rng.standard_normal(model.shape)
    return {
        "model": np.nanquantile(model, INTERVAL, axis=0),
        "predictive": np.nanquantile(noisy, INTERVAL, axis=0),
    }
