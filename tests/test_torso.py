"""A body off the legs (a torso on the hip): its initial-state keys, and falls named by what fell."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from biped_sim.config import LEG_KEYS, config_from_dict, load_config
from biped_sim.contact.response import BODY_TOO_FAR, HIP_TOO_LOW, LEG_TOO_FAR, STANDING
from biped_sim.errors import ConfigError
from biped_sim.multibody.dispatch import formulation_of, system_fall
from biped_sim.multibody.minimal import tree_system
from biped_sim.multibody.tree import tree_state
from biped_sim.simulate import simulate
from biped_sim.walkers import build_model

TORSO = Path(__file__).parent / "data" / "torso_compass.yaml"
TORSO_KEYS = ("torso_angle", "torso_rate")


def _torso_dict() -> dict[str, Any]:
    return copy.deepcopy(load_config(TORSO).model_dump(mode="json"))


def test_a_body_off_the_legs_has_its_own_initial_state_keys() -> None:
    described = load_config(TORSO).walker.description
    assert described is not None and described.off_leg_bodies() == ["torso"]
    assert described.state_keys() == (*LEG_KEYS, *TORSO_KEYS)


@pytest.mark.parametrize("formulation", ["planar", "minimal"])
def test_the_torso_starts_where_its_keys_say(formulation: str) -> None:
    overrides = [f"formulation.kind={formulation}"]
    model = build_model(load_config(TORSO, [*overrides, "simulation.initial.torso_angle=-0.2",
                                            "simulation.initial.torso_rate=0.7"]))  # fmt: skip
    layout, torso = formulation_of(model.system).layout_of(model.system), model.body_names.index("torso")
    assert model.y0[layout.coordinate(torso, "phi")] == -0.2 and model.y0[layout.rate(torso, "omega")] == 0.7
    upright = build_model(load_config(TORSO, overrides))  # not given: upright and at rest
    assert upright.y0[layout.coordinate(torso, "phi")] == 0.0 and upright.y0[layout.rate(torso, "omega")] == 0.0


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["simulation.initial.torso_angel=0.1"], "simulation.initial: expected the keys stance_angle, stance_rate, "
         "swing_angle, swing_rate, torso_angle, torso_rate (optional: torso_angle, torso_rate; not given: 0)"),
        (["simulation.initial.torso_angle=true"], "simulation.initial"),
        (["simulation.initial.torso_angle=1.5"],
         "simulation.initial.torso_angle: beyond the fall_angle of the body 'torso'"),
        (["walker.description.bodies.torso.fall_angle=0.4", "simulation.initial.torso_angle=0.5"],
         "simulation.initial.torso_angle: beyond the fall_angle of the body 'torso'"),
    ],
)  # fmt: skip
def test_a_wrong_torso_state_is_one_line(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError) as error:
        build_model(load_config(TORSO, overrides))
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["leg"]["bodies"][0].update(fall_angle=0.5), "walker.description.leg.bodies.leg.fall_angle: only a "
         "body off the legs (a torso) has its own; the legs' bodies fall past simulation.fall_leg_angle"),
        (lambda d: (d["bodies"][0].update(name="stance"), d["joints"][0].update(child="stance")),
         "the state key 'stance_angle' of a body off the legs is a leg's too; rename the body"),
        (lambda d: d["bodies"][0].update(fall_angle=0.0), "fall_angle"),
    ],
)  # fmt: skip
def test_a_wrong_fall_angle_or_body_name_is_one_line(edit: Any, message: str) -> None:
    data = _torso_dict()
    edit(data["walker"]["description"])
    with pytest.raises(ConfigError) as error:
        config_from_dict(data)
    assert message in str(error.value) and "\n" not in str(error.value)


def test_the_fall_kernels_name_what_fell_in_both_formulations() -> None:
    """The hip too low, a leg past simulation.fall_leg_angle and the torso past its own fall_angle are three
    codes; the torso's is past its limit only (it may lean further than the legs may swing, or less)."""
    planar = build_model(load_config(TORSO, ["walker.description.bodies.torso.fall_angle=0.6"])).system
    y0 = build_model(load_config(TORSO)).y0
    layout = formulation_of(planar).layout_of(planar)
    names = build_model(load_config(TORSO)).body_names
    torso, leg = names.index("torso"), names.index("leg_2")

    def code(edit: dict[int, float], lift: float = 0.0) -> tuple[int, int]:
        y = y0.copy()
        for body, angle in edit.items():
            y[layout.coordinate(body, "phi")] = angle
        for b in range(len(names)):
            y[layout.coordinate(b, "y")] += lift
        return system_fall(y, planar), system_fall(tree_state(y, planar), tree_system(planar))

    assert code({}) == (STANDING, STANDING)
    assert code({torso: 0.59}) == (STANDING, STANDING)
    assert code({torso: -0.61}) == (BODY_TOO_FAR + torso,) * 2
    assert code({leg: 1.41}) == (LEG_TOO_FAR,) * 2
    assert code({}, lift=-0.3) == (HIP_TOO_LOW,) * 2


def test_a_torso_without_its_springs_falls_and_the_run_says_so() -> None:
    config = load_config(TORSO, ["walker.parameters.torso_stiffness=0", "walker.parameters.torso_damping=0",
                                 "walker.description.bodies.torso.fall_angle=0.8", "simulation.t_end=3"])  # fmt: skip
    result = simulate(config)
    assert result.status == "fell"
    assert result.status_reason == "the body 'torso' (off the legs) past its fall_angle from the slope normal"
    assert result.summary["status_reason"] == result.status_reason
    torso = np.abs(result.run.y[:, formulation_of(result.model.system).layout_of(result.model.system).coordinate(
        result.model.body_names.index("torso"), "phi")])  # fmt: skip
    assert np.max(torso) <= 0.8 + 1e-2 and np.max(torso) > 0.7  # stopped at the limit
