"""What the samples say: per output the mean (with its standard error), standard deviation, quantiles and range
over the walking samples; the probability of walking with a Wilson interval; the samples per status; and the
step-period bands (50 and 90 %) against step number.

Statistics of an output are taken over the samples that walked (status ``walking``) and have the output (a
run too short for ``STEADY_STEPS`` steps has no steady period): a fallen walker has no steady period. How many
samples each statistic used is part of it (``n``). The standard error of the mean is ``sd / sqrt(n)``, that
of independent samples: quasi-Monte Carlo designs are at least as accurate, so it is an upper estimate.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import stats

QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
BAND_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)  # the 90 % band, the 50 % band and the median
CONFIDENCE = 0.95


def column(outputs: Sequence[dict[str, Any]], name: str) -> np.ndarray:
    """Output ``name`` of every sample (NaN where a sample has none)."""
    return np.array([math.nan if o.get(name) is None else float(o[name]) for o in outputs], dtype=np.float64)


def walking_mask(outputs: Sequence[dict[str, Any]]) -> np.ndarray:
    """Which samples walked to the end of their run."""
    return np.array([o["status"] == "walking" for o in outputs], dtype=bool)


def wilson_interval(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson's score interval of a binomial proportion (well behaved at 0 and 1, unlike p +- z se)."""
    if n == 0:
        return (0.0, 1.0)
    z = float(stats.norm.ppf(0.5 + confidence / 2.0))
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def describe(values: np.ndarray) -> dict[str, Any]:
    """Mean, its standard error, sd, quantiles, min and max of the finite ``values`` (None for none)."""
    finite = values[np.isfinite(values)]
    n = int(finite.size)
    if n == 0:
        return {"n": 0, "mean": None}
    sd = float(np.std(finite, ddof=1)) if n > 1 else 0.0
    return {
        "n": n,
        "mean": float(np.mean(finite)),
        "mean_se": sd / math.sqrt(n),
        "sd": sd,
        "quantiles": {f"{q:g}": float(np.quantile(finite, q)) for q in QUANTILES},
        "min": float(np.min(finite)),
        "max": float(np.max(finite)),
    }


def statistics(outputs: Sequence[dict[str, Any]], names: Sequence[str]) -> dict[str, Any]:
    """The study's statistics: the counts per status, the probability of walking and each output described."""
    walking = walking_mask(outputs)
    n, k = len(outputs), int(np.count_nonzero(walking))
    low, high = wilson_interval(k, n)
    return {
        "n_samples": n,
        "status_counts": dict(sorted(Counter(o["status"] for o in outputs).items())),
        "probability_walking": {"value": k / n if n else math.nan, "ci": [low, high], "confidence": CONFIDENCE},
        "outputs": {name: describe(np.where(walking, column(outputs, name), np.nan)) for name in names},
    }


def period_matrix(outputs: Sequence[dict[str, Any]]) -> np.ndarray:
    """Step periods (samples x step number), NaN past a sample's last step."""
    longest = max((len(o["periods"]) for o in outputs), default=0)
    matrix = np.full((len(outputs), longest), np.nan)
    for i, o in enumerate(outputs):
        matrix[i, : len(o["periods"])] = o["periods"]
    return matrix


def period_bands(outputs: Sequence[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Quantiles (``BAND_QUANTILES``) of the walking samples' step period at each step number, and how many
    samples reached it (``count``); steps reached by fewer than half of them are left out."""
    matrix = period_matrix([o for o in outputs if o["status"] == "walking"])
    if matrix.size == 0:
        return {"step": np.zeros(0), "count": np.zeros(0), "quantiles": np.zeros((len(BAND_QUANTILES), 0))}
    count = np.count_nonzero(np.isfinite(matrix), axis=0)
    keep = count >= max(1, matrix.shape[0] // 2)
    quantiles = np.nanquantile(matrix[:, keep], BAND_QUANTILES, axis=0)
    return {"step": np.flatnonzero(keep) + 1.0, "count": count[keep].astype(float), "quantiles": quantiles}
