"""``biped-sim report SWEEP_DIR``: the paper's comparison tables and figures from a finished sweep.

Tables (Markdown, CSV and LaTeX each), for whichever axes the sweep varies:

- ``runs``: every run, its swept values, status and gait;
- ``by_integrator``: method with its step size or tolerances, accuracy against the most
  accurate run of the same group, constraint violation, energy residual and cost;
- ``by_normal_model``: gait, penetration, peak force and dissipation per normal force law;
- ``by_friction_model``: gait, slip and friction dissipation per friction law;
- ``baumgarte``: the standard method (alpha = beta = 0) against Baumgarte stabilisation.

Figures (PNG 200 dpi + SVG): mean step period against the swept numeric parameter (one line
per integrator or model), step period against step number, constraint violation against time,
contact forces around a heel strike, energy dissipated and the balance residual, stance-foot
slip per step, phase portraits, and the cost of each run. Overlays of many runs show the runs at
one value of the numeric parameter (stated in the caption), at most ``MAX_OVERLAY`` of them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from biped_sim.errors import ConfigError
from biped_sim.io.atomic import write_text_atomic
from biped_sim.io.tables import Column, Table
from biped_sim.io.trajectory import RunData, load_run, load_summary
from biped_sim.plots import (
    accuracy_cost_figure,
    bar_figure,
    constraint_violation_figure,
    contact_forces_figure,
    energy_balance_figure,
    parameter_lines_figure,
    phase_portrait_figure,
    save_figure,
    slip_figure,
    step_period_figure,
)
from biped_sim.rigid.run import INTEGRATOR as RIGID_INTEGRATOR
from biped_sim.sweep.runner import read_sweep
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


def _fmt(value: Any) -> str:
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
        return [row for row in self.rows if row["status"] in FINISHED]

    def label(self, row: dict[str, Any], exclude: tuple[str, ...] = ()) -> str:
        """'slope=0.018, rk4 dt = 1e-04 s': the swept values of a run (integrator with its step control)."""
        parts = [
            f"{self.short[k]}={_fmt(row[k])}"
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


def runs_table(view: SweepView) -> Table:
    """Every run: swept values, status, gait, cost."""
    columns = [
        Column("run", "run"),
        *view.param_columns(()),
        STATUS,
        STEPS,
        PERIOD,
        LAST_PERIOD,
        Column("period_spread_s", "period spread", "s", ".1e"),
        SPEED,
        WALL,
        Column("error", "error"),
    ]
    notes = [
        "Period spread: max - min of the step periods over the last half of the steps (0 on a period-1 gait).",
        "Wall time: integration only, one worker process.",
    ]
    return Table("runs", f"Sweep {view.manifest['name']}: all runs", columns, view.rows, notes)


def _integrator_rank(row: dict[str, Any]) -> tuple[int, float, int]:
    """Sort key: the most accurate run first (adaptive by tolerance, then fixed-step by step size; higher order)."""
    method = row["integrator.method"]
    if method in ADAPTIVE and "rtol" in row["step_control"]:
        return (0, row["integrator.rtol"], -ORDER[method])
    return (1, row["integrator.dt"], -ORDER[method])


def integrator_accuracy(view: SweepView, rows: list[dict[str, Any]]) -> tuple[list[dict[str, Any]], list[str]]:
    """Rows with 'period_deviation_s': max_k |T_k - T_k(ref)| against the most accurate run of the same group.

    A group is the runs that differ only in the integrator; its reference is the walking run
    ranked first by :func:`_integrator_rank`.
    """
    integrator_keys = ("integrator.method", "integrator.dt", "integrator.rtol", "integrator.atol", "step_control")
    other = [k for k in view.axes if k not in integrator_keys]
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(tuple(row[k] for k in other), []).append(row)
    periods = {
        row["run"]: load_summary(view.sweep_dir / "runs" / row["run"])["step_periods"]
        for row in rows
        if row["status"] in FINISHED
    }
    out, notes = [], []
    for members in groups.values():
        walking = sorted((r for r in members if r["status"] == "walking"), key=_integrator_rank)
        reference = walking[0] if walking else None
        if reference is not None:
            notes.append(
                f"Accuracy reference for {view.label(reference, exclude=('integrator',)) or 'all runs'}: "
                f"{reference['integrator.method']} {reference['step_control']}."
            )
        for row in members:
            deviation = math.nan
            if reference is not None and row["run"] in periods:
                mine, ref = periods[row["run"]], periods[reference["run"]]
                n = min(len(mine), len(ref))
                diffs = [abs(a - b) for a, b in zip(mine[:n], ref[:n], strict=True) if a is not None and b is not None]
                deviation = max(diffs) if diffs else math.nan
            out.append({**row, "period_deviation_s": deviation})
    order = {row["run"]: i for i, row in enumerate(rows)}
    out.sort(key=lambda r: order[r["run"]])
    return out, notes


def _grouped(rows: list[dict[str, Any]], key: Callable[[dict[str, Any]], Any]) -> list[dict[str, Any]]:
    """Rows ordered by ``key`` (in order of first appearance), run order within a group."""
    first: dict[Any, int] = {}
    for i, row in enumerate(rows):
        first.setdefault(key(row), i)
    return sorted(rows, key=lambda r: first[key(r)])


def integrator_table(view: SweepView) -> Table:
    """Integrators compared: step size or tolerances stated, accuracy, violation, energy, cost."""
    rows, notes = integrator_accuracy(view, view.rows)
    rows = _grouped(rows, lambda r: (r["integrator.method"], r["step_control"]))
    columns = [
        Column("integrator.method", "integrator"),
        Column("step_control", "step size / tolerances"),
        *view.param_columns(("integrator.method", "integrator.dt", "integrator.rtol", "integrator.atol")),
        STATUS,
        STEPS,
        PERIOD,
        Column("period_deviation_s", "max |dT| vs ref.", "s", ".1e"),
        VIOLATION_POS,
        VIOLATION_VEL,
        RESIDUAL,
        WALL,
        RHS,
        ACCEPTED,
    ]
    notes = [
        "max |dT| vs ref.: largest difference of a step period from the same step of the group's reference run.",
        *notes,
    ]
    return Table("by_integrator", "Integrators: accuracy, constraint violation and cost", columns, rows, notes)


def normal_model_table(view: SweepView) -> Table:
    """Normal contact force laws compared."""
    rows = _grouped(view.rows, lambda r: r["contact.model"])
    columns = [
        Column("contact.model", "normal force model"),
        *view.param_columns(("contact.model",)),
        STATUS,
        STEPS,
        PERIOD,
        SPEED,
        Column("max_penetration_m", "max penetration", "m", ".2e"),
        Column("peak_normal_force_N", "peak normal force", "N", ".1f"),
        Column("energy_dissipated_normal_J", "dissipated (normal)", "J", ".3f"),
        Column("energy_dissipated_friction_J", "dissipated (friction)", "J", ".3f"),
        WALL,
    ]
    return Table("by_normal_model", "Normal contact force models", columns, rows)


def friction_model_table(view: SweepView) -> Table:
    """Friction laws compared."""
    rows = _grouped(view.rows, lambda r: r["friction.model"])
    columns = [
        Column("friction.model", "friction model"),
        *view.param_columns(("friction.model",)),
        STATUS,
        STEPS,
        PERIOD,
        SPEED,
        Column("slip_mean_m", "mean |slip| per step", "m", ".2e"),
        Column("slip_max_m", "max |slip| per step", "m", ".2e"),
        Column("energy_dissipated_friction_J", "dissipated (friction)", "J", ".3f"),
        WALL,
        RHS,
    ]
    return Table("by_friction_model", "Friction models", columns, rows)


def baumgarte_table(view: SweepView) -> Table:
    """The standard method (alpha = beta = 0) against Baumgarte stabilisation."""
    rows = []
    for row in view.rows:
        alpha, beta = row["formulation.baumgarte.alpha"], row["formulation.baumgarte.beta"]
        method = "standard" if alpha == 0 and beta == 0 else "Baumgarte"
        rows.append({**row, "stabilisation": method})
    rows = _grouped(rows, lambda r: (r["formulation.baumgarte.alpha"], r["formulation.baumgarte.beta"]))
    columns = [
        Column("stabilisation", "stabilisation"),
        Column("formulation.baumgarte.alpha", "alpha", "1/s", "g"),
        Column("formulation.baumgarte.beta", "beta", "1/s", "g"),
        *view.param_columns(("formulation.baumgarte.alpha", "formulation.baumgarte.beta")),
        STATUS,
        STEPS,
        VIOLATION_POS,
        VIOLATION_VEL,
        RESIDUAL,
        PERIOD,
        WALL,
        RHS,
    ]
    return Table("baumgarte", "Standard method against Baumgarte stabilisation", columns, rows)


def tables_for(view: SweepView) -> list[Table]:
    """The tables this sweep supports."""
    tables = [runs_table(view)]
    if view.integrator_varies:
        tables.append(integrator_table(view))
    if view.contact_varies:
        tables.append(normal_model_table(view))
    if view.friction_varies:
        tables.append(friction_model_table(view))
    if view.baumgarte_varies:
        tables.append(baumgarte_table(view))
    return tables


def parameter_lines(view: SweepView, axis: str, column: str) -> list[tuple[str, list[float], list[float]]]:
    """``column`` against ``axis``, one line per combination of the other swept values: (label, x, y)."""
    lines: dict[str, tuple[list[float], list[float]]] = {}
    for row in view.finished:
        if row[column] is None:
            continue
        xs, ys = lines.setdefault(view.label(row, exclude=view.moving_with(axis)), ([], []))
        xs.append(row[axis])
        ys.append(row[column])
    out = []
    for label, (xs, ys) in lines.items():
        order = sorted(range(len(xs)), key=xs.__getitem__)
        out.append((label, [xs[i] for i in order], [ys[i] for i in order]))
    return out


def accuracy_series(view: SweepView) -> list[tuple[str, list[float], list[float]]]:
    """(integrator with step control, wall times, max period deviations) for the accuracy-cost figure."""
    rows, _ = integrator_accuracy(view, view.finished)
    series: dict[str, tuple[list[float], list[float]]] = {}
    for row in rows:
        walls, deviations = series.setdefault(f"{row['integrator.method']} {row['step_control']}", ([], []))
        walls.append(row["wall_time_s"])
        deviations.append(row["period_deviation_s"])
    return [
        (label, walls, deviations)
        for label, (walls, deviations) in series.items()
        if any(d is not None and d > 0 for d in deviations)  # reference runs (deviation 0) are not drawn
    ]


def overlay_runs(view: SweepView) -> tuple[list[tuple[str, RunData]], str]:
    """The runs to overlay in the time-series figures, and a caption note saying which.

    Rigid runs have no contact or constraint channels to draw: they are left out (their gait is in the
    tables and the parameter figures).
    """
    rows = [row for row in view.finished if row.get("step_control") != RIGID_INTEGRATOR]
    if not rows:
        return [], "no compliant run"
    axis = view.numeric_axis()
    exclude: tuple[str, ...] = ()
    note = "all finished runs"
    if axis is not None and len(view.axes) > len(view.moving_with(axis)):
        values = sorted({row[axis] for row in rows})
        middle = values[(len(values) - 1) // 2]
        rows = [row for row in rows if row[axis] == middle]
        exclude = view.moving_with(axis)
        note = f"runs at {view.short[axis]} = {_fmt(middle)}"
    if len(rows) > MAX_OVERLAY:
        rows = rows[:MAX_OVERLAY]
        note += f" (first {MAX_OVERLAY})"
    return [(view.label(row, exclude=exclude), load_run(view.sweep_dir / "runs" / row["run"])) for row in rows], note


@dataclass
class Report:
    """What ``build_report`` wrote."""

    out_dir: Path
    tables: list[Table]
    figures: dict[str, str]  # name -> caption

    @property
    def markdown_path(self) -> Path:
        return self.out_dir / "report.md"


def build_figures(view: SweepView, figure_dir: Path) -> dict[str, str]:
    """Write the sweep figures; returns name -> caption."""
    captions: dict[str, str] = {}
    finished = view.finished
    axis = view.numeric_axis()
    if axis is not None:
        x_label = AXIS_LABELS.get(axis, axis)
        stem = view.short[axis].replace(".", "_")
        for name, column, y_label, log_y, what in (
            (f"period_vs_{stem}", "mean_period_s", "mean step period [s]", False, "Mean step period"),
            (f"violation_vs_{stem}", "violation_position_max_m", r"max $\|\Phi\|$ [m]", True, "Largest |Phi|"),
            (f"wall_time_vs_{stem}", "wall_time_s", "integration wall time [s]", False, "Integration wall time"),
        ):
            lines = parameter_lines(view, axis, column)
            save_figure(parameter_lines_figure(x_label, y_label, lines, log_y), figure_dir, name)
            captions[name] = f"{what} against {axis}, one line per combination of the other swept values."
    else:
        labels = [view.label(r) for r in finished]
        for name, column, x_label, what in (
            ("mean_period", "mean_period_s", "mean step period [s]", "Mean step period"),
            ("wall_time", "wall_time_s", "integration wall time [s]", "Integration wall time"),
        ):
            save_figure(bar_figure(labels, [r[column] for r in finished], x_label), figure_dir, name)
            captions[name] = f"{what} of each finished run."
    if view.integrator_varies:
        save_figure(accuracy_cost_figure(accuracy_series(view)), figure_dir, "accuracy_vs_cost")
        captions["accuracy_vs_cost"] = (
            "Integrators: largest step-period difference from the group's reference run against wall time "
            "(reference runs, at zero, are not drawn)."
        )
    series, note = overlay_runs(view)
    if not series:
        return captions
    figures = {
        "period_vs_step": (step_period_figure(series), "Step period against step number"),
        "constraint_violation": (
            constraint_violation_figure(series),
            "Constraint violation (position, velocity) against time, log scale",
        ),
        "contact_forces": (
            contact_forces_figure(series),
            "Normal and friction force of the striking foot around a heel strike in the middle of each run",
        ),
        "energy": (
            energy_balance_figure(series),
            "Energy dissipated by normal damping and by friction, and the energy-balance residual",
        ),
        "slip": (slip_figure(series), "Stance-foot slip per step"),
        "phase_portrait": (phase_portrait_figure(series), "Phase portrait of the first leg"),
    }
    for name, (fig, caption) in figures.items():
        save_figure(fig, figure_dir, name)
        captions[name] = f"{caption}; {note}."
    return captions


def report_markdown(view: SweepView, tables: list[Table], captions: dict[str, str]) -> str:
    """report.md: what the sweep is, its tables, its figures."""
    counts: dict[str, int] = {}
    for row in view.rows:
        counts[row["status"]] = counts.get(row["status"], 0) + 1
    status_text = ", ".join(f"{n} {status}" for status, n in counts.items())
    lines = [
        f"# Sweep report: {view.manifest['name']}",
        "",
        view.manifest.get("description") or "",
        "",
        f"- Sweep file: `{view.manifest['source']}`; base config: `{view.manifest['base']}`",
        f"- Swept: {', '.join(f'`{a}`' for a in view.axes)}",
        f"- Runs: {len(view.rows)} ({status_text})",
    ]
    if view.manifest.get("overrides"):
        lines.append(f"- Command-line overrides: {', '.join(f'`{o}`' for o in view.manifest['overrides'])}")
    lines.append("")
    lines.append("Tables are also written as CSV and LaTeX in `tables/`; figures as PNG and SVG in `figures/`.")
    lines.append("")
    lines += [table.markdown(heading_level=2) for table in tables]
    lines.append("## Figures")
    lines.append("")
    for name, caption in captions.items():
        lines += [f"![{caption}](figures/{name}.png)", "", f"*{caption}* ([SVG](figures/{name}.svg))", ""]
    return "\n".join(lines)


def build_report(sweep_dir: Path, out_dir: Path | None = None) -> Report:
    """Write report.md, tables/*.{md,csv,tex} and figures/*.{png,svg} for the sweep in ``sweep_dir``."""
    view = SweepView.load(sweep_dir)
    if not view.finished:
        raise ConfigError(str(sweep_dir), "no finished run in this sweep (run or resume it first)")
    out_dir = out_dir or sweep_dir / "report"
    tables = tables_for(view)
    for table in tables:
        table.write(out_dir / "tables")
    captions = build_figures(view, out_dir / "figures")
    write_text_atomic(out_dir / "report.md", report_markdown(view, tables, captions))
    return Report(out_dir=out_dir, tables=tables, figures=captions)
