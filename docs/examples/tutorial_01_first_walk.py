"""
Your first walk
===============

Load the default walker (a round-foot compass on a 0.02 rad slope, compliant Flores contact with Ambrosio
friction), simulate a few steps, read its step table, plot it and draw one frame of its animation.

The bundled config walks 15 s (34 steps); three seconds show the first steps and keep this page fast.
"""

# %%
# Load and simulate
# -----------------
# :func:`biped_sim.load_config` reads a YAML file and applies ``--set``-style overrides; :func:`biped_sim.simulate`
# integrates and measures it, writing nothing.
from pathlib import Path
from tempfile import mkdtemp

import matplotlib.pyplot as plt

from biped_sim import load_config, run, simulate

# the bundled configs, found from wherever this script runs (the repository or docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())

config = load_config(CONFIGS / "round_foot_walker.yaml", ["simulation.t_end=3.0"])
result = simulate(config)
result

# %%
# The result says how the run ended (``walking``, ``fell``, ``diverged`` or ``timeout``) and what it measured:
# one row per heel strike, the step it begins.
print(result.status, result.summary["n_steps"], "heel strikes")
print("step periods [s]:", result.step_periods.round(4))
steps = result.to_pandas()
steps

# %%
# Plot
# ----
# The compliant run keeps its integration: the hip's path and the contact channels are computed when first asked.
fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 4.5), sharex=True, layout="constrained")
time = result.run.t
top.plot(time, result.hip[:, 1], color="C0")
top.set_ylabel("hip height [m]")
for foot in range(result.contact["normal_force"].shape[1]):
    bottom.plot(time, result.contact["normal_force"][:, foot], label=f"foot {foot + 1}")
bottom.set_xlabel("time [s]")
bottom.set_ylabel("normal force [N]")
bottom.legend()

# %%
# Write, read back, draw
# ----------------------
# :func:`biped_sim.run` simulates and writes the run directory (``trajectory.h5``, ``summary.json``,
# ``steps.csv``, ``config.yaml``), as ``biped-sim run`` does. The figures and the animation read that
# directory: here the walker's poses over one step (``biped-sim plot``'s ``walker`` figure) and one frame
# of ``biped-sim animate``.
from biped_sim.animate import WalkerDrawing
from biped_sim.io.trajectory import load_run
from biped_sim.plots import walker_figure

out = Path(mkdtemp()) / "first_walk"
run(config, out)
data = load_run(out)
poses = walker_figure(data)

# %%
frame = plt.figure(figsize=(4, 3.2))
drawing = WalkerDrawing(data, frame)
drawing.draw(len(data.time) // 2)  # the sample in the middle of the run

# %%
# From the command line the same is ``biped-sim run configs/round_foot_walker.yaml --set simulation.t_end=3``,
# then ``biped-sim plot RUN_DIR`` and ``biped-sim animate RUN_DIR --out walk.gif``.
