"""One row of ``sweep.csv`` per run: its swept values, its settings and what it measured; the table written and read.

The metrics come from the run's summary.json alone (never its trajectory.h5), so a row
built by a worker right after its run and a row rebuilt from disk when a sweep resumes are the
same. Column names carry their units (``_s``, ``_m``, ``_J``...) so the table reads on its own.
A run without results (status ``error``, ``pending``, or any other a later tool adds) has empty metrics.
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.integrate.driver import takes_fixed_steps
from biped_sim.io.atomic import write_text_atomic, write_with
from biped_sim.rigid.start import INTEGRATOR

# Settings that the report's comparison tables group by; always present, swept or not.
SETTING_COLUMNS = (
    "ground.slope",
    "contact.model",
    "friction.model",
    "integrator.method",
    "integrator.dt",
    "integrator.rtol",
    "integrator.atol",
    "formulation.baumgarte.alpha",
    "formulation.baumgarte.beta",
)

METRIC_COLUMNS = (
    "status",
    "n_steps",
    "mean_period_s",
    "last_period_s",
    "period_spread_s",
    "speed_m_s",
    "slip_mean_m",
    "slip_max_m",
    "energy_dissipated_normal_J",
    "energy_dissipated_friction_J",
    "energy_residual_max_J",
    "energy_residual_rel",
    "violation_position_max_m",
    "violation_velocity_max_m_s",
    "max_penetration_m",
    "peak_normal_force_N",
    "wall_time_s",
    "rhs_evals",
    "accepted_steps",
    "rejected_steps",
    "stop_time_s",
    "error",
)

INTEGER_COLUMNS = ("n_steps", "rhs_evals", "accepted_steps", "rejected_steps")


def step_control(config: Config) -> str:
    """How the integrator's step is set: 'dt = 1e-04 s' (fixed step) or 'rtol = 1e-08, atol = 1e-10'; a rigid run
    ignores the integrator section (its own DOP853 at rtol 1e-12)."""
    if config.dynamics == "rigid":
        return INTEGRATOR
    integ = config.integrator
    if takes_fixed_steps(integ):
        return f"dt = {integ.dt:.0e} s"
    return f"rtol = {integ.rtol:.0e}, atol = {integ.atol:.0e}"


def settings_of(config: Config) -> dict[str, Any]:
    """The setting columns of a run, read from its resolved config."""
    data = config.model_dump(mode="json")
    out: dict[str, Any] = {}
    for key in SETTING_COLUMNS:
        node: Any = data
        for part in key.split("."):
            node = node[part]
        out[key] = node
    out["step_control"] = step_control(config)
    return out


def period_spread(periods: list[float]) -> float:
    """max - min of the step periods over the last half of the steps (0 on a period-1 gait)."""
    tail = [p for p in periods[len(periods) // 2 :] if p is not None and math.isfinite(p)]
    return max(tail) - min(tail) if len(tail) >= 2 else math.nan


def _number(value: Any) -> float:
    return math.nan if value is None else float(value)


def metrics_from_summary(summary: dict[str, Any]) -> dict[str, Any]:
    """The metric columns of a finished run, from its summary.json alone.

    A rigid run's summary has no ``rejected_steps`` (scipy does not report them): NaN. Its impact losses are its
    ``energy_dissipated.normal`` (the rigid limit of normal damping) and its constraint violations are 0.
    """
    periods = [p for p in summary["step_periods"] if p is not None]
    slips = [abs(s) for s in summary["slip_per_step"] if s is not None and math.isfinite(s)]
    return {
        "status": summary["status"],
        "n_steps": summary["n_steps"],
        "mean_period_s": _number(summary["mean_step_period"]),
        "last_period_s": _number(summary["last_step_period"]),
        "period_spread_s": period_spread(periods),
        "speed_m_s": _number(summary["mean_speed"]),
        "slip_mean_m": float(np.mean(slips)) if slips else math.nan,
        "slip_max_m": float(np.max(slips)) if slips else math.nan,
        "energy_dissipated_normal_J": _number(summary["energy_dissipated"]["normal"]),
        "energy_dissipated_friction_J": _number(summary["energy_dissipated"]["friction"]),
        "energy_residual_max_J": _number(summary["energy_residual_max"]),
        "energy_residual_rel": _number(summary["energy_residual_max_relative"]),
        "violation_position_max_m": _number(summary["constraint_violation_max"]["position"]),
        "violation_velocity_max_m_s": _number(summary["constraint_violation_max"]["velocity"]),
        "max_penetration_m": _number(summary.get("max_penetration")),
        "peak_normal_force_N": _number(summary.get("peak_normal_force")),
        "wall_time_s": _number(summary["wall_time_s"]),
        "rhs_evals": summary["rhs_evals"],
        "accepted_steps": summary["accepted_steps"],
        "rejected_steps": summary.get("rejected_steps", math.nan),
        "stop_time_s": _number(summary["stop_time"]),
        "error": "",
    }


def unfinished_metrics(status: str, error: str) -> dict[str, Any]:
    """Metric columns of a run without results: 'error' (it raised) or 'pending' (not run yet)."""
    row: dict[str, Any] = dict.fromkeys(METRIC_COLUMNS, math.nan)
    row.update(status=status, error=error)
    return row


def parquet_available() -> bool:
    """pyarrow (or fastparquet) present: the sweep table is also written as Parquet."""
    return any(importlib.util.find_spec(name) is not None for name in ("pyarrow", "fastparquet"))


def table_frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    """The sweep table as a DataFrame (integer counters stay integers where present)."""
    frame = pd.DataFrame(rows)
    for column in INTEGER_COLUMNS:
        frame[column] = frame[column].astype("Int64")
    return frame


def write_table(rows: list[dict[str, Any]], sweep_dir: Path) -> None:
    """Write sweep.csv (and sweep.parquet) atomically."""
    frame = table_frame(rows)
    write_text_atomic(sweep_dir / "sweep.csv", frame.to_csv(index=False))
    if parquet_available():
        write_with(sweep_dir / "sweep.parquet", lambda tmp: frame.to_parquet(tmp, index=False))


def read_sweep(sweep_dir: Path) -> tuple[dict[str, Any], pd.DataFrame]:
    """(manifest, table) of a sweep directory; ConfigError if it is not one or its files are damaged."""
    manifest_path, table_path = sweep_dir / "sweep.json", sweep_dir / "sweep.csv"
    if not manifest_path.is_file() or not table_path.is_file():
        raise ConfigError(str(sweep_dir), "not a sweep directory (no sweep.json and sweep.csv)")
    try:
        data = json.loads(manifest_path.read_text())
    except (OSError, ValueError) as exc:
        raise ConfigError(str(manifest_path), f"damaged or truncated ({exc})") from None
    dtypes = {"error": str, **dict.fromkeys(INTEGER_COLUMNS, "Int64")}
    try:
        frame = pd.read_csv(table_path, keep_default_na=False, na_values=[""], dtype=dtypes)
    except (OSError, ValueError) as exc:  # pandas' parser errors are ValueErrors
        raise ConfigError(str(table_path), f"damaged or truncated ({str(exc).strip()})") from None
    missing = [c for c in ("run", *METRIC_COLUMNS) if c not in frame.columns]
    if not isinstance(data, dict) or not isinstance(data.get("runs"), list) or "axes" not in data:
        raise ConfigError(str(manifest_path), "damaged: not a sweep manifest")
    if missing:
        raise ConfigError(str(table_path), f"damaged or truncated (no columns {', '.join(missing)})")
    if len(frame) != len(data["runs"]) or frame["run"].isna().any() or frame["status"].isna().any():
        raise ConfigError(str(table_path), f"damaged or truncated ({len(frame)} rows for {len(data['runs'])} runs)")
    frame["error"] = frame["error"].fillna("")
    return data, frame
