"""
Calibrating against measured periods, with a posterior
======================================================

``biped-sim fit`` adjusts config keys until the model's steps match a reference of measured ones: a global stage
(a Sobol design, polished), the least-squares optimum with standard errors, profile scans that say whether the
data fix each key, and, in the Bayesian mode, a posterior by emcee's ensemble sampler, whose likelihood weighs
each step by the standard error of its measured mean.

Tiny here: Garcia's simplest walker (rigid: each evaluation walks a few compiled steps in milliseconds), its
slope to be recovered from seven step periods with synthetic noise. The worked example of
``docs/experiments.md`` fits the compliant default walker's leg inertia and hip mass the same way (minutes).
"""

# %%
# A synthetic reference
# ---------------------
# The walker's own first seven periods at slope 0.009, each plus Gaussian noise (sd 0.002 in units of
# :math:`\sqrt{l/g}`): a reference file's content, marked synthetic in every field. A real one holds measured
# means, their single-trial sd and the number of trials (the how-to on measured periods).
from pathlib import Path
from tempfile import mkdtemp

import numpy as np
import pandas as pd
import yaml

from biped_sim import load_config
from biped_sim.config import derive
from biped_sim.io.references import load_reference
from biped_sim.studies.fit import calibrate, fit_problems, synthetic_reference

CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())
truth = load_config(CONFIGS / "simplest_walker.yaml")
reference_file = Path(mkdtemp()) / "synthetic_periods.yaml"
reference_file.write_text(synthetic_reference(truth, steps=7, noise=0.002, seed=3))
reference = load_reference(reference_file)
print(yaml.safe_load(reference_file.read_text())["values"])

# %%
# The fit
# -------
# One key, ``ground.slope``, searched in [0.005, 0.013] from a wrong start (0.012), then 800 posterior draws
# (16 walkers x 50 steps). ``executor=None`` evaluates in this process; a ``study_executor("local", 2)`` or a
# Dask cluster spreads the evaluations.
start = derive(truth, {"ground.slope": 0.012})
[(_, problem)] = fit_problems(start, reference, ["ground.slope=0.005:0.013"])
calibration = calibrate(problem, None, draws=800)
result = calibration.result
print(result.verdict)
pd.DataFrame([vars(e) for e in result.estimates])[["key", "start", "value", "standard_error", "at_bound"]]

# %%
# The posterior
# -------------
# The retained draws (burn-in discarded, thinned by the autocorrelation time) and the 90 % credible interval.
posterior = calibration.posterior
low, median, high = posterior.intervals["ground.slope"]
print(f"slope: median {median:.5f}, 90 % credible interval [{low:.5f}, {high:.5f}] (truth 0.009)")
print(f"acceptance {posterior.acceptance:.2f}, {len(posterior.samples)} draws kept")

# %%
from biped_sim.report.fit_figures import corner_figure, predictive_figure

corner = corner_figure(posterior, truth={"ground.slope": 0.009})

# %%
# The posterior predictive band of the periods against the reference (its error bars the standard errors).
band = predictive_figure(calibration)

# %%
# From the command line: ``biped-sim fit configs/simplest_walker.yaml --reference REF.yaml --param
# ground.slope=0.005:0.013 --posterior 800``, which writes ``fit.json``, the tables, ``posterior.h5`` and these
# figures. The draws go on into ``biped-sim uncertainty --from-fit`` (predictions with error bars).
np.testing.assert_allclose(median, 0.009, atol=3 * (high - low))  # the truth lies within the posterior's reach
