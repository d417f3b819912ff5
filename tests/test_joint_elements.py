"""Passive joint elements (contact/joint_element.py): the laws, their registry, and the schema that names them."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numba
import numpy as np
import pytest

from biped_sim.config import config_from_dict, load_config
from biped_sim.contact.joint_element import (
    JOINT_ELEMENT_LAWS,
    JointElements,
    NoElements,
    element_energy,
    element_parameters,
    element_torque,
    element_torques,
    elements_energy,
    make_elements,
)
from biped_sim.errors import ConfigError
from biped_sim.multibody.minimal import tree_system
from biped_sim.simulate import simulate
from biped_sim.walkers import build_model

from .conftest import CONFIGS
from .test_described import formulations_agree

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


def test_a_walker_without_joint_elements_has_an_elements_record_of_its_own_type() -> None:
    """No elements is a type (NoElements), on which numba specialises: such a walker compiles none of the elements'
    code and their kernels are no-ops; a walker with elements has a JointElements record, in both formulations."""
    plain = build_model(config_from_dict({})).system
    torso = build_model(load_config(CONFIGS / "torso_walker.yaml")).system
    assert type(plain.elements) is NoElements and plain.elements.law.shape == (0,)
    assert type(torso.elements) is JointElements and numba.typeof(torso.elements) != numba.typeof(plain.elements)
    assert type(tree_system(plain).elements) is NoElements and type(tree_system(torso).elements) is JointElements
    y, force = np.ones(6), np.ones(3)
    assert element_torques(y, plain.elements, force) == 0.0 and elements_energy(y, plain.elements) == 0.0
    assert force.tolist() == [1.0] * 3


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


def held_in_the_world(data: dict[str, Any], stiffness: float, damping: float, rest_angle: float = 0.0) -> None:
    """Replace the waist's elements of the torso walker ``data`` by a spring and a damper against the ground."""
    joint = next(j for j in data["walker"]["description"]["joints"] if j["name"] == "waist")
    spring = {"name": "spring", "law": "linear_spring", "stiffness": stiffness, "rest_angle": rest_angle}
    damper = {"name": "damper", "law": "linear_damper", "damping": damping}
    joint["elements"] = [{**spring, "against": "ground"}, {**damper, "against": "ground"}]


def test_an_element_against_the_ground_holds_its_child_s_absolute_angle() -> None:
    """``against: ground``: theta is the torso's angle from the slope normal, the torque acts on the torso alone (its
    reaction goes to the ground), and the tree formulation agrees with the absolute coordinates'."""
    data = _torso_dict()
    held_in_the_world(data, 30.0, 0.5, rest_angle=0.1)
    config = config_from_dict(data)
    assert config.walker.description is not None
    assert [other for *_, other in config.walker.description.joint_elements()] == ["ground", "ground"]
    model = build_model(config)
    planar, torso = model.system, model.body_names.index("torso")
    y = model.y0.copy()
    nb = len(model.body_names)
    y[3 * torso + 2], y[3 * nb + 3 * torso + 2] = 0.3, -0.4
    force = np.zeros(3 * nb)
    assert element_torques(y, planar.elements, force) == pytest.approx(0.5 * 0.4**2)
    expected = np.zeros(3 * nb)
    expected[3 * torso + 2] = -30.0 * (0.3 - 0.1) + 0.5 * 0.4
    np.testing.assert_allclose(force, expected, rtol=1e-15)
    assert elements_energy(y, planar.elements) == pytest.approx(0.5 * 30.0 * 0.2**2)
    assert all(full[-1] > 0.0 for full in formulations_agree(planar, count=10, seed=7))  # W_element's rate


def test_a_body_named_ground_is_refused_in_one_line() -> None:
    data = _torso_dict()
    described = data["walker"]["description"]
    described["bodies"][0]["name"] = "ground"
    next(j for j in described["joints"] if j["name"] == "waist")["child"] = "ground"
    with pytest.raises(ConfigError, match="bodies: 'ground' names the ground") as error:
        config_from_dict(data)
    assert "\n" not in str(error.value)


def test_a_walker_without_elements_has_none() -> None:
    described = load_config(CONFIGS / "kneed_walker.yaml").walker.description
    assert described is not None and described.joint_elements() == []


# --- compliant dynamics ---------------------------------------------------------------------------------------------


def test_the_tree_formulation_agrees_with_absolute_coordinates_with_joint_elements() -> None:
    """On random states, the torso walker's accelerations, the elements' work rate and the energies agree in both
    formulations (the elements' indices moved to the minimal state's angles)."""
    planar = build_model(load_config(TORSO)).system
    minimal = tree_system(planar)
    assert not minimal.star and minimal.elements.law.shape[0] == 4
    assert all(full[-1] > 0.0 for full in formulations_agree(planar, count=20, seed=5))  # W_element's rate


@pytest.mark.parametrize("formulation", ["planar", "minimal"])
def test_the_elements_close_the_energy_balance(formulation: str) -> None:
    """The springs' energy (in the elastic term) and the dampers' work W_element close the audit to the tolerance
    of the compass's audit (tests/test_conservation.py); without W_element it would stay open."""
    tight = ["integrator.rtol=1e-9", "integrator.atol=1e-11", "simulation.t_end=1.0"]
    result = simulate(load_config(TORSO, [f"formulation.kind={formulation}", *tight]))
    audit = result.energy
    m_g_l = result.model.total_mass * 9.81 * result.model.leg_length
    dissipated = audit.dissipated_elements - audit.dissipated_elements[0]
    assert dissipated[-1] > 1e-3 * m_g_l and np.max(audit.elastic) > 1e-2 * m_g_l  # the elements took part
    assert np.max(np.abs(audit.residual)) < 1e-5 * m_g_l
    assert np.max(np.abs(audit.residual - dissipated)) > 1e3 * np.max(np.abs(audit.residual))
    assert result.summary["energy_dissipated"]["elements"] == pytest.approx(float(dissipated[-1]))
    assert result.model.state_names()[-3:] == ["W_normal", "W_friction", "W_element"]  # no stops: W_element last
    channels = {channel.path: channel.data for channel in result.trajectory().channels}
    assert np.array_equal(channels["energy/dissipated_elements"], audit.dissipated_elements)
