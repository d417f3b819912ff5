"""`biped-sim validate`: the whole report (slow), and the reference file it reads."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from biped_sim.studies.validation import load_rigid_references
from tests.conftest import invoke


def test_rigid_references_carry_their_sources() -> None:
    refs = load_rigid_references()
    for key in ("garcia1998", "goswami1998"):
        assert "citation" in refs[key]
    assert refs["garcia1998"]["period_doubling"]["where"].startswith("Abstract")
    assert refs["garcia1998"]["fixed_point"]["stance_angle"] == 0.20031090049483


@pytest.mark.slow
def test_validate_passes_and_writes_the_report(tmp_path: Path) -> None:
    """``biped-sim validate`` (CI runs it only here, in ``make test-slow``): every check passes, exit code 0, and
    the report is written, within 10 minutes of CPU: its wall time, in the report, is whatever else the machine
    runs (docs/guide/development.md, "Where CI time goes")."""
    before = os.times()
    result = invoke("validate", "--out", str(tmp_path))
    after = os.times()
    assert result.exit_code == 0, result.output
    report = (tmp_path / "report.md").read_text()
    assert "| check | expected | obtained | tolerance | pass |" in report
    written = json.loads((tmp_path / "report.json").read_text())
    assert written["checks"] and [check for check in written["checks"] if not check["passed"]] == []  # named if not
    assert written["wall_time_s"] > 0.0
    assert sum(after[:4]) - sum(before[:4]) < 600  # CPU s: user and system, this process and its finished children
