"""The uncertainty study's checks against known answers: every one is a row of ``biped-sim validate``, which the slow
tier runs and checks once (tests/test_validation.py); the fast tier checks the estimator on Ishigami's function."""

from __future__ import annotations

from biped_sim.studies.uncertainty.checks import ishigami_checks


def test_ishigami_indices_come_out_of_the_same_estimator_code() -> None:
    """Cheap enough for the fast tier: the design and the estimator alone."""
    assert all(c.passed for c in ishigami_checks())
