"""Steps of a run: the per-step table (periods, lengths, slip, touchdown angles), its summary and CSV.

Heel strikes come from the compiled loop (the first touchdown of a leading foot that is not the
previous strike's foot: bounces are debounced there); the table is read from the strike states.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np

from biped_sim.integrate.driver import Integration
from biped_sim.measure.loops import hip_loop
from biped_sim.multibody.dispatch import measures, system_foot_contact
from biped_sim.walkers.model import BuiltModel

if TYPE_CHECKING:
    import pandas as pd


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
    # spatial runs only (else None): LATERAL_STEP_COLUMNS, defined in docs/guide/outputs.md (:func:`lateral_steps`)
    width: np.ndarray | None = None
    heading: np.ndarray | None = None
    sway: np.ndarray | None = None
    bank: np.ndarray | None = None

    @property
    def columns(self) -> tuple[tuple[str, str], ...]:
        """(name, SI unit) of the columns this table has: :data:`STEP_COLUMNS`, then a spatial run's lateral ones."""
        present = {f.name for f in fields(self) if getattr(self, f.name) is not None}
        return tuple((name, unit) for name, unit in (*STEP_COLUMNS, *LATERAL_STEP_COLUMNS) if name in present)


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
LATERAL_STEP_COLUMNS = (("width", "m"), ("heading", "rad"), ("sway", "m"), ("bank", "rad"))


def steps_csv(steps: StepTable, unit: Callable[[str], str]) -> str:
    """steps.csv: one row per heel strike (the step it begins); ``unit`` maps an SI unit to the run's."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    columns = steps.columns
    writer.writerow(["step"] + [f"{name} [{unit(units)}]" if units != "1" else name for name, units in columns])
    for k in range(len(steps.strike_time)):
        row: list[object] = [k + 1]
        for name, _ in columns:
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
        import pandas as pd  # here: pandas adds 0.25 s to every command's start-up, and a run does not need it

        columns = self.steps.columns
        frame = pd.DataFrame({name: getattr(self.steps, name) for name, _ in columns})
        frame.index = pd.RangeIndex(1, len(frame) + 1, name="step")
        frame.attrs["units"] = dict(columns)
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
    return _contact_x(y, system, foot) + _rolling_radius(system, foot) * theta


def _rolling_radius(system: object, foot: int) -> float:
    """The foot's radius of curvature fore-aft at its bottom: its arc's (a planar model's), a sphere's, a disc's in
    the sagittal plane plus its tube, a ring's in the lateral plane only its tube's (an ellipsoid's taken as its
    zero radius: its slip reads as the contact point's travel)."""
    radius = float(system.foot_radius[foot])  # type: ignore[attr-defined]
    axis = getattr(system, "foot_axis", None)
    if axis is None or not np.any(axis[foot]):
        return radius
    return radius * abs(float(axis[foot][2])) + float(system.foot_tube[foot])  # type: ignore[attr-defined]


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
    lateral = lateral_steps(model, run) if m.foot_point is not None else {}
    return StepTable(run.strike_t.copy(), run.strike_foot.copy(), period, length, slip, *angles.T, **lateral)


def lateral_steps(model: BuiltModel, run: Integration) -> dict[str, np.ndarray]:
    """A spatial run's lateral step columns (slope frame: x downhill, y the normal, z = x cross y, the walker's right).

    Row k, the step strike k begins: ``width`` the lateral distance |z_(k+1) - z_k| between where the two strikes
    put their feet (each foot's lowest point at its strike); ``heading`` and ``bank`` the new stance leg's at strike
    k, right-handed about the slope normal (positive turning left) and about the downhill axis (positive with the
    leg's left side up), the rigid walker's section angles; ``sway`` the hip's lateral excursion over the step,
    max - min of its z over the samples between the two strikes and the strike states; width and sway nan for the
    last row (its step did not end).
    """
    system = model.system
    m = measures(system)
    n = len(run.strike_t)
    width, sway = np.full(n, np.nan), np.full(n, np.nan)
    heading, bank = np.empty(n), np.empty(n)
    hip = np.empty((len(run.t), 3))
    hip_loop(run.y, system, hip)
    strike_hip = np.empty((n, 3))
    hip_loop(run.strike_y, system, strike_hip)
    place = [m.foot_point(run.strike_y[k], system, int(run.strike_foot[k]))[1] for k in range(n)]
    for k in range(n):
        _, roll, yaw, _ = m.attitude(run.strike_y[k], system, int(system.foot_body[int(run.strike_foot[k])]))
        heading[k], bank[k] = -yaw, -roll
        if k + 1 < n:
            width[k] = abs(place[k + 1] - place[k])
            inside = (run.t >= run.strike_t[k]) & (run.t <= run.strike_t[k + 1])
            z = np.concatenate([hip[inside, 2], strike_hip[k : k + 2, 2]])
            sway[k] = float(z.max() - z.min())
    return {"width": width, "heading": heading, "sway": sway, "bank": bank}
