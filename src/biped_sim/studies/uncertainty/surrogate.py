"""A cheaper estimate of the Sobol indices: a polynomial-chaos surrogate (chaospy) of an output, fitted to the runs
already made, its indices read from its coefficients (Sudret, Reliab. Eng. Syst. Saf. 93 (2008) 964-979).

The expansion is in the polynomials orthogonal under the keys' distributions, to total degree ``order``,
fitted by least squares (chaospy's ``fit_regression``) to the samples that have the output (a fallen walker has
no steady period: the surrogate is that of the walking region). Its accuracy is measured, not assumed: it is
fitted again without every fifth sample and its relative RMS error on those (``holdout_error``) is reported.
A surrogate needs at least ``SAMPLES_PER_TERM`` samples per polynomial term; fewer, and it says so. The study
reports it beside the sampled (Saltelli) indices, as a check of each by the other.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from biped_sim.studies.uncertainty.distributions import Distribution

SAMPLES_PER_TERM = 2
HOLDOUT_EVERY = 5
DEFAULT_ORDER = 3


def chaos_distribution(dist: Distribution) -> Any:
    """The chaospy distribution of ``dist``."""
    import chaospy  # the surrogate only: an optional estimate

    n = dist.numbers
    if dist.kind in ("uniform", "interval"):
        return chaospy.Uniform(n[0], n[1])
    if dist.kind == "normal":
        return chaospy.Normal(n[0], n[1])
    if dist.kind == "lognormal":
        return chaospy.LogNormal(math.log(n[0]), n[1])
    return chaospy.Triangle(n[0], n[1], n[2])


@dataclass(frozen=True)
class SurrogateIndices:
    """The surrogate's first-order and total indices per key, and how well it fits."""

    output: str
    order: int
    terms: int
    samples: int
    holdout_error: float | None
    s1: np.ndarray | None
    st: np.ndarray | None
    reason: str | None = None

    def to_json(self, keys: Sequence[str]) -> dict[str, Any]:
        doc: dict[str, Any] = {"order": self.order, "terms": self.terms, "samples": self.samples,
                               "holdout_relative_rms_error": self.holdout_error}  # fmt: skip
        if self.s1 is None or self.st is None:
            return {**doc, "indices": None, "reason": self.reason}
        return {**doc, "indices": {k: {"S1": float(self.s1[j]), "ST": float(self.st[j])} for j, k in enumerate(keys)}}


def surrogate_indices(
    name: str, distributions: Sequence[Distribution], values: np.ndarray, y: np.ndarray, order: int = DEFAULT_ORDER
) -> SurrogateIndices:
    """The surrogate of output ``y`` (NaN where a sample has none) over ``values`` (samples x keys)."""
    import chaospy  # the surrogate only: an optional estimate

    joint = chaospy.J(*[chaos_distribution(d) for d in distributions])
    expansion, norms = chaospy.generate_expansion(order, joint, retall=True)
    terms = len(expansion)
    have = np.isfinite(y)
    x, f = values[have].T, y[have]
    if f.size < SAMPLES_PER_TERM * terms:
        reason = f"{f.size} samples for {terms} terms (order {order}): too few for a surrogate"
        return SurrogateIndices(name, order, terms, int(f.size), None, None, None, reason)
    held = np.arange(f.size) % HOLDOUT_EVERY == 0
    trial = chaospy.fit_regression(expansion, x[:, ~held], f[~held])
    error = float(np.sqrt(np.mean((trial(*x[:, held]) - f[held]) ** 2)) / max(np.std(f), 1e-300))
    _, coefficients = chaospy.fit_regression(expansion, x, f, retall=1)
    s1, st = coefficient_indices(expansion, np.asarray(norms) * np.asarray(coefficients) ** 2)
    return SurrogateIndices(name, order, terms, int(f.size), error, s1, st)


def coefficient_indices(expansion: Any, variances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first-order and total indices of an orthogonal expansion from its terms' ``variances`` (coefficient
    squared times the term's norm), as Sudret reads them: a key's first-order share is that of the terms in it
    alone, its total share that of every term it appears in.

    The same numbers as chaospy's ``Sens_m`` and ``Sens_t`` on the fitted polynomial, which integrate its
    conditional expectations symbolically: far slower, and at a high degree slower than the study's runs.
    """
    uses = np.array([np.asarray(term.exponents).max(axis=0) > 0 for term in expansion])  # terms x keys
    alone = uses & (uses.sum(axis=1) == 1)[:, None]
    total = variances[uses.any(axis=1)].sum()
    return variances @ alone / total, variances @ uses / total
