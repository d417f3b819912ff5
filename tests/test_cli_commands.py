"""The commands without a test module of their own (`drop-test`, `converge`, `bench`): output and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .conftest import CONFIGS, invoke, one_line_error


def test_drop_test_json_gives_the_effective_restitution_of_each_law_asked_for() -> None:
    result = invoke("drop-test", "--model", "hertz", "--model", "flores", "--restitution", "0.5", "--json")
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert [(row["model"], row["nominal_restitution"]) for row in rows] == [("hertz", 0.5), ("flores", 0.5)]
    assert rows[0]["effective_restitution"] == pytest.approx(1.0, abs=1e-4)  # Hertz is elastic
    assert rows[1]["effective_restitution"] == pytest.approx(0.5, abs=0.05)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["drop-test", "--model", "hertz2"], "--model: unknown normal law 'hertz2'"),
        (["drop-test", "--restitution", "1.5"], "--restitution: 1.5 is not in (0, 1]"),
        (["converge", str(CONFIGS / "rimless_wheel.yaml")], "walker.kind: converge compares the compliant and rigid"),
        (["converge", "missing.yaml"], "missing.yaml: no such config file"),
        (
            ["converge", str(CONFIGS / "round_foot_walker.yaml"), "--mu-kinetic", "1", "--mu-static", "0.5"],
            "--mu-static: must be >= the kinetic coefficient (1.0)",
        ),
        (["bench", "--config", "missing.yaml"], "missing.yaml: no such config file"),
        (["bench", "--quick", "--config", "bad.yaml"], "malformed YAML"),
    ],
)
def test_bad_input_to_the_other_commands_is_one_line_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, args: list[str], expected: str
) -> None:
    (tmp_path / "bad.yaml").write_text("walker: {leg_length: 0.5\n")
    monkeypatch.chdir(tmp_path)  # relative paths, and the default results/ directory, are here
    result = invoke(*args)
    assert result.exit_code == 2, result.output
    assert expected in one_line_error(result.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml"]  # nothing written
