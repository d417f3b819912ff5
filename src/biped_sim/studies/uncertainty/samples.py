"""The run of an uncertainty study's samples: each sample a run of the config with its keys set, in chunks on an
executor, every finished chunk recorded atomically so that a rerun resumes.

A sample's run is the config with the sample's values set by :func:`~biped_sim.config.derive` (a value the
schema refuses is the sample's result, status ``invalid``, never an error of the study), in minimal
coordinates when the config is planar and compliant (the same walker by construction, as the fit runs it).
What a run gives (:func:`sample_outputs`): its status, the steady step period and step length (the mean of
the last ``STEADY_STEPS`` steps), the mean speed, the energy dissipated per step, the mean slip per step, the
peak normal force, the step periods for the bands; for rigid walkers also the period-1 fixed point and the
largest Floquet multiplier (modulus) of the config at the sample's values. A run that raises is recorded with
status ``error`` and its message: no sample is ever dropped.

Chunks of ``CHUNK`` consecutive samples run as one task; a finished chunk goes to ``DIR/samples/`` under a key
of the resolved config, the keys and the sample values, so a rerun of the same study skips the chunks done.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import Config, derive
from biped_sim.errors import ConfigError
from biped_sim.io.atomic import json_safe, write_json_atomic
from biped_sim.studies.tasks import results_as_done

CHUNK = 16
STEADY_STEPS = 3
SAMPLES_DIR = "samples"
SCALARS = ("steady_period", "speed", "step_length", "energy_per_step", "slip", "peak_normal_force")
LEG_KEYS = ("stance_angle", "stance_rate", "swing_angle", "swing_rate")
RIGID_SCALARS = ("floquet_max", *(f"fixed_{k}" for k in LEG_KEYS))
WALKING = "walking"


def _steady(values: list[float]) -> float:
    return float(np.mean(values[-STEADY_STEPS:])) if len(values) >= STEADY_STEPS else math.nan


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)


def _rigid_cycle(config: Config) -> dict[str, Any]:
    """The period-1 fixed point (post-impact leg state) and its largest multiplier (NaN when Newton finds none)."""
    from biped_sim.rigid.limit_cycle import StepFailedError
    from biped_sim.studies.limit_cycle import limit_cycle  # rigid walkers only: Newton on the step map

    try:
        cycle = limit_cycle(config)
    except (ConfigError, StepFailedError):
        cycle = None
    if cycle is None or not cycle.converged:
        return dict.fromkeys(RIGID_SCALARS, math.nan)
    fixed = {f"fixed_{k}": float(cycle.fixed_point.get(k, math.nan)) for k in LEG_KEYS}
    return {"floquet_max": cycle.max_multiplier_modulus, **fixed}


def sample_outputs(config: Config) -> dict[str, Any]:
    """What one sample's run gives (see the module docstring); plain data."""
    from biped_sim.simulate import simulate  # the engine: imported by the workers that run samples

    result = simulate(config)
    s = json_safe({  # the summary's entries it reads: the steps', no channel but the normal force
        **result.step_summary(),
        "energy_dissipated": result.energy_dissipated(),
        "peak_normal_force": result.peak_normal_force(),
    })  # fmt: skip
    lost = s["energy_dissipated"]
    energy = (lost["impact"] if "impact" in lost else lost["normal"]) + lost["friction"]
    slips = [v for v in (s.get("slip_per_step") or []) if v is not None]
    out: dict[str, Any] = {
        "status": result.status,
        "reason": result.status_reason,
        "n_steps": int(s["n_steps"]),
        "steady_period": _steady(s["step_periods"]),
        "speed": _number(s.get("mean_speed")),
        "step_length": _steady(s["step_lengths"]),
        "energy_per_step": energy / s["n_steps"] if s["n_steps"] else math.nan,
        "slip": float(np.mean(slips)) if slips else math.nan,
        "peak_normal_force": _number(s.get("peak_normal_force")),
        "periods": [float(v) for v in s["step_periods"]],
    }
    if config.dynamics == "rigid":
        out.update(_rigid_cycle(config))
    return out


def failed_outputs(status: str, reason: str) -> dict[str, Any]:
    """The record of a sample without a run (``invalid``: the schema refused its values) or whose run raised."""
    return {"status": status, "reason": reason, "n_steps": 0, "periods": [], **dict.fromkeys(SCALARS, math.nan)}


@dataclass(frozen=True)
class ChunkTask:
    """Samples ``start``.. of a study (plain data: pickles to any worker)."""

    config: Config
    keys: tuple[str, ...]
    values: np.ndarray  # (chunk rows, keys)
    start: int


def run_sample(config: Config, keys: tuple[str, ...], row: np.ndarray) -> dict[str, Any]:
    """One sample: the config at ``row``'s values, run; a refused value or a raising run is its result."""
    from biped_sim.simulate import study_formulation  # the engine: imported by the workers that run samples

    try:
        variant = derive(config, {**dict(zip(keys, (float(v) for v in row), strict=True)),
                                  "formulation.kind": study_formulation(config)})  # fmt: skip
    except ConfigError as exc:
        return failed_outputs("invalid", str(exc))
    try:
        return sample_outputs(variant)
    except ConfigError as exc:  # the walker cannot start there (e.g. a foot below the ground)
        return failed_outputs("invalid", str(exc))
    except Exception as exc:  # recorded with the sample, never dropped
        return failed_outputs("error", f"{type(exc).__name__}: {str(exc)[:200]}")


def run_chunk(task: ChunkTask) -> dict[str, Any]:
    """Run one chunk (in a worker): {'start', 'outputs': [one record per sample]}."""
    return {"start": task.start, "outputs": [run_sample(task.config, task.keys, row) for row in task.values]}


def study_key(config: Config, keys: tuple[str, ...], values: np.ndarray) -> str:
    """What the chunks were computed for: the resolved config, the keys and every sample's values."""
    digest = hashlib.sha256(json.dumps([config.hash(), list(keys)]).encode())
    digest.update(np.ascontiguousarray(values, dtype=np.float64).tobytes())
    return digest.hexdigest()[:16]


def _chunk_path(out_dir: Path, start: int) -> Path:
    return out_dir / SAMPLES_DIR / f"chunk_{start:06d}.json"


def finished_chunks(key: str, starts: list[int], sizes: dict[int, int], out_dir: Path) -> dict[int, list[Any]]:
    """Chunks recorded by an earlier run of the same study (others' or unreadable files are ignored)."""
    done = {}
    for start in starts:
        try:
            record = json.loads(_chunk_path(out_dir, start).read_text())
        except (OSError, ValueError):
            continue
        if record.get("key") == key and len(record.get("outputs", [])) == sizes[start]:
            done[start] = record["outputs"]
    return done


@dataclass
class SampleRuns:
    """Every sample's record, in sample order, and how many chunks a rerun reused."""

    outputs: list[dict[str, Any]]
    chunks_reused: int


def run_samples(
    config: Config,
    keys: tuple[str, ...],
    values: np.ndarray,
    out_dir: Path | None,
    executor: Executor | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SampleRuns:
    """Run every row of ``values`` (one sample a row, columns ``keys``), ``CHUNK`` rows a task on ``executor``
    (None: here); with ``out_dir``, finished chunks are recorded in ``out_dir/samples`` and reused by a rerun.
    ``progress(done, total)`` after each chunk, in samples."""
    n = len(values)
    starts = list(range(0, n, CHUNK))
    sizes = {s: min(CHUNK, n - s) for s in starts}
    key = study_key(config, keys, values)
    done = finished_chunks(key, starts, sizes, out_dir) if out_dir is not None else {}
    reused = len(done)
    if out_dir is not None:
        (out_dir / SAMPLES_DIR).mkdir(parents=True, exist_ok=True)
    tasks = [ChunkTask(config, keys, values[s : s + sizes[s]], s) for s in starts if s not in done]
    for result in results_as_done(run_chunk, tasks, executor):
        if out_dir is not None:
            write_json_atomic(_chunk_path(out_dir, result["start"]), {"key": key, **result})
        done[result["start"]] = result["outputs"]
        if progress is not None:
            progress(sum(len(v) for v in done.values()), n)
    return SampleRuns([record for s in starts for record in done[s]], reused)
