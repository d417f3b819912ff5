"""Sobol indices of the study's outputs: first-order and total, with bootstrap confidence intervals.

The estimator is SALib's (``SALib.analyze.sobol``, SALib >= 1.5): Saltelli's (2010) first-order and Jansen's
(1999) total-effect estimators on the Saltelli design of :mod:`.sampling`, with bootstrap confidence
intervals (``RESAMPLES`` resamples of the base points). SALib is the field's reference implementation;
``scipy.stats.sobol_indices`` computes the same estimators but takes a function to call rather than the
outputs of runs already made, so it could not be fed resumed, recorded runs (docs/experiments.md).

Failed samples are never dropped silently. A continuous output (the steady period, the speed) is defined only
for a sample that walked, so its indices are computed on the base points whose whole block (A, every AB_i, B)
walked, and say so (``blocks_used`` of ``blocks``); when fewer than ``MIN_BLOCK_FRACTION`` of the blocks
qualify, most samples fell and the output gets no indices, only that note. The survival indicator (1 walked,
0 did not) is defined for every sample, and its indices, over all blocks, say which keys decide survival.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from biped_sim.studies.uncertainty.sampling import unit_problem
from biped_sim.studies.uncertainty.statistics import column, walking_mask

RESAMPLES = 500
CONFIDENCE = 0.95
MIN_BLOCK_FRACTION = 0.5
INDEX_OUTPUTS = ("steady_period", "speed")
SURVIVAL = "walks"


def saltelli_indices(y: np.ndarray, dimensions: int, seed: int, resamples: int = RESAMPLES) -> dict[str, np.ndarray]:
    """S1, S1_conf, ST, ST_conf of outputs ``y`` on a Saltelli design (``dimensions + 2`` rows a block)."""
    from SALib.analyze import sobol  # SALib: only the Sobol-index studies need it

    with warnings.catch_warnings():  # SALib warns of a sample count that is not a power of two (a subset)
        warnings.simplefilter("ignore")
        result = sobol.analyze(
            unit_problem(dimensions), np.asarray(y, dtype=np.float64), calc_second_order=False, num_resamples=resamples,
            conf_level=CONFIDENCE, seed=seed, print_to_console=False,
        )  # fmt: skip
    return {name: np.asarray(result[name], dtype=np.float64) for name in ("S1", "S1_conf", "ST", "ST_conf")}


@dataclass
class OutputIndices:
    """One output's indices per key (None when they could not be computed; ``reason`` says why)."""

    output: str
    blocks_used: int
    blocks: int
    subset: str
    indices: dict[str, np.ndarray] | None
    reason: str | None = None

    def to_json(self, keys: Sequence[str]) -> dict[str, Any]:
        doc: dict[str, Any] = {"blocks_used": self.blocks_used, "blocks": self.blocks, "subset": self.subset}
        if self.indices is None:
            return {**doc, "indices": None, "reason": self.reason}
        per_key = {key: {name: float(values[j]) for name, values in self.indices.items()} for j, key in enumerate(keys)}
        return {**doc, "indices": per_key, "ranking_total": ranking(self, keys)}


def ranking(output: OutputIndices, keys: Sequence[str]) -> list[str]:
    """The keys by total index, largest first."""
    if output.indices is None:
        return []
    return [keys[j] for j in np.argsort(-output.indices["ST"], kind="stable")]


@dataclass
class SobolIndices:
    """The indices of every output, the design's cost, and the notes on subsets and failures."""

    keys: tuple[str, ...]
    base_samples: int
    runs: int
    outputs: list[OutputIndices]
    notes: list[str] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {
            "estimator": "SALib.analyze.sobol (Saltelli 2010 first order, Jansen total; bootstrap CIs)",
            "confidence": CONFIDENCE,
            "resamples": RESAMPLES,
            "base_samples": self.base_samples,
            "runs": self.runs,
            "outputs": {o.output: o.to_json(self.keys) for o in self.outputs},
        }


def _blocks(values: np.ndarray, size: int) -> np.ndarray:
    return values.reshape(-1, size)


def output_indices(name: str, y: np.ndarray, ok: np.ndarray, dimensions: int, seed: int, subset: str) -> OutputIndices:
    """Indices of ``y`` on the blocks where every row is ``ok``, or the reason there are none."""
    size = dimensions + 2
    keep = _blocks(ok, size).all(axis=1)
    used, blocks = int(np.count_nonzero(keep)), keep.size
    if used < MIN_BLOCK_FRACTION * blocks:
        reason = f"most samples fell or lack it: only {used} of {blocks} blocks complete; no indices"
        return OutputIndices(name, used, blocks, subset, None, reason)
    y_kept = _blocks(y, size)[keep].ravel()
    if np.ptp(y_kept) == 0.0:
        return OutputIndices(name, used, blocks, subset, None, "the output does not vary over the samples")
    return OutputIndices(name, used, blocks, subset, saltelli_indices(y_kept, dimensions, seed))


def sobol_study(outputs: Sequence[dict[str, Any]], keys: Sequence[str], base: int, seed: int) -> SobolIndices:
    """The indices of the continuous outputs (on the walking blocks) and of survival (on every block)."""
    d = len(keys)
    walks = walking_mask(outputs)
    results = []
    for name in INDEX_OUTPUTS:
        y = column(outputs, name)
        ok = walks & np.isfinite(y)
        results.append(output_indices(name, np.where(ok, y, 0.0), ok, d, seed, "blocks whose every sample walked"))
    results.append(output_indices(SURVIVAL, walks.astype(float), np.ones_like(walks), d, seed, "every sample"))
    notes = [
        f"Sobol indices: {base} base points x ({d} keys + 2) = {len(outputs)} runs; "
        + "; ".join(f"{o.output} on {o.blocks_used}/{o.blocks} blocks" for o in results if o.indices is not None)
    ]
    notes += [f"{o.output}: {o.reason}" for o in results if o.indices is None]
    return SobolIndices(tuple(keys), base, len(outputs), results, notes)
