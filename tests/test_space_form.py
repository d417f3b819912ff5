"""A described walker of the rigid model's form in space (config.space_form): the one builder from
walker.description to the rigid model's data, its one-line refusals, and the bundled walkers in space
(configs/space) giving the published walkers' numbers exactly (those walker.kind: description3d held; the runs
were compared bit for bit while it existed, at febce45)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from biped_sim import config_from_dict
from biped_sim.config import load_config
from biped_sim.config.space_description import InertiaSpec, SpaceDescription, SpaceFoot, SpaceLeg
from biped_sim.errors import ConfigError
from biped_sim.rigid.space_cycle import space_cycle_from
from tests.conftest import CONFIGS, invoke, one_line_error
from tests.test_space_compliant import GAIT, RIGID_PERIOD

TOY = CONFIGS / "space" / "tinkertoy.yaml"
STARTED = "simulation.initial=" + repr(GAIT).replace("'", '"')
# Coleman et al.'s leg (x forward, y along the hinge away from the other leg, z up) and the Kuo-type compass's
TOY_LEG = {"mass": 1.0, "com": (0.0, 0.6969, -0.6863), "inertia": InertiaSpec(
    xx=0.1982, yy=0.0186, zz=0.1802, xy=0.0071, xz=-0.0023, yz=0.0573)}  # fmt: skip
KUO_LEG = {"mass": 5.0, "com": (0.0, 0.0, -0.5), "inertia": InertiaSpec(xx=0.1, yy=0.0, zz=0.1)}
RING = SpaceFoot(shape="ring", radius=0.1236, centre=(0.0, 0.0, -0.8764))
SPHERE = SpaceFoot(shape="sphere", radius=0.1236, centre=(0.0, 0.0, -0.8764))
PUBLISHED = {
    "tinkertoy": SpaceDescription(hip_width=0.3624, leg=SpaceLeg(**TOY_LEG, foot=RING)),
    "tinkertoy_compliant": SpaceDescription(hip_width=0.3624, leg=SpaceLeg(**TOY_LEG, foot=RING)),
    "tinkertoy_sphere": SpaceDescription(hip_width=0.3624, leg=SpaceLeg(**TOY_LEG, foot=SPHERE)),
    "tinkertoy_sphere_compliant": SpaceDescription(hip_width=0.3624, leg=SpaceLeg(**TOY_LEG, foot=SPHERE)),
    "kuo_compass_3d": SpaceDescription(hip_width=0.1, hip_mass=10.0, leg=SpaceLeg(
        **KUO_LEG, foot=SpaceFoot(shape="sphere", radius=0.001, centre=(0.0, 0.0, -0.999)))),
    "kuo_compass_3d_compliant": SpaceDescription(hip_width=0.1, hip_mass=10.0, leg=SpaceLeg(
        **KUO_LEG, foot=SpaceFoot(shape="sphere", radius=0.3, centre=(0.0, 0.0, -0.7)))),
}  # fmt: skip


def toy() -> dict[str, Any]:
    """configs/space/tinkertoy.yaml as data."""
    return yaml.safe_load(TOY.read_text())


@pytest.mark.parametrize("name", list(PUBLISHED))
def test_a_bundled_walker_in_space_is_the_published_walker_to_the_bit(name: str) -> None:
    """The description's rigid form equals the published numbers field by field (floats compared exactly, the
    signs of the zeros too: the rigid model's arrays are the same bits)."""
    described = load_config(CONFIGS / "space" / f"{name}.yaml")
    assert described.walker.kind == "description" and described.in_space
    assert repr(described.walker.space) == repr(PUBLISHED[name])
    assert described.walker.leg_length == described.walker.space.leg_length()


def test_the_described_toy_has_its_published_gait() -> None:
    """Newton from the gait's 8-digit keys: the fixed point and period to 1e-8 (the README's digits)."""
    cycle = space_cycle_from(load_config(TOY), GAIT)
    assert cycle is not None and cycle.walker == "description"
    assert cycle.fixed_point == pytest.approx(GAIT, abs=1e-8)
    assert cycle.step_period == pytest.approx(RIGID_PERIOD, abs=1e-8)


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


def _torso_and_head(d: dict[str, Any]) -> None:
    d["bodies"] = [{"name": "torso", "mass": 1.0, "com": [0.0, 0.3]}, {"name": "head", "mass": 0.5, "com": [0.0, 0.1]}]
    d["joints"] = [
        {"name": "waist", "parent": "leg_1", "child": "torso"},
        {"name": "neck", "parent": "torso", "child": "head", "at": [0.0, 0.5]},
    ]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            _kneed,
            "walker.description.leg.joints.knee.stops: the rigid model in space takes two legs on a hip hinge: a "
            "knee with one stop, at the straight knee (angle 0)",
        ),
        (
            _torso_and_head,
            "walker.description.bodies.torso: the rigid model in space takes two legs on a hip hinge, one body off "
            "the legs: a torso",
        ),
        (lambda d: d["hip"].update(stops=[{"side": "upper", "angle": 1.0}]), "walker.description.hip.stops"),
        (
            lambda d: d["hip"].update(elements=[{"name": "k", "law": "linear_spring", "stiffness": 1.0}]),
            "walker.description.hip.elements",
        ),
        (lambda d: d["hip"].update(axis=[1.0, 0.0, 0.0]), "walker.description.hip.axis"),
        (lambda d: d["hip"].update(at=[0.0, -0.1]), "walker.description.hip.at"),
        (lambda d: d["leg"]["feet"][0].update(centre=[0.0, 0.5]), "walker.description.leg.feet.foot.centre"),
    ],
)
def test_what_the_rigid_model_in_space_lacks_is_one_line_naming_the_field(change: Any, message: str) -> None:
    assert _refused(change).startswith(message)


def test_a_kneed_walker_in_space_made_rigid_is_refused_for_its_start_not_its_legs() -> None:
    """The bundled 3D kneed walker with ``dynamics: rigid``: the rigid model takes its legs (thigh and shank on a
    latching knee), not its start (the compliant run's body angles), which is named with the keys it takes."""
    data = yaml.safe_load((CONFIGS / "space" / "kneed_walker_3d.yaml").read_text())
    data["dynamics"] = "rigid"
    del data["formulation"]
    with pytest.raises(ConfigError) as error:
        config_from_dict(data)
    assert str(error.value).startswith("simulation.initial: expected the keys heading, bank, pitch")


def test_a_point_mass_on_a_leg_off_the_hinge_is_lumped_into_its_body() -> None:
    """A point mass on the leg's hip point (off the hinge's midpoint, the legs 0.3624 apart; written once, on both
    legs): the leg's mass, centre of mass and inertia by parallel axes, the hip mass unchanged."""
    bare, data = load_config(TOY).walker.space, toy()
    data["walker"]["description"]["leg"]["point_masses"] = [{"name": "m", "body": "leg", "mass": 1.0}]
    lumped = config_from_dict(data).walker.space
    assert lumped.hip_mass == bare.hip_mass and lumped.leg.mass == pytest.approx(bare.leg.mass + 1.0)
    np.testing.assert_allclose(lumped.leg.com, np.array(bare.leg.com) * bare.leg.mass / lumped.leg.mass)
    offset = np.array(bare.leg.com) - np.array(lumped.leg.com)
    shift = lambda r, m: m * (r @ r * np.eye(3) - np.outer(r, r))  # noqa: E731
    expected = bare.leg.inertia.matrix() + shift(offset, bare.leg.mass) + shift(np.array(lumped.leg.com), 1.0)
    np.testing.assert_allclose(lumped.leg.inertia.matrix(), expected, atol=1e-15)


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


def test_the_cli_refuses_a_knee_without_its_stop_in_rigid_space_with_exit_2(tmp_path: Path) -> None:
    data = toy()
    _kneed(data["walker"]["description"])
    path = tmp_path / "kneed_in_space.yaml"
    path.write_text(yaml.safe_dump(data))
    result = invoke("limit-cycle", str(path))
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith("error: walker.description.leg.joints.knee.stops: the rigid model")
