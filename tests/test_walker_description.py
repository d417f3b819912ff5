"""The walker description (walker.kind: description): a tree of bodies, joints with stops, feet and legs."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

from biped_sim.config import LEG_KEYS, STATE_KEYS, InitialState, config_from_dict, derive, load_config
from biped_sim.config.walker_registry import WALKERS, refusal
from biped_sim.errors import ConfigError
from biped_sim.studies.bifurcation import check_bifurcation
from biped_sim.studies.convergence import check_converge
from biped_sim.studies.robustness import gait_start
from biped_sim.walkers import build_model
from biped_sim.walkers.describe import describe

from .conftest import CONFIGS

KNEED = load_config(CONFIGS / "kneed_walker.yaml")


def _kneed_dict() -> dict[str, Any]:
    return copy.deepcopy(KNEED.model_dump(mode="json"))


def test_kneed_walker_names_its_state_keys_from_its_legs() -> None:
    assert KNEED.walker.description is not None
    assert KNEED.walker.description.state_keys() == tuple(
        f"{side}_{body}_{what}"
        for side in ("stance", "swing")
        for body in ("thigh", "shank")
        for what in ("angle", "rate")
    )


def test_one_body_legs_keep_the_readme_keys() -> None:
    data = _kneed_dict()
    data["walker"]["description"]["legs"] = [["thigh_1"], ["thigh_2"]]
    described = config_from_dict(data).walker.description
    assert described is not None
    assert described.state_keys()[:4] == LEG_KEYS == tuple(InitialState.model_fields)  # the README's, spelled once
    shanks = ("shank_1_angle", "shank_1_rate", "shank_2_angle", "shank_2_rate")  # now off the legs: keys of their own
    assert described.state_keys()[4:] == described.off_leg_keys() == shanks


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
        (lambda d: d["joints"][1]["stops"].append({"side": "lower", "angle": 0.1}), "must not be above the upper"),
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
    with pytest.raises(ConfigError, match=r"walker\.description: only walker\.kind: description has one"):
        config_from_dict(data)


def test_the_registry_decides_what_the_schema_refuses() -> None:
    # every (kind, dynamics, formulation) the schema accepts is one the registry declares, and no other
    for kind, caps in WALKERS.items():
        if kind in ("description", "description3d"):  # written as data: no config without it
            continue
        for dynamics in ("compliant", "rigid"):
            for formulation in ("planar", "minimal", "spatial"):
                declared = formulation in caps.formulations.get(dynamics, ())
                overrides = {"walker.kind": kind, "dynamics": dynamics, "formulation.kind": formulation}
                try:
                    config_from_dict({}, [f"{key}={value}" for key, value in overrides.items()])
                    accepted = True
                except ConfigError as error:
                    accepted = False
                    assert str(error) == ": ".join(refusal(kind, dynamics, formulation) or ("", ""))
                assert accepted == declared, (kind, dynamics, formulation)


def _folded(description: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each body's mass and its centre of mass (point masses folded in)."""
    masses, coms = [], []
    for body in description.bodies:
        points = [(body.mass, np.array(body.com))]
        points += [(p.mass, np.array(p.at)) for p in description.point_masses if p.body == body.name]
        mass = sum(m for m, _ in points)
        masses.append(mass)
        coms.append(sum(m * r for m, r in points) / mass if mass > 0 else np.zeros(2))
    return np.array(masses), np.array(coms)


@pytest.mark.parametrize(
    "overrides",
    [
        {},
        {"walker.leg_com_offset": 0.02, "walker.foot_offset": 0.01},
        {"walker.kind": "four_legged", "formulation.kind": "minimal"},
    ],
)
def test_a_bundled_kind_describes_the_walker_its_builder_builds(overrides: dict[str, Any]) -> None:
    config = derive(config_from_dict({}), overrides)
    model, description = build_model(config), describe(config)
    masses, coms = _folded(description)
    assert np.allclose(masses, model.system.body_mass, rtol=1e-14)
    assert [f.name for f in description.feet] == model.foot_names
    assert description.state_keys() == LEG_KEYS
    owner = [[b.name for b in description.bodies].index(f.body) for f in description.feet]
    centres = np.array([f.centre for f in description.feet])
    # the planar builder places a foot from its body's centre of mass, the minimal one from the hip
    expected = centres if config.formulation.kind == "minimal" else centres - coms[owner]
    assert np.allclose(expected, model.system.foot_center, atol=1e-14)
    if not description.point_masses:  # the four-legged pairs: their inertia as the builder has it
        assert np.allclose([b.inertia for b in description.bodies], model.system.body_inertia, rtol=1e-14)


def test_the_rigid_walkers_describe_their_keys() -> None:
    wheel = describe(config_from_dict({}, ["walker.kind=rimless_wheel", "dynamics=rigid"]))
    assert wheel.state_keys() == ("stance_angle", "stance_rate") and len(wheel.feet) == 8
    simplest = describe(config_from_dict({}, ["walker.kind=simplest", "dynamics=rigid"]))
    assert simplest.state_keys() == LEG_KEYS and STATE_KEYS == (
        "stance_angle",
        "swing_angle",
        "stance_rate",
        "swing_rate",
    )


def test_the_registry_decides_what_a_described_walker_takes() -> None:
    data = _kneed_dict()
    assert describe(config_from_dict(data)) == KNEED.walker.description
    with pytest.raises(ConfigError, match=r"^formulation\.kind: 'spatial' is available with dynamics: compliant only"):
        config_from_dict({**data, "dynamics": "rigid", "formulation": {"kind": "spatial"}})
    spatial = {**data, "dynamics": "compliant", "formulation": {"kind": "spatial"}, "contact": {"stiffness": 1e6}}
    assert config_from_dict(spatial).formulation.kind == "spatial"  # its joints: multibody.hinge
    data["simulation"] = {"t_end": 2.0, "pushes": [{"time": 1.0, "impulse": [1.0, 0.0]}]}
    data["ground"]["profile"] = {"kind": "steps", "steps": [{"at": 0.3, "height": -0.01}]}
    assert config_from_dict(data).walker.kind == "description"  # pushes and profiles: declared, accepted


def test_the_studies_guards_read_the_registry() -> None:
    four_legged = derive(config_from_dict({}), {"walker.kind": "four_legged", "formulation.kind": "minimal"})
    with pytest.raises(ConfigError, match=r"^walker\.kind: bifurcation .* \(the four_legged walker does not"):
        check_bifurcation(four_legged, 0.01, 0.02, 3)
    with pytest.raises(ConfigError, match=r"^walker\.kind: robustness pushes a planar walker .*\(the four_legged"):
        gait_start(four_legged)
    check_converge(load_config(CONFIGS / "kneed_walker_compliant.yaml"), 3, 0.6, 0.8)  # the compliant one converges
