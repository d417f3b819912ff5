"""The figure of a basin of attraction: the outcome of every cell, the fixed point marked."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from biped_sim.plots import COLUMN_WIDTH_IN, styled
from biped_sim.studies.basin import OUTCOMES, Basin

COLORS = ("0.9", "C1", "C0")  # fell, walks (not converged), converged


@styled
def basin_figure(basin: Basin) -> Figure:
    """Cells coloured by outcome (fell, walked K steps, converged to the gait); the fixed point as a star."""
    spec = basin.spec
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.8), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(
        spec.x.values, spec.y.values, basin.outcome, cmap=ListedColormap(COLORS), vmin=-0.5, vmax=2.5, shading="nearest"
    )
    fixed = basin.fixed_point
    handles = [Patch(color=c, label=name) for c, name in zip(COLORS, OUTCOMES, strict=True)]
    if fixed is not None:
        (star,) = ax.plot(fixed[spec.x.key], fixed[spec.y.key], "*", color="C3", markersize=8, label="fixed point")
        handles.append(star)
    ax.set_xlabel(spec.x.key)
    ax.set_ylabel(spec.y.key)
    ax.grid(False)
    walking = float(np.mean(basin.outcome != 0))
    ax.set_title(
        f"{spec.config.walker.kind}, slope {spec.config.ground.slope:g}: {walking:.1%} walk {spec.steps} steps"
    )
    ax.legend(handles=handles, loc="best")
    return fig
