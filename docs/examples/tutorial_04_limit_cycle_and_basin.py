r"""
A limit cycle, its multipliers and its basin
============================================

A passive gait is a periodic orbit: the state just after one heel strike maps, through a step, onto the state
just after the next, :math:`z_{k+1} = P(z_k)`. A period-1 gait is a fixed point :math:`z^* = P(z^*)`; it is
stable when every eigenvalue (Floquet multiplier) of the Jacobian :math:`\partial P / \partial z` at
:math:`z^*` lies inside the unit circle. Its basin of attraction is the set of starts that walk onto it.

Here Garcia's simplest walker (rigid: point feet, massless legs, a plastic heel strike; nondimensional with
:math:`g = l = 1`), whose step map is compiled and cheap. ``biped-sim limit-cycle``, ``bifurcation`` and ``basin``
do the same from the command line.
"""

# %%
# The fixed point and its multipliers
# -----------------------------------
# Newton on the step map (tolerance 1e-10), multipliers by central differences of the map. The section
# coordinates are the post-impact variables the strike leaves free.
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from biped_sim import load_config
from biped_sim.studies.limit_cycle import limit_cycle

CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())
config = load_config(CONFIGS / "simplest_walker.yaml")
cycle = limit_cycle(config)
print("converged:", cycle.converged, "residual", f"{cycle.residual:.1e}")
print("fixed point:", {key: round(value, 5) for key, value in cycle.fixed_point.items()})
print("step period", round(cycle.step_period, 4), "step length", round(cycle.step_length, 4))
print("multipliers:", np.round(cycle.multipliers, 4), "stable:", cycle.stable)

# %%
# Multipliers in the complex plane, against the unit circle.
fig, ax = plt.subplots(figsize=(3.5, 3.5), layout="constrained")
angle = np.linspace(0, 2 * np.pi, 200)
ax.plot(np.cos(angle), np.sin(angle), "k:", lw=0.8)
ax.plot(cycle.multipliers.real, cycle.multipliers.imag, "o", color="C3")
ax.set_aspect("equal")
ax.set_xlabel("Re")
ax.set_ylabel("Im")
ax.set_title("Floquet multipliers", fontsize=9)

# %%
# The basin
# ---------
# Every cell of a grid over the stance angle and rate (the swing leg as a heel strike leaves it, Garcia's
# relations) walks up to 30 steps and is classified: it falls (after how many steps), walks, or converges to the
# gait. The simplest walker's basin is a thin sliver (Schwab and Wisse 2001): a 31 x 31 grid close around the
# fixed point here; ``biped-sim basin configs/simplest_walker.yaml --x stance_angle=0.02:0.42:41 --y
# stance_rate=-0.6:0:41`` maps the wider view of the gallery's figure. The period-1 gait along the slope, up to
# its period doubling, is ``biped-sim bifurcation``.
from biped_sim.report.basin import basin_figure
from biped_sim.studies.basin import BasinSpec, map_basin, parse_axis

spec = BasinSpec(
    config,
    parse_axis("x", "stance_angle=0.12:0.28:31"),
    parse_axis("y", "stance_rate=-0.32:-0.08:31"),
    steps=30,
)
basin = map_basin(spec, out_dir=None)
summary = basin.to_json()
print(f"walking: {summary['fraction_walking']:.2f} of the cells, converged: {summary['fraction_converged']:.2f}")
figure = basin_figure(basin)
