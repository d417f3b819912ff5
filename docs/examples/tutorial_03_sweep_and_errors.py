"""
A sweep and its error table against a reference
===============================================

A sweep runs every combination of some config keys, in parallel, one run directory each, and tabulates them;
``biped-sim report`` turns it into the paper's comparison tables and figures; ``biped-sim compare`` sets each
run's step periods against a reference, step by step, as Corral et al. (2020) set their model against Liu's
measured walker (their relative errors per step, 0-8 %, in the paper's Figure 6).

Here: two slopes by two integrators, 4 s each. The bundled demo (``make sweep-demo``) is four slopes by four
integrators, 15 s each.
"""

# %%
# A sweep file
# ------------
# A base config, keys set for every run, and the axes (a grid here; ``zip`` axes vary together).
from pathlib import Path
from tempfile import mkdtemp

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from biped_sim.sweep import load_sweep, local_executor, run_sweep

CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())
work = Path(mkdtemp())
sweep_file = work / "slopes_integrators_short.yaml"
sweep_file.write_text(f"""
name: slopes_integrators_short
description: Two slopes by two integrators, 4 s each.
base: {CONFIGS / "round_foot_walker.yaml"}
set:
  simulation.t_end: 4.0
  integrator.dt: 1.0e-4
grid:
  ground.slope: [0.015, 0.02]
  integrator.method: [dopri5, rk2]
""")
sweep = load_sweep(sweep_file)
print(len(sweep.runs), "runs")

# %%
# Run it on two local worker processes (``--executor dask`` runs the same on a Dask cluster). A rerun skips
# the finished runs: the sweep resumes.
with local_executor(jobs=2) as executor:
    outcome = run_sweep(sweep, work / "sweep", executor)
outcome

# %%
# The sweep table (``sweep.csv``) is a DataFrame:
table = outcome.to_pandas()
table[["run", "ground.slope", "integrator.method", "status", "n_steps", "mean_period_s", "speed_m_s", "wall_time_s"]]

# %%
# The report
# ----------
# Tables as Markdown, CSV and LaTeX, figures as PNG and SVG: here the integrator table, read from its CSV.
from biped_sim.report import build_report

report = build_report(work / "sweep")
pd.read_csv(report.out_dir / "tables" / "by_integrator.csv").iloc[:, :9]

# %%
# The error table against a reference
# -----------------------------------
# Liu's measured periods are not available to this project; the bundled reference
# ``synthetic_round_foot_periods.yaml`` holds the default walker's own first seven periods plus 1 ms of noise
# (synthetic, never to be presented as measured). Its steps are numbered from the release (step 1 ends at the
# first heel strike).
from biped_sim.io.references import load_reference
from biped_sim.report.targets import compare_targets
from biped_sim.studies.compare import compare_periods

reference = load_reference(CONFIGS / "references" / "synthetic_round_foot_periods.yaml")
series, missing = compare_targets(work / "sweep")
comparisons = [compare_periods(reference, periods, label) for label, periods in series]
errors = pd.DataFrame({c.label: c.relative_errors for c in comparisons}, index=pd.Index(reference.steps, name="step"))
errors.round(3)

# %%
# The same as bars per step, as the paper's Figure 6 shows its errors (theirs against Liu's walker, ours against
# a synthetic reference of our own walker: the numbers are not comparable, the layout is).
fig, ax = plt.subplots(figsize=(6, 3.2), layout="constrained")
width = 0.8 / len(errors.columns)
for i, label in enumerate(errors.columns):
    ax.bar(np.array(reference.steps) + (i - (len(errors.columns) - 1) / 2) * width, errors[label], width, label=label)
ax.set_xlabel("step")
ax.set_ylabel("|model - reference| / reference [%]")
ax.legend(fontsize=7)

# %%
# Each comparison's statistics (``compare_stats`` in the command's files):
pd.DataFrame(
    {
        c.label: {"steps": c.stats.n, "RMS error [s]": c.stats.rms_abs, "max error [%]": c.stats.max_rel}
        for c in comparisons
    }
).T
