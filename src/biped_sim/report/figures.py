"""The report's figures: parameter lines, overlays of runs, accuracy against cost."""

from __future__ import annotations

from pathlib import Path

from biped_sim.io.trajectory import RunData, load_run
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
from biped_sim.report.tables import integrator_accuracy
from biped_sim.report.view import AXIS_LABELS, MAX_OVERLAY, SweepView, fmt_value
from biped_sim.rigid.start import INTEGRATOR as RIGID_INTEGRATOR


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
        note = f"runs at {view.short[axis]} = {fmt_value(middle)}"
    if len(rows) > MAX_OVERLAY:
        rows = rows[:MAX_OVERLAY]
        note += f" (first {MAX_OVERLAY})"
    return [(view.label(row, exclude=exclude), load_run(view.sweep_dir / "runs" / row["run"])) for row in rows], note


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
