"""Passive joint elements (contact/joint_element.py): the laws, their registry, and the schema that names them."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from biped_sim.config import config_from_dict, load_config
from biped_sim.contact.joint_element import (
    JOINT_ELEMENT_LAWS,
    element_energy,
    element_parameters,
    element_torque,
    element_torques,
    elements_energy,
    make_elements,
)
from biped_sim.errors import ConfigError

from .conftest import CONFIGS

TORSO = Path(__file__).parent / "data" / "torso_compass.yaml"
SPRING = element_parameters("linear_spring", stiffness=12.0, rest_angle=0.3)
DAMPER = element_parameters("linear_damper", damping=0.7)


@pytest.mark.parametrize("theta", [-0.4, 0.0, 0.3, 1.1])
def test_a_spring_s_torque_is_minus_the_gradient_of_its_energy(theta: float) -> None:
    law = JOINT_ELEMENT_LAWS["linear_spring"].index
    h = 1e-6
    gradient = (element_energy(law, theta + h, SPRING) - element_energy(law, theta - h, SPRING)) / (2 * h)
    tau, power = element_torque(law, theta, 5.0, SPRING)
    assert tau == pytest.approx(-gradient, rel=1e-7, abs=1e-9) and tau == -12.0 * (theta - 0.3)
    assert power == 0.0  # conservative
    assert element_energy(law, theta, SPRING) == pytest.approx(0.5 * 12.0 * (theta - 0.3) ** 2)


def test_a_damper_dissipates_what_its_torque_takes() -> None:
    law = JOINT_ELEMENT_LAWS["linear_damper"].index
    tau, power = element_torque(law, 0.2, -3.0, DAMPER)
    assert tau == pytest.approx(2.1) and power == pytest.approx(-tau * -3.0) == pytest.approx(0.7 * 9.0)
    assert element_energy(law, 0.2, DAMPER) == 0.0


def test_elements_act_equal_and_opposite_on_their_two_bodies() -> None:
    # y: angles 0..2, rates 3..5; a spring between bodies 1 (child) and 0, a damper between 2 and 0
    y = np.array([0.1, 0.5, -0.2, 1.0, -2.0, 0.5])
    laws = [JOINT_ELEMENT_LAWS[name].index for name in ("linear_spring", "linear_damper")]
    elements = make_elements(np.array([[1, 0, 4, 3], [2, 0, 5, 3]]), np.array(laws), np.array([SPRING, DAMPER]))
    force = np.zeros(6)
    power = element_torques(y, elements, force)
    spring, damper = -12.0 * (0.4 - 0.3), -0.7 * (0.5 - 1.0)
    assert force[:3] == pytest.approx([-spring - damper, spring, damper]) and force[:3].sum() == pytest.approx(0.0)
    assert power == pytest.approx(0.7 * 0.25)
    assert elements_energy(y, elements) == pytest.approx(0.5 * 12.0 * 0.1**2)


def test_a_parameter_the_law_does_not_read_is_refused() -> None:
    with pytest.raises(ValueError, match="damping: a linear_spring reads only stiffness, rest_angle"):
        element_parameters("linear_spring", stiffness=1.0, damping=0.1)


# --- the schema ----------------------------------------------------------------------------------------------------


def _torso_dict() -> dict[str, Any]:
    return copy.deepcopy(load_config(TORSO).model_dump(mode="json"))


def test_elements_are_written_with_named_parameters_and_reached_by_dotted_keys() -> None:
    config = load_config(TORSO)
    described = config.walker.description
    assert described is not None
    elements = [(j.name, e.name, e.law, other) for j, e, other in described.joint_elements()]
    assert elements == [
        ("waist", "spring_1", "linear_spring", "leg_1"),
        ("waist", "spring_2", "linear_spring", "leg_2"),
        ("waist", "damper_1", "linear_damper", "leg_1"),
        ("waist", "damper_2", "linear_damper", "leg_2"),
    ]
    stiffer = load_config(TORSO, ["walker.parameters.torso_stiffness=40"]).walker.description
    assert stiffer is not None and [e.stiffness for _, e, _ in stiffer.joint_elements()][:2] == [40.0, 40.0]
    one = load_config(TORSO, ["walker.description.joints.waist.elements.spring_2.rest_angle=0.1"]).walker.description
    assert one is not None and [e.rest_angle for _, e, _ in one.joint_elements()][:2] == [None, 0.1]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda e: e[0].pop("stiffness"), "stiffness: a linear_spring needs it"),
        (lambda e: e[2].update(stiffness=1.0), "stiffness: a linear_damper reads only damping"),
        (lambda e: e[0].update(law="cubic_spring"), "law"),
        (lambda e: e[0].update(stiffness=-1.0), "stiffness"),
        (lambda e: e[1].update(name="spring_1"), "elements: names must be unique on a joint"),
        (lambda e: e[1].update(against="tail"), "joints: unknown body 'tail'"),
        (lambda e: e[1].update(against="torso"), "element 'spring_2' of joint 'waist' acts against its own body"),
    ],
)
def test_a_broken_element_is_one_line_naming_the_field(edit: Any, message: str) -> None:
    data = _torso_dict()
    joint = next(j for j in data["walker"]["description"]["joints"] if j["name"] == "waist")
    edit(joint["elements"])
    with pytest.raises(ConfigError, match=message) as error:
        config_from_dict(data)
    assert "\n" not in str(error.value)


def test_a_walker_without_elements_has_none() -> None:
    described = load_config(CONFIGS / "kneed_walker.yaml").walker.description
    assert described is not None and described.joint_elements() == []
