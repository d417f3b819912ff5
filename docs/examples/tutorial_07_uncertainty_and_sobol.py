"""
Uncertainty and Sobol indices
=============================

What a walker does when its parameters are known only to within some spread: ``biped-sim uncertainty`` draws
samples of the uncertain keys (a scrambled Sobol design, Latin hypercube, or a fit's posterior draws), runs
each, and reports the statistics of each output over the samples that walked, the probability of walking with
its Wilson interval, the step-period bands, and, with Saltelli's design, the Sobol indices: the share of an
output's variance due to each key alone (first order, :math:`S_1`) and with its interactions (total,
:math:`S_T`), with bootstrap confidence intervals (SALib).

Tiny here: the rigid compass gait (Goswami's walker, its compiled step map) with three uncertain keys and 32
base samples (160 runs). The compliant default walker's study, 1,024 samples of 4 s each, takes minutes on two
workers (README's performance notes).
"""

# %%
# The study
# ---------
# Each key's distribution is ``KEY=KIND:ARGS`` (uniform, normal, lognormal, triangular, interval), as on the
# command line; the design is Saltelli's, which the indices need: base samples x (keys + 2) runs.
from pathlib import Path

import pandas as pd

from biped_sim import load_config
from biped_sim.studies.uncertainty.distributions import parse_param
from biped_sim.studies.uncertainty.study import UncertaintySpec, run_study

CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())
config = load_config(CONFIGS / "compass_goswami.yaml", ["dynamics=rigid", "simulation.t_end=15"])
keys = [
    parse_param("ground.slope=uniform:0.05:0.055"),
    parse_param("walker.hip_mass=normal:10:0.3"),
    parse_param("walker.leg_mass=uniform:4.8:5.2"),
]
study = run_study(UncertaintySpec(config, tuple(keys), samples=32, method="saltelli", seed=0), out_dir=None)
study

# %%
# The statistics of each output over the samples that walked (``to_pandas``), and one row per sample
# (``samples_frame``) for any plot of your own.
study.to_pandas()[["n", "mean", "sd", "q0.05", "q0.95"]]

# %%
samples = study.samples_frame()
ax = samples.plot.scatter(x="ground.slope", y="steady_period", c="walker.hip_mass", figsize=(5, 3.2))

# %%
# The Sobol indices
# -----------------
# Ranked per output, with their 95 % bootstrap intervals. With 32 base samples the intervals are wide; the
# indices sharpen as the square root of the base samples.
rows = []
for output in study.indices.outputs:
    if output.indices is None:
        continue
    for key, first, total in zip(study.spec.keys, output.indices["S1"], output.indices["ST"], strict=True):
        rows.append({"output": output.output, "key": key, "S1": first, "ST": total})
pd.DataFrame(rows).set_index(["output", "key"]).round(3)

# %%
from biped_sim.report.uncertainty import sobol_figure

sobol = sobol_figure(study.indices)
