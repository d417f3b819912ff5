"""The uncertainty study's checks against known answers (slow tier; `biped-sim validate` runs them too)."""

from __future__ import annotations

import pytest

from biped_sim.studies.uncertainty.checks import (
    ishigami_checks,
    mean_period_checks,
    simplest_index_checks,
    wheel_mfpt_checks,
)


@pytest.mark.slow
@pytest.mark.parametrize("checks", [ishigami_checks, simplest_index_checks, mean_period_checks, wheel_mfpt_checks])
def test_the_uncertainty_study_meets_its_known_answers(checks) -> None:  # type: ignore[no-untyped-def]
    failed = [c for c in checks() if not c.passed]
    assert failed == []


def test_ishigami_indices_come_out_of_the_same_estimator_code() -> None:
    """Cheap enough for the fast tier: the design and the estimator alone."""
    assert all(c.passed for c in ishigami_checks())
