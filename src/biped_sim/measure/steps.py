"""Steps of a run: the per-step table (periods, lengths, slip, touchdown angles), its summary and CSV.

Heel strikes come from the compiled loop (the first touchdown of a leading foot that is not the
previous strike's foot: bounces are debounced there); the table is read from the strike states.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from biped_sim.integrate.driver import Integration
from biped_sim.multibody.dispatch import measures, system_foot_contact
from biped_sim.walkers.model import BuiltModel


@dataclass
class StepTable:
    """One row per heel strike k: the step that strike begins."""

    strike_time: np.ndarray
    foot: np.ndarray
    period: np.ndarray  # t_{k+1} - t_k (nan for the last strike)
    length: np.ndarray  # contact point advance to the next strike (nan for the last)
    slip: np.ndarray  # stance-foot slip during the step (nan for the last)
    stance_angle: np.ndarray
    stance_rate: np.ndarray
    swing_angle: np.ndarray
    swing_rate: np.ndarray


STEP_COLUMNS = (
    ("strike_time", "s"),
    ("foot", "1"),
    ("period", "s"),
    ("length", "m"),
    ("slip", "m"),
    ("stance_angle", "rad"),
    ("stance_rate", "rad/s"),
    ("swing_angle", "rad"),
    ("swing_rate", "rad/s"),
)


def steps_csv(steps: StepTable, unit: Callable[[str], str]) -> str:
    """steps.csv: one row per heel strike (the step it begins); ``unit`` maps an SI unit to the run's."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["step"] + [f"{name} [{unit(units)}]" if units != "1" else name for name, units in STEP_COLUMNS])
    for k in range(len(steps.strike_time)):
        row: list[object] = [k + 1]
        for name, _ in STEP_COLUMNS:
            value = getattr(steps, name)[k]
            row.append(int(value) if name == "foot" else ("" if not np.isfinite(value) else repr(float(value))))
        writer.writerow(row)
    return buffer.getvalue()


class StepAccess:
    """Step accessors shared by the compliant and the rigid run results (which hold a ``steps`` StepTable)."""

    steps: StepTable

    @property
    def heel_strike_times(self) -> np.ndarray:
        return self.steps.strike_time

    @property
    def step_periods(self) -> np.ndarray:
        """Periods of the completed steps (between consecutive heel strikes)."""
        return self.steps.period[:-1] if len(self.steps.period) else self.steps.period

    @property
    def step_lengths(self) -> np.ndarray:
        return self.steps.length[:-1] if len(self.steps.length) else self.steps.length

    @property
    def heel_strike_states(self) -> list[dict[str, float]]:
        """Touchdown leg angles and rates at each heel strike; 'stance' is the leg that just touched down."""
        s = self.steps
        return [
            {
                "stance_angle": float(s.stance_angle[k]),
                "stance_rate": float(s.stance_rate[k]),
                "swing_angle": float(s.swing_angle[k]),
                "swing_rate": float(s.swing_rate[k]),
            }
            for k in range(len(s.strike_time))
        ]

    def to_pandas(self) -> pd.DataFrame:
        """The step table as a DataFrame (what steps.csv holds): one row per heel strike k, indexed by k from 1,
        the step that strike begins; the last row's period, length and slip are NaN (its step did not end).
        The columns' units are in ``frame.attrs["units"]``."""
        frame = pd.DataFrame({name: getattr(self.steps, name) for name, _ in STEP_COLUMNS})
        frame.index = pd.RangeIndex(1, len(frame) + 1, name="step")
        frame.attrs["units"] = dict(STEP_COLUMNS)
        return frame

    def step_summary(self) -> dict[str, Any]:
        """The summary.json entries of the steps: times, feet, periods, lengths, mean speed, slip."""
        steps, periods, lengths = self.steps, self.step_periods, self.step_lengths
        span = float(steps.strike_time[-1] - steps.strike_time[0]) if len(steps.strike_time) > 1 else 0.0
        return {
            "n_steps": len(steps.strike_time),
            "step_times": steps.strike_time.tolist(),
            "step_feet": steps.foot.tolist(),
            "step_periods": periods.tolist(),
            "step_lengths": lengths.tolist(),
            "mean_step_period": _finite_or_none(float(np.mean(periods))) if len(periods) else None,
            "last_step_period": _finite_or_none(float(periods[-1])) if len(periods) else None,
            "mean_speed": float(np.nansum(lengths)) / span if span > 0 else 0.0,
            "slip_per_step": steps.slip[:-1].tolist() if len(steps.slip) else [],
        }


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _contact_x(y: np.ndarray, system: tuple, foot: int) -> float:
    """A foot's contact point along the slope [m] (the formulation's ``foot_contact``, as the events read it)."""
    return float(system_foot_contact(y, system, foot)[2])


def _rolling_coordinate(y: np.ndarray, model: BuiltModel, foot: int) -> float:
    """x_C + R theta of a foot: constant while the arc rolls without slipping, so its change is the slip."""
    system = model.system
    m = measures(system)
    theta = m.pitch(y, system, int(system.foot_body[foot]))[0]
    return _contact_x(y, system, foot) + system.foot_radius[foot] * theta


def step_table(model: BuiltModel, run: Integration) -> StepTable:
    """Per-step quantities from the heel-strike states."""
    system = model.system
    m = measures(system)
    n = len(run.strike_t)
    period = np.full(n, np.nan)
    length = np.full(n, np.nan)
    slip = np.full(n, np.nan)
    angles = np.zeros((n, 4))
    for k in range(n):
        y = run.strike_y[k]
        foot = int(run.strike_foot[k])
        stance_body = int(system.foot_body[foot])
        swing_body = int(system.foot_body[system.foot_partner[foot]]) if system.foot_partner[foot] >= 0 else stance_body
        angles[k] = [*m.pitch(y, system, stance_body), *m.pitch(y, system, swing_body)]
        if k + 1 < n:
            y_next = run.strike_y[k + 1]
            period[k] = run.strike_t[k + 1] - run.strike_t[k]
            next_foot = int(run.strike_foot[k + 1])
            length[k] = _contact_x(y_next, system, next_foot) - _contact_x(y, system, foot)
            slip[k] = _rolling_coordinate(y_next, model, foot) - _rolling_coordinate(y, model, foot)
    return StepTable(run.strike_t.copy(), run.strike_foot.copy(), period, length, slip, *angles.T)
