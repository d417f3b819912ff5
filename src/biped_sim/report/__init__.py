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

A sweep need not be complete: runs that raised (``error``), were not run (``pending``) or have any
other status without results are listed in the tables with empty metrics, and left out of the figures
with one line saying how many and why. The report is written into a temporary directory that replaces
the old one only when everything is written (:func:`~biped_sim.io.output.staged_directory`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from biped_sim.errors import ConfigError
from biped_sim.io.atomic import write_text_atomic
from biped_sim.io.output import OutputKind, check_output_dir, staged_directory
from biped_sim.io.tables import Table
from biped_sim.report.figures import build_figures
from biped_sim.report.tables import tables_for
from biped_sim.report.view import SweepView

__all__ = ["REPORT_OUTPUT", "Report", "build_report", "report_markdown"]

REPORT_OUTPUT = OutputKind(
    "report", ("report.md", *(f"tables/*.{ext}" for ext in ("md", "csv", "tex")), "figures/*.png", "figures/*.svg")
)


@dataclass
class Report:
    """What ``build_report`` wrote."""

    out_dir: Path
    tables: list[Table]
    figures: dict[str, str]  # name -> caption
    missing: str | None = None  # one line on the runs without results, if any

    @property
    def markdown_path(self) -> Path:
        return self.out_dir / "report.md"


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
    missing = view.missing_note("drawn")
    if missing:
        lines += [f"*{missing}.*", ""]
    for name, caption in captions.items():
        lines += [f"![{caption}](figures/{name}.png)", "", f"*{caption}* ([SVG](figures/{name}.svg))", ""]
    return "\n".join(lines)


def build_report(sweep_dir: Path, out_dir: Path | None = None) -> Report:
    """Write report.md, tables/*.{md,csv,tex} and figures/*.{png,svg} for the sweep in ``sweep_dir``.

    The output directory (default ``sweep_dir/report``) is checked before anything is computed and replaced as
    a whole when everything is written; ConfigError on a damaged sweep or an unusable output directory.
    """
    view = SweepView.load(sweep_dir)
    if not view.finished:
        raise ConfigError(str(sweep_dir), "no finished run in this sweep (run or resume it first)")
    out_dir = out_dir or sweep_dir / "report"
    check_output_dir(out_dir, REPORT_OUTPUT)
    tables = tables_for(view)
    with staged_directory(out_dir, REPORT_OUTPUT) as stage:
        for table in tables:
            table.write(stage / "tables")
        captions = build_figures(view, stage / "figures")
        write_text_atomic(stage / "report.md", report_markdown(view, tables, captions))
    return Report(out_dir=out_dir, tables=tables, figures=captions, missing=view.missing_note("drawn"))
