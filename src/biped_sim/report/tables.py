"""The report's comparison tables: all runs, integrators, normal laws, friction laws, Baumgarte."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from biped_sim.io.tables import Column, Table
from biped_sim.io.trajectory import load_summary
from biped_sim.report.view import (
    ACCEPTED,
    ADAPTIVE,
    FINISHED,
    LAST_PERIOD,
    ORDER,
    PERIOD,
    RESIDUAL,
    RHS,
    SPEED,
    STATUS,
    STEPS,
    VIOLATION_POS,
    VIOLATION_VEL,
    WALL,
    SweepView,
)


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


def _model_table(view: SweepView, key: str, header: str, name: str, title: str, measures: list[Column]) -> Table:
    """Runs grouped by the law in ``key``: the law, the other swept values, status, gait, ``measures``, cost."""
    columns = [Column(key, header), *view.param_columns((key,)), STATUS, STEPS, PERIOD, SPEED, *measures, WALL]
    return Table(name, title, columns, _grouped(view.rows, lambda r: r[key]))


def normal_model_table(view: SweepView) -> Table:
    """Normal contact force laws compared: penetration, peak force, dissipation."""
    measures = [
        Column("max_penetration_m", "max penetration", "m", ".2e"),
        Column("peak_normal_force_N", "peak normal force", "N", ".1f"),
        Column("energy_dissipated_normal_J", "dissipated (normal)", "J", ".3f"),
        Column("energy_dissipated_friction_J", "dissipated (friction)", "J", ".3f"),
    ]
    return _model_table(
        view, "contact.model", "normal force model", "by_normal_model", "Normal contact force models", measures
    )


def friction_model_table(view: SweepView) -> Table:
    """Friction laws compared: slip per step, friction dissipation, cost in right-hand sides."""
    measures = [
        Column("slip_mean_m", "mean |slip| per step", "m", ".2e"),
        Column("slip_max_m", "max |slip| per step", "m", ".2e"),
        Column("energy_dissipated_friction_J", "dissipated (friction)", "J", ".3f"),
    ]
    table = _model_table(view, "friction.model", "friction model", "by_friction_model", "Friction models", measures)
    table.columns.append(RHS)
    return table


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
