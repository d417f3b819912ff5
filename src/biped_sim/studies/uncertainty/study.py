"""An uncertainty study: what is known of some config keys (distributions, or a fit's posterior samples), the
samples drawn, their runs, and what they say.

:class:`UncertaintySpec` holds the config, the keys and where their samples come from; :func:`run_study` draws
the design (:mod:`.sampling`), maps it through the distributions, runs every sample (:mod:`.samples`, on the
executor passed in, resumable), and returns an :class:`Uncertainty`: the statistics (:mod:`.statistics`) and,
for a Saltelli design, the Sobol indices (:mod:`.sobol`); on request the indices of a polynomial-chaos
surrogate fitted to the same runs (:mod:`.surrogate`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from biped_sim.config import Config
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.io.posterior import Posterior
from biped_sim.simulate.budget import check_run_count
from biped_sim.studies.fit.parameters import numeric_value
from biped_sim.studies.uncertainty.distributions import Distribution, check_distributions
from biped_sim.studies.uncertainty.samples import RIGID_SCALARS, SCALARS, SampleRuns, run_samples
from biped_sim.studies.uncertainty.sampling import block_size, check_count, unit_design
from biped_sim.studies.uncertainty.sobol import INDEX_OUTPUTS, SobolIndices, sobol_study
from biped_sim.studies.uncertainty.statistics import column, period_bands, statistics, walking_mask
from biped_sim.studies.uncertainty.surrogate import SurrogateIndices, surrogate_indices

DEFAULT_SAMPLES = 256


@dataclass(frozen=True)
class UncertaintySpec:
    """The config, its uncertain keys and their samples' source: ``distributions`` (a design of ``samples``
    points by ``method``, seeded) or ``posterior`` (its draws, ``samples`` of them evenly spaced, or all)."""

    config: Config
    distributions: tuple[Distribution, ...] = ()
    samples: int = DEFAULT_SAMPLES
    method: str = "sobol"
    seed: int = 0
    posterior: Posterior | None = None
    surrogate_order: int | None = None  # also a polynomial-chaos surrogate's indices, of this total degree

    def __post_init__(self) -> None:
        if self.posterior is not None:
            if self.distributions:
                raise ArgumentError("posterior", "give distributions or a fit's posterior, not both")
            if self.method == "saltelli":
                reason = "Sobol indices (Saltelli's design) need independent distributions, not a posterior"
                raise ArgumentError("posterior", reason)
            for key in self.posterior.parameters:
                numeric_value(self.config, key)
            if self.samples < 2:
                raise ArgumentError("samples", "need at least 2 samples")
        else:
            check_distributions(self.config, self.distributions)
            check_count(self.samples, self.method)
        check_run_count(self.rows, "samples", "runs (samples x (keys + 2) for Sobol indices)")
        if self.surrogate_order is not None and (self.posterior is not None or not 1 <= self.surrogate_order <= 10):
            raise ArgumentError("surrogate_order", "a surrogate takes distributions and a degree from 1 to 10")

    @property
    def keys(self) -> tuple[str, ...]:
        return self.posterior.parameters if self.posterior is not None else tuple(d.key for d in self.distributions)

    @property
    def rows(self) -> int:
        """How many runs the study makes."""
        if self.posterior is not None:
            return min(self.samples, len(self.posterior.samples))
        return self.samples * block_size(self.method, len(self.distributions))

    def design(self) -> tuple[np.ndarray | None, np.ndarray]:
        """(unit design or None, values): one row per run, one column per key."""
        if self.posterior is not None:
            draws = self.posterior.samples
            pick = np.unique(np.linspace(0, len(draws) - 1, self.rows).round().astype(int))
            return None, np.array(draws[pick], dtype=np.float64)
        unit = unit_design(self.samples, len(self.distributions), self.method, self.seed)
        values = np.column_stack([d.values(unit[:, j]) for j, d in enumerate(self.distributions)])
        return unit, values

    def source(self) -> dict[str, Any]:
        """Where the samples came from, for the study's files."""
        if self.posterior is not None:
            return {"source": "posterior", "keys": list(self.keys), "draws": len(self.posterior.samples)}
        return {
            "source": "distributions",
            "distributions": {d.key: d.text() for d in self.distributions},
            "method": self.method,
            "seed": self.seed,
            "base_samples": self.samples,
        }


@dataclass
class Uncertainty:
    """A finished study: the samples' values and records, their statistics, bands and (Saltelli) indices."""

    spec: UncertaintySpec
    unit: np.ndarray | None
    values: np.ndarray
    runs: SampleRuns
    stats: dict[str, Any]
    bands: dict[str, np.ndarray]
    indices: SobolIndices | None = None
    surrogate: list[SurrogateIndices] = field(default_factory=list)
    wall_time_s: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def outputs(self) -> list[dict[str, Any]]:
        return self.runs.outputs

    def to_pandas(self) -> pd.DataFrame:
        """The statistics as a DataFrame: one row per output, over the samples that walked (``n``, the mean, its
        standard error, the sd, the quantiles ``q0.05`` ... ``q0.95``, min and max)."""
        rows = {}
        for name, described in self.stats["outputs"].items():
            quantiles = {f"q{q}": value for q, value in described.get("quantiles", {}).items()}
            rows[name] = {key: value for key, value in described.items() if key != "quantiles"} | quantiles
        return pd.DataFrame.from_dict(rows, orient="index")

    def samples_frame(self) -> pd.DataFrame:
        """One row per sample: the keys' values, the run's status and its scalar outputs (NaN where it has none)."""
        frame = pd.DataFrame(self.values, columns=list(self.spec.keys))
        frame["status"] = [output["status"] for output in self.outputs]
        for name in output_names(self.spec.config):
            frame[name] = column(self.outputs, name)
        return frame

    def __repr__(self) -> str:
        walking = self.stats["probability_walking"]
        low, high = walking["ci"]
        period = self.stats["outputs"]["steady_period"]
        text = (f"<Uncertainty of {', '.join(self.spec.keys)}: {self.stats['n_samples']} samples, "
                f"P(walking) {walking['value']:.3f} [{low:.3f}, {high:.3f}]")  # fmt: skip
        if period.get("mean") is not None:
            text += f", steady period {period['mean']:.4g} (sd {period['sd']:.2g})"
        return text + ">"

    def to_json(self) -> dict[str, Any]:
        """The document of ``biped-sim uncertainty --json``: the statistics, the indices and the notes."""
        return {
            "walker": self.spec.config.walker.kind,
            "dynamics": self.spec.config.dynamics,
            **self.spec.source(),
            "runs": len(self.values),
            "chunks_reused": self.runs.chunks_reused,
            "statistics": self.stats,
            "sobol": self.indices.to_json() if self.indices is not None else None,
            "surrogate": {s.output: s.to_json(self.spec.keys) for s in self.surrogate} or None,
            "wall_time_s": self.wall_time_s,
            "notes": self.notes,
        }


def output_names(config: Config) -> tuple[str, ...]:
    """The scalar outputs of the config's runs."""
    return SCALARS + (RIGID_SCALARS if config.dynamics == "rigid" else ())


def _notes(spec: UncertaintySpec, stats: dict[str, Any]) -> list[str]:
    counts = stats["status_counts"]
    failed = {k: v for k, v in counts.items() if k != "walking"}
    notes = [
        f"statistics over the {counts.get('walking', 0)} of {stats['n_samples']} samples that walked to the end of "
        "their run; steady period and step length: the mean of the last steps",
    ]
    if failed:
        notes.append("samples that did not walk: " + ", ".join(f"{v} {k}" for k, v in failed.items()))
    if any(d.kind == "interval" for d in spec.distributions):
        notes.append("interval keys are sampled uniformly over their bounds; each output's min and max is its range")
    return notes


def run_study(
    spec: UncertaintySpec,
    out_dir: Path | None,
    executor: Executor | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Uncertainty:
    """Draw the samples, run them (resuming from ``out_dir/samples``), and summarise them."""
    clock = time.perf_counter()
    unit, values = spec.design()
    if not np.all(np.isfinite(values)):
        raise ConfigError("parameters", "a distribution gave non-finite values")
    runs = run_samples(spec.config, spec.keys, values, out_dir, executor, progress)
    stats = statistics(runs.outputs, output_names(spec.config))
    notes = _notes(spec, stats)
    indices = None
    if spec.method == "saltelli" and spec.posterior is None:
        indices = sobol_study(runs.outputs, spec.keys, spec.samples, spec.seed)
        notes += indices.notes
    surrogate = _surrogates(spec, values, runs)
    notes += [f"surrogate of {s.output}: {s.reason}" for s in surrogate if s.reason]
    return Uncertainty(spec, unit, values, runs, stats, period_bands(runs.outputs), indices, surrogate,
                       time.perf_counter() - clock, notes)  # fmt: skip


def _walking(runs: SampleRuns, name: str, walks: np.ndarray) -> np.ndarray:
    return np.where(walks, column(runs.outputs, name), np.nan)


def _surrogates(spec: UncertaintySpec, values: np.ndarray, runs: SampleRuns) -> list[SurrogateIndices]:
    """The polynomial-chaos surrogate's indices of the outputs that have Sobol indices (walking samples only)."""
    if spec.surrogate_order is None:
        return []
    walks = walking_mask(runs.outputs)
    return [
        surrogate_indices(name, spec.distributions, values, _walking(runs, name, walks), spec.surrogate_order)
        for name in INDEX_OUTPUTS
    ]
