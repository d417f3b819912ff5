"""Sobol indices of the study's outputs: first-order and total, with bootstrap confidence intervals.

The estimator is SALib's (``SALib.analyze.sobol``, SALib >= 1.5): Saltelli's (2010) first-order and Jansen's
(1999) total-effect estimators on the Saltelli design of :mod:`.sampling`, with bootstrap confidence
intervals (``RESAMPLES`` resamples of the base points). SALib is the field's reference implementation;
``scipy.stats.sobol_indices`` computes the same estimators but takes a function to call rather than the
outputs of runs already made, so it could not be fed resumed, recorded runs (docs/experiments.md).

Failed samples are never dropped silently. A continuous output (the steady period, the speed) is defined only
for a sample that walked. Key i's estimators read the rows A, AB_i and B of each block, so its indices are
computed (SALib on that key alone) on the blocks whose three rows walked, and say so (``blocks_used``: the
fewest over the keys, of ``blocks``); when fewer than ``MIN_BLOCK_FRACTION`` of the blocks qualify for a key,
most samples fell and the output gets no indices, only that note. The variance each key's indices divide by
is that of its own subset's A and B rows; with every sample walking it is the whole design's, and the indices
are SALib's on the whole design. The survival indicator (1 walked,
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
    """Indices of ``y``, key by key on the blocks whose A, AB_i and B rows are ``ok`` (the rows that key's
    estimators read), or the reason there are none."""
    blocks_y, blocks_ok = _blocks(y, dimensions + 2), _blocks(ok, dimensions + 2)
    per_key: list[dict[str, np.ndarray]] = []
    used = []
    for i in range(dimensions):
        columns = [0, 1 + i, dimensions + 1]  # A, AB_i, B
        keep = blocks_ok[:, columns].all(axis=1)
        used.append(int(np.count_nonzero(keep)))
        if used[-1] < MIN_BLOCK_FRACTION * len(keep):
            reason = f"most samples fell or lack it: for key {i + 1} only {used[-1]} of {len(keep)} blocks; no indices"
            return OutputIndices(name, min(used), len(keep), subset, None, reason)
        y_kept = blocks_y[keep][:, columns].ravel()
        if np.ptp(y_kept) == 0.0:
            return OutputIndices(name, min(used), len(keep), subset, None, "the output does not vary over the samples")
        per_key.append(saltelli_indices(y_kept, 1, seed))
    indices = {field: np.array([k[field][0] for k in per_key]) for field in ("S1", "S1_conf", "ST", "ST_conf")}
    return OutputIndices(name, min(used), len(blocks_ok), subset, indices)


def sobol_study(outputs: Sequence[dict[str, Any]], keys: Sequence[str], base: int, seed: int) -> SobolIndices:
    """The indices of the continuous outputs (on the walking blocks) and of survival (on every block)."""
    d = len(keys)
    walks = walking_mask(outputs)
    results = []
    for name in INDEX_OUTPUTS:
        y = column(outputs, name)
        ok = walks & np.isfinite(y)
        subset = "per key, the blocks whose A, AB_i and B samples walked"
        results.append(output_indices(name, np.where(ok, y, 0.0), ok, d, seed, subset))
    results.append(output_indices(SURVIVAL, walks.astype(float), np.ones_like(walks), d, seed, "every sample"))
    notes = [
        f"Sobol indices: {base} base points x ({d} keys + 2) = {len(outputs)} runs; "
        + "; ".join(f"{o.output} on {o.blocks_used}/{o.blocks} blocks" for o in results if o.indices is not None)
    ]
    notes += [f"{o.output}: {o.reason}" for o in results if o.indices is None]
    return SobolIndices(tuple(keys), base, len(outputs), results, notes)
