"""The posterior's 90 % credible intervals cover the truth in about 90 % of repeated noisy experiments (slow).

Each repeat draws a new synthetic reference (the default walker's first three periods at leg inertia 0.005
plus Gaussian noise of std 0.5 ms, given as the reference's std), fits the leg inertia and samples its
posterior (8 walkers x 100 steps). Over 20 repeats the number covered is binomial(20, 0.9) if the intervals
are calibrated: 14 or fewer has probability 0.011, so the test asks for 15 to 20; and the intervals must be
as narrow as the data allow (median width within 30 % of the Laplace approximation's 2 x 1.645 standard
errors), so that always-covering, prior-wide intervals fail too.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from biped_sim.io.references import Reference, ReferenceSpec
from biped_sim.studies.fit import calibrate, fit_problems, synthetic_reference_data
from biped_sim.sweep import local_executor
from tests.test_fit import BOUNDS, TRUE_INERTIA, _config

REPEATS, NOISE_S, STEPS = 20, 5e-4, 3


@pytest.mark.slow
def test_ninety_percent_intervals_cover_the_truth_about_ninety_percent_of_the_time() -> None:
    truth, start = _config(f"walker.leg_inertia={TRUE_INERTIA}"), _config("walker.leg_inertia=0.0047")
    covered, widths, laplace = 0, [], []
    with local_executor(2) as pool:
        for seed in range(100, 100 + REPEATS):
            spec = ReferenceSpec.model_validate(synthetic_reference_data(truth, STEPS, NOISE_S, seed))
            problem = fit_problems(start, Reference(Path(f"synthetic-{seed}"), spec), [BOUNDS])[0][1]
            calibration = calibrate(problem, pool, draws=800, walkers=8, seed=seed)
            assert calibration.posterior is not None
            low, _, high = calibration.posterior.intervals["walker.leg_inertia"]
            covered += int(low <= TRUE_INERTIA <= high)
            widths.append(high - low)
            laplace.append(2 * 1.645 * calibration.result.estimates[0].standard_error)
    ratio = float(np.median(np.array(widths) / np.array(laplace)))
    print(f"90 % intervals covered the truth in {covered} of {REPEATS}; median width / Laplace width {ratio:.3f}")
    assert 15 <= covered <= REPEATS, f"{covered} of {REPEATS} covered"
    assert 0.7 < ratio < 1.3, ratio
