"""A described walker of the rigid model's form in space (config.space_form): the one builder from
walker.description to the rigid model's data, its one-line refusals, and the bundled walkers in space written as
descriptions (configs/space) giving their description3d twins' results (tests/data/space)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from biped_sim import config_from_dict, simulate
from biped_sim.config import load_config
from biped_sim.errors import ConfigError
from biped_sim.rigid.space_cycle import space_cycle_from, space_walker_model
from tests.conftest import CONFIGS, SPACE_FIXTURES, invoke, one_line_error
from tests.test_space_compliant import GAIT

BUNDLED = [
    "tinkertoy",
    "tinkertoy_compliant",
    "tinkertoy_sphere",
    "tinkertoy_sphere_compliant",
    "kuo_compass_3d",
    "kuo_compass_3d_compliant",
]
TOY = CONFIGS / "space" / "tinkertoy.yaml"
STARTED = "simulation.initial=" + repr(GAIT).replace("'", '"')


def toy() -> dict[str, Any]:
    """configs/space/tinkertoy.yaml as data."""
    return yaml.safe_load(TOY.read_text())


@pytest.mark.parametrize("name", BUNDLED)
def test_a_bundled_walker_in_space_is_its_description3d_twin_to_the_bit(name: str) -> None:
    """The description's rigid form equals description3d's walker field by field (floats compared exactly), so the
    rigid model's parts and feet are the same numbers."""
    described, twin = load_config(CONFIGS / "space" / f"{name}.yaml"), load_config(SPACE_FIXTURES / f"{name}.yaml")
    assert described.walker.kind == "description" and described.in_space
    assert described.walker.space == twin.walker.space
    assert described.walker.leg_length == twin.walker.leg_length
    ours, theirs = space_walker_model(described), space_walker_model(twin)
    for a, b in zip(ours.parts + ours.feet, theirs.parts + theirs.feet, strict=True):
        for field in a.__dataclass_fields__:
            assert np.array_equal(getattr(a, field), getattr(b, field)), field


def test_the_described_toy_finds_description3d_s_gait() -> None:
    """Newton from the gait's keys: the same fixed point and multipliers (to 1e-9 and 1e-6: the same bits)."""
    ours, theirs = (space_cycle_from(load_config(p), GAIT) for p in (TOY, SPACE_FIXTURES / "tinkertoy.yaml"))
    assert ours is not None and theirs is not None and ours.walker == "description"
    np.testing.assert_allclose(ours.section_point, theirs.section_point, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(np.sort_complex(ours.multipliers), np.sort_complex(theirs.multipliers), atol=1e-6)
    assert ours.step_period == theirs.step_period


def test_the_described_toys_compliant_run_is_description3d_s_bit_for_bit() -> None:
    """The compliant toy on spheres, started on the rigid gait from its keys: the same run, every sample."""
    overrides = [STARTED, "simulation.t_end=1.2"]
    ours, theirs = (
        simulate(load_config(p / "tinkertoy_sphere_compliant.yaml", overrides)) for p in (TOY.parent, SPACE_FIXTURES)
    )
    assert len(ours.heel_strike_times) >= 1 and np.array_equal(ours.heel_strike_times, theirs.heel_strike_times)
    assert np.array_equal(ours.run.t, theirs.run.t) and np.array_equal(ours.run.y, theirs.run.y)


def test_a_described_walker_in_space_starts_on_its_bodies_angles_when_given_them() -> None:
    """In the spatial formulation the gait's keys (or rigid_limit_cycle) start it on the rigid gait in space; its
    bodies' angle keys leave it a tree lifted into space (walkers.spatial_described)."""
    path = CONFIGS / "space" / "tinkertoy_compliant.yaml"
    assert load_config(path, [STARTED]).in_space
    legs = "simulation.initial={stance_angle: 0.1, stance_rate: -0.5, swing_angle: -0.1, swing_rate: 0.0}"
    assert not load_config(path, [legs]).in_space


def _refused(change: Any) -> str:
    data = toy()
    change(data["walker"]["description"])
    with pytest.raises(ConfigError) as error:
        config_from_dict(data)
    assert "\n" not in str(error.value)
    return str(error.value)


def _kneed(d: dict[str, Any]) -> None:
    d["leg"]["bodies"].append({"name": "shank", "mass": 0.1, "com": [0.0, -0.2]})
    d["leg"]["joints"] = [{"name": "knee", "parent": "leg", "child": "shank", "at": [0.0, -0.5]}]
    d["leg"]["feet"][0]["body"] = "shank"


def _torso(d: dict[str, Any]) -> None:
    d["bodies"] = [{"name": "torso", "mass": 1.0, "com": [0.0, 0.3]}]
    d["joints"] = [{"name": "waist", "parent": "leg_1", "child": "torso"}]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_kneed, "walker.description.legs: the rigid model in space takes two one-body legs"),
        (
            _torso,
            "walker.description.bodies.torso: the rigid model in space takes two one-body legs on a hip hinge, "
            "no body off the legs",
        ),
        (lambda d: d["hip"].update(stops=[{"side": "upper", "angle": 1.0}]), "walker.description.joints.hip.stops"),
        (
            lambda d: d["hip"].update(elements=[{"name": "k", "law": "linear_spring", "stiffness": 1.0}]),
            "walker.description.joints.hip.elements",
        ),
        (lambda d: d["hip"].update(axis=[1.0, 0.0, 0.0]), "walker.description.joints.hip.axis"),
        (lambda d: d["hip"].update(at=[0.0, -0.1]), "walker.description.joints.hip.at"),
        (
            lambda d: d.update(point_masses=[{"name": "hip", "body": "leg_1", "mass": 1.0}]),
            "walker.description.point_masses.hip: the rigid model in space takes two one-body legs on a hip hinge: a "
            "point mass only on the hinge's midpoint (at: [0, 0], lateral: -0.1812)",
        ),
        (lambda d: d["leg"]["feet"][0].update(centre=[0.0, 0.5]), "walker.description.feet.foot_1.centre"),
    ],
)
def test_what_the_rigid_model_in_space_lacks_is_one_line_naming_the_field(change: Any, message: str) -> None:
    assert _refused(change).startswith(message)


def test_legs_that_are_not_mirror_images_are_refused() -> None:
    """Two legs written by hand (no ``leg``) must be mirror images: here the second is heavier."""
    data = toy()
    d = data["walker"]["description"]
    leg, hip = d.pop("leg"), d.pop("hip")
    body, foot = leg["bodies"][0], leg["feet"][0]
    d["bodies"] = [{**body, "name": "leg_1"}, {**body, "name": "leg_2", "com_lateral": -0.6969, "mass": 2.0}]
    d["bodies"][1]["inertia_tensor"] = {**body["inertia_tensor"], "xz": -0.0071, "yz": -0.0573}
    d["feet"] = [{**foot, "name": "foot_1", "body": "leg_1"}, {**foot, "name": "foot_2", "body": "leg_2"}]
    d["joints"] = [{"name": "hip", "parent": "leg_1", "child": "leg_2", **hip}]
    d["legs"] = [["leg_1"], ["leg_2"]]
    mirrored = copy.deepcopy(data)
    mirrored["walker"]["description"]["bodies"][1]["mass"] = 1.0
    assert config_from_dict(mirrored).walker.space == load_config(TOY).walker.space  # written by hand, the same
    with pytest.raises(ConfigError, match=r"^walker\.description\.legs: .* the second the first's mirror image"):
        config_from_dict(data)


def test_the_cli_refuses_a_kneed_walker_in_rigid_space_with_exit_2(tmp_path: Path) -> None:
    data = toy()
    _kneed(data["walker"]["description"])
    path = tmp_path / "kneed_in_space.yaml"
    path.write_text(yaml.safe_dump(data))
    result = invoke("limit-cycle", str(path))
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith("error: walker.description.legs: the rigid model in space")
