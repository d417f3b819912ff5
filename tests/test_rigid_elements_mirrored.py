"""Rigid dynamics and the joint elements: the legs swap coordinates at each heel strike while every element stays
on its coordinates, so a walker is taken only if that swap maps its elements onto themselves
(:func:`biped_sim.rigid.tree_build.check_elements_mirrored`); any other is refused with one line naming the element."""

from __future__ import annotations

import copy
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from biped_sim.config import config_from_dict, load_config
from biped_sim.contact.joint_element import JOINT_ELEMENT_LAWS, element_parameters
from biped_sim.errors import ConfigError
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.tree_build import check_elements_mirrored

from .conftest import CONFIGS, invoke, one_line_error
from .test_joint_elements import held_in_the_world

TORSO_WALKER = CONFIGS / "torso_walker.yaml"
SWAP = [1, 0, 2]  # the relabelling of two one-body legs and a torso: the legs swap, the torso keeps its coordinate
LEG_1, LEG_2, TORSO, GROUND = 0, 1, 2, -1


def _element(law: str, child: int, other: int, **values: float) -> list[float]:
    return [JOINT_ELEMENT_LAWS[law].index, child, other, *element_parameters(law, **values)]


def _check(*elements: list[float]) -> None:
    """check_elements_mirrored on ``elements``, named e_0, e_1, ... of one joint ``j``."""
    named = [(SimpleNamespace(name="j"), SimpleNamespace(name=f"e_{k}", law=law), None)
             for k, law in enumerate(_law_names(elements))]  # fmt: skip
    check_elements_mirrored(SimpleNamespace(joint_elements=lambda: named), list(elements), SWAP)  # type: ignore[arg-type]


def _law_names(elements: tuple[list[float], ...]) -> list[str]:
    by_index = {law.index: name for name, law in JOINT_ELEMENT_LAWS.items()}
    return [by_index[int(e[0])] for e in elements]


def test_elements_the_swap_maps_onto_themselves_are_taken() -> None:
    _check(_element("linear_spring", LEG_2, LEG_1, stiffness=3.0))  # a hip spring at rest angle 0: the same turned
    _check(_element("linear_damper", LEG_2, LEG_1, damping=0.2))  # a hip damper, any
    _check(_element("linear_spring", TORSO, GROUND, stiffness=3.0, rest_angle=0.1))  # on the torso, kept by the swap
    _check(  # a hip spring with a rest angle and its mirror image
        _element("linear_spring", LEG_2, LEG_1, stiffness=3.0, rest_angle=0.2),
        _element("linear_spring", LEG_1, LEG_2, stiffness=3.0, rest_angle=0.2),
    )
    _check(  # a leg held against the ground, and the other leg alike
        _element("linear_spring", LEG_1, GROUND, stiffness=3.0, rest_angle=0.1),
        _element("linear_spring", LEG_2, GROUND, stiffness=3.0, rest_angle=0.1),
    )


UNLIKE = [
    _element("linear_spring", TORSO, LEG_1, stiffness=2.0),
    _element("linear_spring", TORSO, LEG_2, stiffness=2.5),
]


@pytest.mark.parametrize(
    "elements",
    [
        [_element("linear_spring", LEG_2, LEG_1, stiffness=3.0, rest_angle=0.2)],  # a hip spring with a rest angle
        [_element("linear_spring", LEG_1, GROUND, stiffness=3.0)],  # one leg held against the ground
        [_element("linear_damper", TORSO, LEG_1, damping=0.1)],  # the torso to one leg only
        UNLIKE,  # the torso to both legs, unlike
    ],
)
def test_an_element_the_swap_would_move_is_refused_by_name(elements: list[list[float]]) -> None:
    with pytest.raises(ConfigError, match=r"j\.e_0: rigid dynamics swaps the legs' coordinates"):
        _check(*elements)


def _torso_walker(overrides: list[str]) -> dict[str, Any]:
    return copy.deepcopy(load_config(TORSO_WALKER, ["dynamics=rigid", *overrides]).model_dump(mode="json"))


def test_the_bundled_torso_walkers_are_taken_unchanged() -> None:
    """Springs and dampers to both legs alike, or the torso held against the ground: the swap keeps them."""
    bundled = rigid_walker(config_from_dict(_torso_walker([])))
    data = _torso_walker([])
    held_in_the_world(data, 30.0, 0.5, rest_angle=0.1)
    held = rigid_walker(config_from_dict(data))
    assert bundled.n_q == held.n_q == 3
    for walker in (bundled, held):
        assert len(walker.params.elements) > 0 and np.all(np.isfinite(walker.params.element_params))


def test_a_rigid_run_of_a_torso_spring_with_a_rest_angle_on_one_side_is_one_line_exit_2(tmp_path: Path) -> None:
    """The compliant run keeps such an element on its leg; the rigid one would move it at every strike: refused."""
    out = tmp_path / "run"
    result = invoke("run", str(TORSO_WALKER), "--set", "dynamics=rigid", "--set",
                    "walker.description.joints.waist.elements.spring_2.rest_angle=0.1", "--out", str(out))  # fmt: skip
    assert result.exit_code == 2
    assert "waist.spring_1: rigid dynamics swaps the legs' coordinates" in one_line_error(result.stderr)
    assert not out.exists()
