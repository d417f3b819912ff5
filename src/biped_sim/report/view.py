"""A sweep's table as the report sees it: plain rows, what varies, labels for runs, shared columns."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from biped_sim.io.tables import Column
from biped_sim.sweep.rows import read_sweep
from biped_sim.sweep.spec import short_keys

MAX_OVERLAY = 10
FINISHED = ("walking", "fell", "diverged")
# Preference for the accuracy reference of an integrator group: tighter tolerance or step, then higher order.
ORDER = {"dop853": 8, "dopri5": 5, "radau": 5, "bdf": 2, "rk4": 4, "rk2": 2, "euler": 1}
ADAPTIVE = ("dopri5", "dop853", "radau", "bdf")
AXIS_LABELS = {
    "ground.slope": "slope [rad]",
    "integrator.dt": "time step dt [s]",
    "integrator.rtol": "relative tolerance",
    "formulation.baumgarte.alpha": "Baumgarte alpha [1/s]",
    "formulation.baumgarte.beta": "Baumgarte beta [1/s]",
    "contact.restitution": "restitution e",
    "friction.mu_kinetic": "kinetic friction coefficient",
}

PERIOD = Column("mean_period_s", "mean period", "s", ".4f")
LAST_PERIOD = Column("last_period_s", "last period", "s", ".4f")
STATUS = Column("status", "status")
STEPS = Column("n_steps", "steps", "", "d")
SPEED = Column("speed_m_s", "speed", "m/s", ".3f")
WALL = Column("wall_time_s", "wall time", "s", ".2f")
RHS = Column("rhs_evals", "RHS evals", "", "d")
ACCEPTED = Column("accepted_steps", "integrator steps", "", "d")
VIOLATION_POS = Column("violation_position_max_m", "max |Phi|", "m", ".1e")
VIOLATION_VEL = Column("violation_velocity_max_m_s", "max |dPhi/dt|", "m/s", ".1e")
RESIDUAL = Column("energy_residual_rel", "energy residual", "m g l", ".1e")


def records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """DataFrame rows as plain Python values (None for missing, int for integer counters)."""
    out = []
    for row in frame.astype(object).to_dict("records"):
        clean = {}
        for key, value in row.items():
            if value is pd.NA or (isinstance(value, float) and math.isnan(value)):
                clean[key] = None
            elif hasattr(value, "item"):  # numpy scalar
                clean[key] = value.item()
            else:
                clean[key] = value
        out.append(clean)
    return out


def fmt_value(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


@dataclass
class SweepView:
    """A sweep's table plus what varies in it, and labels for its runs."""

    sweep_dir: Path
    manifest: dict[str, Any]
    rows: list[dict[str, Any]]
    axes: list[str]
    zip_axes: list[str]
    integrator_varies: bool
    contact_varies: bool
    friction_varies: bool
    baumgarte_varies: bool
    short: dict[str, str] = field(default_factory=dict)

    @classmethod
    def load(cls, sweep_dir: Path) -> SweepView:
        manifest, frame = read_sweep(sweep_dir)
        rows = records(frame)
        axes = [a for a in manifest["axes"] if a in frame.columns]

        def varies(*keys: str) -> bool:
            return len({tuple(row[k] for k in keys) for row in rows}) > 1

        return cls(
            sweep_dir=sweep_dir,
            manifest=manifest,
            rows=rows,
            axes=axes,
            zip_axes=[a for a in manifest.get("zip_axes", []) if a in axes],
            integrator_varies=varies("integrator.method", "step_control"),
            contact_varies=varies("contact.model"),
            friction_varies=varies("friction.model"),
            baumgarte_varies=varies("formulation.baumgarte.alpha", "formulation.baumgarte.beta"),
            short=short_keys(axes),
        )

    @property
    def finished(self) -> list[dict[str, Any]]:
        """The runs with results (walking, fell or diverged): what figures and comparisons can use."""
        return [row for row in self.rows if row["status"] in FINISHED]

    def missing_note(self, verb: str) -> str | None:
        """One line on the runs without results, e.g. '2 of 5 runs have no results and are not drawn (1 error,
        1 pending)'; None when every run has results."""
        counts: dict[str, int] = {}
        for row in self.rows:
            if row["status"] not in FINISHED:
                counts[row["status"]] = counts.get(row["status"], 0) + 1
        if not counts:
            return None
        detail = ", ".join(f"{n} {status}" for status, n in counts.items())
        return f"{sum(counts.values())} of {len(self.rows)} runs have no results and are not {verb} ({detail})"

    def label(self, row: dict[str, Any], exclude: tuple[str, ...] = ()) -> str:
        """'slope=0.018, rk4 dt = 1e-04 s': the swept values of a run (integrator with its step control)."""
        parts = [
            f"{self.short[k]}={fmt_value(row[k])}"
            for k in self.axes
            if k not in exclude and not (k.startswith("integrator.") and self.integrator_varies)
        ]
        if self.integrator_varies and "integrator" not in exclude:
            parts.append(f"{row['integrator.method']} {row['step_control']}")
        return ", ".join(parts) or row["run"]

    def numeric_axis(self) -> str | None:
        """The swept axis to put on an x axis: ground.slope if swept, else the first numeric swept axis."""
        numeric = [
            k
            for k in self.axes
            if len({row[k] for row in self.rows}) > 1
            and all(isinstance(row[k], int | float) and not isinstance(row[k], bool) for row in self.rows)
        ]
        if "ground.slope" in numeric:
            return "ground.slope"
        return numeric[0] if numeric else None

    def moving_with(self, axis: str) -> tuple[str, ...]:
        """The axes that change together with ``axis``: its zip group, or itself."""
        return tuple(self.zip_axes) if axis in self.zip_axes else (axis,)

    def param_columns(self, exclude: tuple[str, ...]) -> list[Column]:
        """Columns for the swept values not already shown by a table's own setting columns."""
        return [Column(k, self.short[k], "", "g") for k in self.axes if k not in exclude]
