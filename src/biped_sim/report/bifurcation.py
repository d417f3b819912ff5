"""A bifurcation diagram's figure: steady step periods and the period-1 branch against the slope."""

from __future__ import annotations

from matplotlib.figure import Figure

from biped_sim.plots import COLUMN_WIDTH_IN, styled
from biped_sim.studies.bifurcation import BifurcationDiagram


@styled
def bifurcation_figure(diagram: BifurcationDiagram) -> Figure:
    """Steady step periods (brute force) and the period-1 branch (stable, unstable) against the slope."""
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.6))
    ax = fig.add_subplot()
    xs = [s for s, periods in diagram.brute for _ in periods]
    ys = [p for _, periods in diagram.brute for p in periods]
    ax.plot(xs, ys, ".", color="0.3", markersize=1.5, label="steady state (brute force)")
    stable = [(c.slope, c.step_period) for c in diagram.cycles if c is not None and c.stable]
    unstable = [(c.slope, c.step_period) for c in diagram.cycles if c is not None and not c.stable]
    if stable:
        ax.plot(*zip(*stable, strict=True), "-", color="C0", label="period 1, stable")
    if unstable:
        ax.plot(*zip(*unstable, strict=True), "--", color="C3", label="period 1, unstable")
    if diagram.period_doubling_slope is not None:
        ax.axvline(diagram.period_doubling_slope, color="0.5", linewidth=0.6)
    ax.set_xlabel("slope [rad]")
    ax.set_ylabel("step period")
    ax.legend(loc="best")
    fig.tight_layout()
    return fig
