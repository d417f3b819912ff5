"""`biped-sim validate`: the whole report (slow), and the reference file it reads."""

from __future__ import annotations

from pathlib import Path

import pytest

from biped_sim.studies.validation import load_rigid_references, run_validation


def test_rigid_references_carry_their_sources() -> None:
    refs = load_rigid_references()
    for key in ("garcia1998", "goswami1998"):
        assert "citation" in refs[key]
    assert refs["garcia1998"]["period_doubling"]["where"].startswith("Abstract")
    assert refs["garcia1998"]["fixed_point"]["stance_angle"] == 0.20031090049483


@pytest.mark.slow
def test_validation_passes_and_writes_the_report(tmp_path: Path) -> None:
    checks, extras = run_validation(tmp_path)
    assert all(c.passed for c in checks), [c for c in checks if not c.passed]
    report = (tmp_path / "report.md").read_text()
    assert "| check | expected | obtained | tolerance | pass |" in report
    assert extras["wall_time_s"] < 600
