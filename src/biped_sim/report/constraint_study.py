"""The constraint-violation study (the paper's Figures 10-11): drift of the standard method against Baumgarte.

Reads a finished sweep over ``formulation.baumgarte.alpha/beta`` and ``integrator.method``
(``configs/sweeps/constraint_violation.yaml``) and draws, per integrator (one column each), the
position violation ||Phi||, the velocity violation ||Phidot|| and, for spatial runs, the
Euler-parameter normalisation violation ||p.p - 1|| against time on log scales, one line per
pair of gains (alpha = beta = 0 is the standard method)::

    biped-sim sweep configs/sweeps/constraint_violation.yaml
    python -m biped_sim.report.constraint_study results/sweeps/constraint_violation docs/figures
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from biped_sim.errors import ConfigError
from biped_sim.integrate.driver import FIXED_STEP_METHODS
from biped_sim.io.trajectory import RunData, load_run
from biped_sim.plots import COLUMN_WIDTH_IN, PANEL_HEIGHT_IN, log_positive, log_scale, save_figure, style_of, styled

FIGURE_NAME = "constraint_violation"
INTEGRATOR_ORDER = ("euler", "rk2", "rk4", "dopri5", "dop853", "radau", "bdf")


def study_runs(sweep_dir: Path) -> dict[str, list[RunData]]:
    """The finished runs of a sweep, grouped by integrator (in INTEGRATOR_ORDER), each sorted by alpha."""
    runs_dir = sweep_dir / "runs"
    if not runs_dir.is_dir():
        raise ConfigError(str(sweep_dir), "not a sweep directory (no runs/)")
    groups: dict[str, list[RunData]] = {}
    for run_dir in sorted(runs_dir.iterdir()):
        if (run_dir / "summary.json").is_file():
            run = load_run(run_dir)
            groups.setdefault(run.config.integrator.method, []).append(run)
    if not groups:
        raise ConfigError(str(sweep_dir), "the sweep has no finished runs")
    ordered = sorted(groups, key=lambda method: INTEGRATOR_ORDER.index(method))
    return {m: sorted(groups[m], key=lambda r: r.config.formulation.baumgarte.alpha) for m in ordered}


def gains_label(run: RunData) -> str:
    """'standard' for alpha = beta = 0, else the Baumgarte gains."""
    gains = run.config.formulation.baumgarte
    if gains.alpha == 0 and gains.beta == 0:
        return "standard"
    if gains.alpha == gains.beta:
        return f"Baumgarte {gains.alpha:g}"
    return f"Baumgarte {gains.alpha:g}/{gains.beta:g}"


def integrator_label(run: RunData) -> str:
    """Integrator name with its step or tolerances."""
    integ = run.config.integrator
    if integ.method in FIXED_STEP_METHODS:
        return f"{integ.method}, dt = {integ.dt:g} s"
    return f"{integ.method}, rtol = {integ.rtol:g}"


@styled
def constraint_study_figure(groups: dict[str, list[RunData]]) -> Figure:
    """Violation against time: rows position, velocity (and normalisation), one column per integrator."""
    spatial = all(run.violation_normalization is not None for runs in groups.values() for run in runs)
    rows = 3 if spatial else 2
    cols = len(groups)
    fig = Figure(figsize=(COLUMN_WIDTH_IN * max(1.0, 0.62 * cols), PANEL_HEIGHT_IN * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, sharex=True, sharey="row", squeeze=False)
    for col, runs in enumerate(groups.values()):
        axes[0, col].set_title(integrator_label(runs[0]))
        for i, run in enumerate(runs):
            style = style_of(i)
            channels = [run.violation_position, run.violation_velocity]
            if spatial:
                channels.append(run.violation_normalization)
            for row, values in enumerate(channels):
                axes[row, col].plot(run.time, log_positive(np.asarray(values)), label=gains_label(run), **style)
        for row in range(rows):
            log_scale(axes[row, col])
        axes[-1, col].set_xlabel("time [s]")
    axes[0, 0].set_ylabel(r"$\|\Phi\|$ [m]")
    axes[1, 0].set_ylabel(r"$\|\dot\Phi\|$ [m/s]")
    if spatial:
        axes[2, 0].set_ylabel(r"$\|p^Tp - 1\|$")
    axes[0, 0].legend(frameon=False)
    return fig


def write_constraint_study(sweep_dir: Path, out_dir: Path) -> list[Path]:
    """Draw the study of ``sweep_dir`` into ``out_dir``/constraint_violation.{png,svg}."""
    return save_figure(constraint_study_figure(study_runs(sweep_dir)), out_dir, FIGURE_NAME)


def main(argv: list[str]) -> int:
    """``python -m biped_sim.report.constraint_study SWEEP_DIR [OUT_DIR]`` (default OUT_DIR: docs/figures)."""
    if len(argv) not in (1, 2):
        print("usage: python -m biped_sim.report.constraint_study SWEEP_DIR [OUT_DIR]", file=sys.stderr)
        return 2
    try:
        paths = write_constraint_study(Path(argv[0]), Path(argv[1] if len(argv) == 2 else "docs/figures"))
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for path in paths:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
