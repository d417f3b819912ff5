"""The walker description (walker.kind: description): a tree of bodies, joints with stops, feet and legs."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from biped_sim.config import config_from_dict, load_config
from biped_sim.errors import ConfigError

KNEED = load_config(Path(__file__).parent / "data" / "kneed_walker.yaml")  # configs/ once it runs


def _kneed_dict() -> dict[str, Any]:
    return copy.deepcopy(KNEED.model_dump(mode="json"))


def test_kneed_walker_names_its_state_keys_from_its_legs() -> None:
    assert KNEED.walker.description is not None
    assert KNEED.walker.description.state_keys() == [
        f"{side}_{body}_{what}"
        for side in ("stance", "swing")
        for body in ("thigh", "shank")
        for what in ("angle", "rate")
    ]


def test_one_body_legs_keep_the_readme_keys() -> None:
    data = _kneed_dict()
    data["walker"]["description"]["legs"] = [["thigh_1"], ["thigh_2"]]
    described = config_from_dict(data).walker.description
    assert described is not None
    assert described.state_keys() == ["stance_angle", "stance_rate", "swing_angle", "swing_rate"]


def test_initial_state_of_a_described_walker_takes_its_own_keys() -> None:
    keys = KNEED.walker.description.state_keys() if KNEED.walker.description else []
    data = _kneed_dict()
    data["simulation"]["initial"] = dict.fromkeys(keys, 0.1)
    assert config_from_dict(data).simulation.initial == dict.fromkeys(keys, 0.1)
    data["simulation"]["initial"] = dict.fromkeys(keys[:-1], 0.1)
    with pytest.raises(ConfigError, match=r"simulation\.initial: expected the keys stance_thigh_angle"):
        config_from_dict(data)
    data["simulation"]["initial"] = dict.fromkeys(keys, True)
    with pytest.raises(ConfigError, match=r"simulation\.initial"):  # true is not 1.0
        config_from_dict(data)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["bodies"].append(dict(d["bodies"][0])), "bodies: names must be unique"),
        (lambda d: d["feet"][0].update(body="calf_1"), "feet: unknown body 'calf_1'"),
        (lambda d: d["joints"].pop(), "every body but the first"),
        (lambda d: d["joints"][0].update(parent="shank_2"), "one tree"),
        (lambda d: d["legs"][1].pop(), "legs: every leg needs the same number of bodies"),
        (lambda d: d["legs"][1].reverse(), "same roles in the same order"),
        (lambda d: d["joints"][1]["stops"].append({"side": "upper", "angle": 0.1}), "at most one stop per side"),
        (lambda d: d["joints"][1]["stops"].append({"side": "lower", "angle": 0.1}), "the lower stop's angle"),
        (lambda d: d["bodies"][0].update(mass=-1.0), "mass"),
    ],
)
def test_a_broken_description_is_one_line_naming_the_field(edit: Any, message: str) -> None:
    data = _kneed_dict()
    edit(data["walker"]["description"])
    with pytest.raises(ConfigError, match=message) as error:
        config_from_dict(data)
    assert "\n" not in str(error.value)


def test_description_goes_with_kind_description_only() -> None:
    data = _kneed_dict()
    data["walker"]["kind"] = "compass"
    with pytest.raises(ConfigError, match=r"walker\.description: given exactly when walker\.kind is 'description'"):
        config_from_dict(data)
