"""`biped-sim validate`'s MuJoCo comparison: run when MuJoCo is installed, one skip line otherwise (CI has none; the
comparison itself: tests/test_space_compliant.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from biped_sim.bench import mujoco_check
from biped_sim.studies import validation
from tests.conftest import invoke


def validate_without_checks(monkeypatch: pytest.MonkeyPatch, out: Path, installed: bool) -> tuple[str, list[Any]]:
    """`biped-sim validate`'s output and the extra stages it handed the report, MuJoCo ``installed`` or not (the
    report's checks stood in for: none)."""
    handed: list[Any] = []

    def no_checks(out: Any, progress: Any = None, extra: Any = ()) -> tuple[list, dict[str, float]]:
        handed.extend(extra)
        return [], {"wall_time_s": 0.0}

    monkeypatch.setattr(mujoco_check, "find_spec", lambda name: object() if installed else None)
    monkeypatch.setattr(validation, "run_validation", no_checks)
    result = invoke("validate", "--out", str(out))
    assert result.exit_code == 0, result.output
    return result.output, handed


def test_without_mujoco_validate_prints_one_skip_line(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    output, handed = validate_without_checks(monkeypatch, tmp_path, installed=False)
    assert handed == []
    assert [line for line in output.splitlines() if line.startswith("skip:")] == [mujoco_check.SKIP]


def test_with_mujoco_validate_runs_the_comparison_of_a_walker_in_space(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    output, handed = validate_without_checks(monkeypatch, tmp_path, installed=True)
    assert [check for _, check in handed] == [mujoco_check.mujoco_space_checks]
    assert "skip:" not in output
