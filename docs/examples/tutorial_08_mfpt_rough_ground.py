r"""
Survival on rough ground: the mean first-passage time
=====================================================

On ground that varies step to step a passive walker eventually falls; how long it walks on average, the mean
first-passage time (MFPT, in steps), measures its robustness (Byl and Tedrake 2009). ``biped-sim mfpt`` walks
many seeds of random ground per roughness level until a fall or a cap, and estimates the MFPT of a geometric
first passage censored at the cap, with a likelihood-ratio interval.

The rimless wheel on slopes drawn per step, :math:`\gamma_k \sim N(\gamma, \sigma^2)`, is the cheap case: its
apex-to-apex map is analytic, so the walks' estimate can be checked against the Markov chain's exact MFPT.
"""

# %%
from pathlib import Path

import pandas as pd

from biped_sim import load_config
from biped_sim.report.uncertainty import mfpt_figure
from biped_sim.studies.uncertainty.mfpt import mfpt_curve

CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())
wheel = load_config(CONFIGS / "rimless_wheel.yaml")
curve = mfpt_curve(wheel, "slope", [0.04, 0.06, 0.08], seeds=100, cap=2000)
curve

# %%
# One row per level: the walks' MFPT with its 95 % interval, how many fell and how many reached the cap, and
# the chain's exact value.
pd.DataFrame(curve.to_pandas()).round(2)

# %%
figure = mfpt_figure([curve])

# %%
# The compliant default walker on random heights (``--ground height``) is the same study at a cost of seconds
# per walk: ``biped-sim mfpt configs/round_foot_walker.yaml --roughness 0.002,0.02 --seeds 20``.
