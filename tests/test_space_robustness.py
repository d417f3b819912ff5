"""`biped-sim robustness` of a walker in space: pushes along and across the slope on the rigid step map (flat ground
only: no steps, rough ground or GSN), bracketed by runs, in the table and the JSON."""

from __future__ import annotations

import json
import math

import pytest

from biped_sim import load_config
from biped_sim.studies.robustness import (
    PUSH_TOLERANCE,
    Gait,
    Robustness,
    gait_start,
    largest_disturbance,
    robustness,
    robustness_configs,
    robustness_table,
    trial,
)

from .conftest import CONFIGS, invoke

TOY = CONFIGS / "space" / "tinkertoy.yaml"


@pytest.fixture(scope="module")
def toy_gait() -> Gait:
    return gait_start(load_config(TOY))


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_largest_lateral_push_the_toy_survives_is_bracketed_by_runs(toy_gait: Gait, sign: float) -> None:
    good, bad = largest_disturbance(toy_gait, "lateral", sign)
    assert bad is not None and 0.0 < good < bad <= good + PUSH_TOLERANCE * bad
    assert trial(toy_gait, "lateral", sign * good).survived
    assert not trial(toy_gait, "lateral", sign * bad).survived


def test_a_walker_in_space_is_studied_in_its_own_dynamics_on_flat_ground_with_lateral_pushes() -> None:
    config = load_config(TOY)
    assert [c.dynamics for c in robustness_configs(config)] == ["rigid"]
    result = robustness(config)
    assert result.step_down is None and result.step_up is None and result.rough_survival == {}
    assert math.isnan(result.gsn)
    for searched in (result.push_forward, result.push_backward, result.push_right, result.push_left):
        assert searched is not None and searched[1] is not None and 0.0 < searched[0] < searched[1]
    table = robustness_table([result])
    keys = [column.key for column in table.columns]
    assert "push_right" in keys and "push_left" in keys and not any(key.startswith("rough") for key in keys)
    assert any("flat ground only" in note for note in table.notes)


def test_the_planar_table_has_no_lateral_columns() -> None:
    searched = (0.1, 0.2)
    planar = Robustness("rigid", "simplest", searched, searched, searched, searched, {0.001: 1.0}, 2.0, 1.0, 1.0)
    assert "push_right" not in [column.key for column in robustness_table([planar]).columns]


@pytest.mark.slow
def test_the_command_reports_a_walker_in_space_s_lateral_pushes_as_json() -> None:
    result = invoke("robustness", str(TOY), "--json")
    assert result.exit_code == 0, result.stderr
    (doc,) = json.loads(result.stdout)
    assert doc["push_right"][0] > 0.0 and doc["push_left"][0] > 0.0 and doc["step_down"] is None
