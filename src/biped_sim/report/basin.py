"""The figure of a basin of attraction: the outcome of every cell, the fixed point marked."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from biped_sim.plots import COLUMN_WIDTH_IN, styled
from biped_sim.studies.basin import OUTCOMES, Basin

COLORS = ("0.9", "C1", "C0")  # fell, walks (not converged), converged


def gait_points(basin: Basin) -> tuple[list[float], list[float]]:
    """Where the gait is on the grid: the fixed point, or along a parameter axis each value's gait (if any)."""
    spec = basin.spec
    if spec.parameter_axis is None:
        fixed = basin.fixed_point
        return ([fixed[spec.x.key]], [fixed[spec.y.key]]) if fixed is not None else ([], [])
    along_x = spec.x.is_parameter
    state_key = spec.y.key if along_x else spec.x.key
    values = (spec.x if along_x else spec.y).values
    pairs = [(float(v), gait[state_key]) for v, gait in zip(values, basin.parameter_gaits, strict=True) if gait]
    points = pairs if along_x else [(s, v) for v, s in pairs]
    return [p[0] for p in points], [p[1] for p in points]


@styled
def basin_figure(basin: Basin) -> Figure:
    """Cells coloured by outcome (fell, walked K steps, converged to the gait); the fixed point as a star."""
    spec = basin.spec
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.8), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(
        spec.x.values, spec.y.values, basin.outcome, cmap=ListedColormap(COLORS), vmin=-0.5, vmax=2.5, shading="nearest"
    )
    handles = [Patch(color=c, label=name) for c, name in zip(COLORS, OUTCOMES, strict=True)]
    xs, ys = gait_points(basin)
    if xs:
        (star,) = ax.plot(xs, ys, "*", color="C3", markersize=8 if len(xs) == 1 else 5, label="fixed point")
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
