"""`biped-sim robustness`: the bracketing search, the disturbed runs, the gait sensitivity norm, the command."""

from __future__ import annotations

import json

import pytest

from biped_sim import load_config
from biped_sim.studies.robustness import (
    GSN_STEP,
    STEP_TOLERANCE,
    Gait,
    Robustness,
    gait_sensitivity,
    gait_start,
    largest_survived,
    robustness_table,
    trial,
)

from .conftest import CONFIGS, invoke, one_line_error

SIMPLEST = CONFIGS / "simplest_walker.yaml"


@pytest.fixture(scope="module")
def simplest_gait() -> Gait:
    return gait_start(load_config(SIMPLEST))


@pytest.mark.parametrize(("relative", "tolerance"), [(False, 1e-4), (True, 1e-2)])
def test_the_search_brackets_the_threshold(relative: bool, tolerance: float) -> None:
    tried: list[float] = []

    def survives(size: float) -> bool:
        tried.append(size)
        return size <= 0.0123

    good, bad = largest_survived(survives, 0.001, 1.0, tolerance, relative)
    assert bad is not None and good <= 0.0123 < bad
    assert bad - good <= (tolerance * bad if relative else tolerance)
    assert good in tried and bad in tried
    # a walker that survives the cap: the cap, and no failure seen
    assert largest_survived(lambda size: True, 0.001, 0.5, tolerance, relative) == (0.5, None)


def test_the_largest_step_down_is_bracketed_by_runs(simplest_gait: Gait) -> None:
    good, bad = largest_survived(
        lambda h: trial(simplest_gait, "step", -h).survived, 0.001, 0.5, STEP_TOLERANCE, relative=False
    )
    assert bad is not None and 0.0 < good < bad <= good + STEP_TOLERANCE
    assert trial(simplest_gait, "step", -good).survived
    assert not trial(simplest_gait, "step", -bad).survived


def test_the_gait_sensitivity_norm_is_a_linear_response(simplest_gait: Gait) -> None:
    e = GSN_STEP["rigid"]
    gsn = gait_sensitivity(simplest_gait, e)
    assert gsn > 1.0  # a step down really changes the gait
    assert gait_sensitivity(simplest_gait, e / 2) == pytest.approx(gsn, rel=1e-3)


def test_the_command_refuses_a_dynamics_the_walker_lacks() -> None:
    result = invoke("robustness", str(SIMPLEST), "--dynamics", "compliant")
    assert result.exit_code == 2
    assert "--dynamics" in one_line_error(result.stderr)
    result = invoke("robustness", str(SIMPLEST), "--dynamics", "soft")
    assert result.exit_code == 2
    assert "--dynamics" in one_line_error(result.stderr)


@pytest.mark.slow
def test_the_command_reports_every_measure() -> None:
    result = invoke("robustness", str(SIMPLEST), "--seeds", "2", "--json")
    assert result.exit_code == 0, result.stderr
    (doc,) = json.loads(result.stdout)
    assert doc["dynamics"] == "rigid" and doc["walker"] == "simplest"
    for key in ("step_down", "step_up", "push_forward", "push_backward"):
        good, bad = doc[key]
        assert bad is None or 0.0 <= good < bad
    assert [row["roughness"] for row in doc["rough_survival"]] == [0.001, 0.002, 0.005, 0.01]
    assert all(0.0 <= row["survival"] <= 1.0 for row in doc["rough_survival"])
    assert doc["gsn"] > 0.0


def test_the_table_shows_the_largest_sizes_survived() -> None:
    result = Robustness(
        dynamics="rigid",
        walker="rimless_wheel",
        step_down=(0.5, None),
        step_up=(0.0479, 0.048),
        push_forward=(2.0, None),
        push_backward=(0.32, 0.325),
        rough_survival={0.001: 1.0, 0.01: 0.25},
        gsn=22.2,
        leg_length=1.0,
        push_scale=3.13,
    )
    table = robustness_table([result])
    (row,) = table.rows
    assert row["step_down"] == ">= 0.5" and row["push_forward"] == ">= 2"
    assert row["step_up"] == 0.0479 and row["rough_0.01"] == 0.25
    assert "| rimless_wheel | rigid | >= 0.5 | 0.0479 |" in table.markdown()
    assert json.loads(json.dumps(result.to_json()))["rough_survival"][1] == {"roughness": 0.01, "survival": 0.25}
