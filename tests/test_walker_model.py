"""The walker model that every study can vary (issue 31): a described walker's named list items addressed by
name (or index) in ``--set``, sweeps, ``fit --param`` and ``uncertainty --param``."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import biped_sim
from biped_sim.config import LEG_KEYS, config_from_dict, derive, load_config, parse_yaml
from biped_sim.config.parameters import written_field
from biped_sim.errors import ConfigError
from biped_sim.io.references import Reference, ReferenceSpec
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.studies.fit import calibrate, fit_problems, synthetic_reference_data
from biped_sim.studies.fit.parameters import fit_parameter, numeric_value
from biped_sim.studies.uncertainty.distributions import check_distributions, parse_distribution
from biped_sim.sweep.spec import load_sweep
from biped_sim.walkers.describe import describe

from .conftest import CONFIGS, invoke, one_line_error

KNEED = CONFIGS / "kneed_walker.yaml"
THIGH = "walker.description.bodies.thigh_1.mass"


def test_set_addresses_a_described_walkers_body_by_name_or_index() -> None:
    by_name = load_config(KNEED, [f"{THIGH}=0.6"])
    by_index = load_config(KNEED, ["walker.description.bodies.0.mass=0.6"])
    assert by_name.walker.description is not None and by_name.walker.description.bodies[0].mass == 0.6
    assert by_name.hash() == by_index.hash() != load_config(KNEED).hash()
    stop = load_config(KNEED, ["walker.description.joints.knee_1.stops.0.angle=-0.1"])
    assert stop.walker.description is not None and stop.walker.description.joints[1].stops[0].angle == -0.1


@pytest.mark.parametrize(
    ("key", "message"),
    [
        ("walker.description.bodies.femur.mass", "walker.description.bodies: no item named 'femur'; the names are "
         "thigh_1, thigh_2, shank_1, shank_2"),
        ("walker.description.bodies.7.mass", "walker.description.bodies: no item 7 (the list has 4)"),
    ],
)  # fmt: skip
def test_an_unknown_item_is_one_line_naming_the_list(key: str, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        load_config(KNEED, [f"{key}=0.6"])
    assert str(caught.value) == message


def test_fit_and_uncertainty_take_a_described_walkers_field() -> None:
    config = load_config(KNEED)
    assert numeric_value(config, THIGH) == 0.5
    assert fit_parameter(config, THIGH, 0.4, 0.6).start == 0.5
    assert derive(config, {THIGH: 0.55}).walker.description.bodies[0].mass == 0.55  # type: ignore[union-attr]
    check_distributions(config, [parse_distribution(THIGH, "uniform:0.45:0.55")])
    with pytest.raises(ConfigError, match="no item named 'femur'"):
        numeric_value(config, "walker.description.bodies.femur.mass")


def test_a_sweep_varies_a_described_walkers_body(tmp_path) -> None:
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"name: thigh\nbase: {KNEED}\ngrid:\n  {THIGH}: [0.45, 0.55]\n")
    assert [run.config.walker.description.bodies[0].mass for run in load_sweep(sweep).runs] == [0.45, 0.55]  # type: ignore[union-attr]


# --- the walker schema: one member per kind, each with its own fields only --------------------------------------


@pytest.mark.parametrize(
    ("path", "overrides", "message"),
    [
        (KNEED, ["walker.leg_length=0.9"], "walker.leg_length: a described walker has no leg_length"),
        (KNEED, ["walker.foot_radius=0.1"], "walker.foot_radius: a described walker has no foot_radius"),
        (CONFIGS / "compass_goswami.yaml", ["walker.description={}"], "walker.description: only walker.kind: "
         "description has one, not the compass walker"),
        (CONFIGS / "compass_goswami.yaml", ["walker.kind=bogus"], "walker.kind: unknown name 'bogus'; expected one "
         "of 'compass'"),
        (CONFIGS / "rimless_wheel.yaml", ["walker.leg_mass=2"], "walker.leg_mass: the rimless_wheel walker has no "
         "leg_mass (another kind's field)"),
        # a described walker on point feet with Hertz contact (foot_radius 0.15 was checked instead: a traceback)
        (KNEED, ["dynamics=compliant", "contact.materials={}"], "contact.stiffness: required for point feet"),
    ],
)  # fmt: skip
def test_each_walker_kind_has_its_own_fields(path, overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        load_config(path, overrides)
    assert str(caught.value).startswith(message)


def test_a_resolved_config_carries_its_kinds_fields_only() -> None:
    assert list(load_config(KNEED).model_dump()["walker"]) == ["kind", "parameters", "description"]
    assert load_config(KNEED).walker.leg_length == 1.0  # hip to the feet, from the description
    assert "description" not in load_config(CONFIGS / "compass_goswami.yaml").model_dump()["walker"]
    assert list(load_config(CONFIGS / "simplest_walker.yaml").model_dump()["walker"]) == ["kind"]


# --- no walker-kind branch outside the registry -----------------------------------------------------------------

PACKAGE = Path(biped_sim.__file__).parent
KINDS = "compass|simplest|rimless_wheel|four_legged|description"
BRANCH = re.compile(
    rf"""(kind|name)\s*(==|!=)\s*["']({KINDS})["']|["']({KINDS})["']\s*(==|!=)|(walker\.(kind|name)|walker_kind)\s+(not\s+)?in\b"""
)


def test_no_walker_kind_branch_outside_the_registry() -> None:
    found = [
        f"{path.relative_to(PACKAGE)}:{number}: {line.strip()}"
        for path in sorted(PACKAGE.rglob("*.py"))
        if path.name != "walker_registry.py"
        for number, line in enumerate(path.read_text().splitlines(), 1)
        if BRANCH.search(line)
    ]
    assert found == []


def test_the_scan_sees_a_branch() -> None:
    assert BRANCH.search('if config.walker.kind == "simplest":') and BRANCH.search("walker.name in KINDS")
    assert not BRANCH.search('if config.formulation.kind == "minimal":')


def test_the_rimless_wheel_written_as_a_description_finds_its_rigid_limit_cycle() -> None:
    bundled = load_config(CONFIGS / "rimless_wheel.yaml", ["simulation.initial=rigid_limit_cycle"])
    description = describe(bundled).model_dump(mode="json")
    data = {"dynamics": "rigid", "gravity": bundled.gravity, "ground": {"slope": bundled.ground.slope},
            "walker": {"kind": "description", "description": description}}  # fmt: skip
    written = rigid_limit_cycle(config_from_dict(data))
    expected = rigid_limit_cycle(bundled)
    assert written.converged and expected.converged
    assert written.fixed_point == pytest.approx(expected.fixed_point, rel=1e-9, abs=1e-12)


# --- named parameters and a leg written once ---------------------------------------------------------------------

PARAMETRISED = Path(__file__).parent / "data" / "kneed_parametrised.yaml"


def test_a_mirrored_leg_with_named_parameters_is_chens_kneed_walker() -> None:
    config = load_config(PARAMETRISED)
    described = config.walker.description
    assert described == load_config(KNEED).walker.description  # the same walker, number for number
    written, bundled = rigid_limit_cycle(config), rigid_limit_cycle(load_config(KNEED))
    assert written.converged and written.fixed_point == bundled.fixed_point  # bit for bit


def test_a_parameter_sets_every_number_that_uses_it() -> None:
    config = load_config(PARAMETRISED, ["walker.parameters.thigh_length=0.6"])
    described = config.walker.description
    assert described is not None and [j.at for j in described.joints[1:]] == [(0.0, -0.6)] * 2
    assert [b.com[1] for b in described.bodies if b.name.startswith("thigh")] == [-0.65 * 0.6] * 2
    assert config.walker.leg_length == pytest.approx(1.1)
    # the config keeps what was written: its YAML reads back to the same walker, a variant re-resolves it
    assert config_from_dict(parse_yaml(config.to_yaml())).hash() == config.hash()
    assert "thigh_length" in config.to_yaml() and "-0.65 * thigh_length" in config.to_yaml()
    heavier = derive(config, {"walker.parameters.thigh_mass": 0.7}).walker.description
    assert heavier is not None and [b.mass for b in heavier.bodies if b.name.startswith("thigh")] == [0.7, 0.7]


def test_every_study_addresses_a_named_parameter(tmp_path: Path) -> None:
    config = load_config(PARAMETRISED)
    key = "walker.parameters.thigh_mass"
    assert numeric_value(config, key) == 0.5 and fit_parameter(config, key, 0.4, 0.6).start == 0.5
    check_distributions(config, [parse_distribution(key, "uniform:0.45:0.55")])
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"name: thigh\nbase: {PARAMETRISED}\ngrid:\n  {key}: [0.45, 0.55]\n")
    masses = [run.config.walker.description.bodies[1].mass for run in load_sweep(sweep).runs]  # type: ignore[union-attr]
    assert masses == [0.45, 0.55]


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["walker.parameters.thigh_mas=0.6"], "walker.parameters: no item named 'thigh_mas'; the names are "
         "thigh_mass, shank_mass, hip_mass, thigh_length, shank_length"),
        (["walker.description.leg.bodies.thigh.mass=thigh_mas"], "walker.description.leg.bodies.thigh.mass: unknown "
         "name 'thigh_mas' (the parameters: hip_mass, shank_length, shank_mass, thigh_length, thigh_mass) in "
         "'thigh_mas'"),
        (["walker.description.leg.bodies.thigh.mass=__import__('os').getcwd()"], "walker.description.leg.bodies."
         "thigh.mass: only numbers, parameter names"),
        (["walker.description.leg.bodies.thigh.mass=thigh_mass.real"], "walker.description.leg.bodies.thigh.mass: "
         "only numbers"),
        (["walker.description.leg.bodies.thigh.mass=9**9**9"], "walker.description.leg.bodies.thigh.mass: '9**9**9' "
         "has no finite value"),
        (["walker.description.leg.bodies.thigh.mass=1/(hip_mass - 0.5)"], "walker.description.leg.bodies.thigh.mass: "
         "'1/(hip_mass - 0.5)' has no finite value"),
        (["walker.description.leg.bodies.thigh.mass=-thigh_mass"], "walker.description.leg.bodies.thigh.mass: Input "
         "should be greater than or equal to 0 (in thigh_1, the leg as written)"),
        (["walker.description.legs=[[thigh_1], [thigh_2]]"], "walker.description.legs: follows from the mirrored leg"),
        (["walker.parameters.0.name=hip_mass"], "walker.parameters: 'hip_mass' is given twice"),
        (["walker.description.bodies.thigh_1.mass=0.6"], "walker.description.bodies: expected a list (of the parts "
         "off the mirrored leg); the leg's own are walker.description.leg.bodies, named without their _1 or _2"),
    ],
)  # fmt: skip
def test_a_bad_parameter_or_expression_is_one_line(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        load_config(PARAMETRISED, overrides)
    assert str(caught.value).startswith(message)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["walker.leg_length=0.9"], "walker.leg_length: a described walker has no leg_length"),
        (["walker.description.bodies.femur.mass=0.6"], "walker.description.bodies: no item named 'femur'"),
        (["dynamics=compliant", "contact.materials={}"], "contact.stiffness: required for point feet"),
    ],
)
def test_the_command_refuses_in_one_line(tmp_path: Path, overrides: list[str], message: str) -> None:
    sets = [arg for key in overrides for arg in ("--set", key)]
    result = invoke("run", str(KNEED), *sets, "--out", str(tmp_path / "run"))
    assert result.exit_code == 2 and one_line_error(result.stderr).startswith(f"error: {message}")
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["walker.description.leg.bodies.shank.mass=-1"], "walker.description.leg.bodies.shank.mass: Input should be "
         "greater than or equal to 0 (in shank_1, the leg as written)"),
        (["walker.description.leg.joints.knee.stops=[{side: up, angle: 0}]"], "walker.description.leg.joints.knee."
         "stops.0.side: unknown name 'up'"),
        (["walker.description.leg.feet.foot.radius=-0.1"], "walker.description.leg.feet.foot.radius: Input should be "
         "greater than or equal to 0 (in foot_1, the leg as written)"),
        (["walker.description.hip={stops: [{side: up, angle: 0}]}"], "walker.description.hip.stops.0.side: unknown "
         "name 'up'"),
        (["walker.description.point_masses.hip.mass=-1"], "walker.description.point_masses.hip.mass: Input should"),
    ],
)  # fmt: skip
def test_a_bad_value_of_a_mirrored_leg_names_the_field_written(
    tmp_path: Path, overrides: list[str], message: str
) -> None:
    """A part of the mirrored leg is named by its path in walker.description.leg (and the copy it is in), the hip
    joint by walker.description.hip, the description's own parts by name: never a list index of the resolved
    description (walker.description.bodies.2.mass), which the user did not write."""
    sets = [arg for key in overrides for arg in ("--set", key)]
    result = invoke("run", str(PARAMETRISED), *sets, "--out", str(tmp_path / "run"))
    assert result.exit_code == 2 and one_line_error(result.stderr).startswith(f"error: {message}")


def test_a_field_of_the_mirror_image_names_the_written_leg_and_its_copy() -> None:
    written = parse_yaml(PARAMETRISED.read_text())["walker"]["description"]
    assert written_field(written, "walker.description.feet.1.radius") == (
        "walker.description.leg.feet.foot.radius",
        " (in foot_2, the mirror image of the leg as written)",
    )
    assert written_field(written, "walker.description.joints.knee_2.stops.0") == (
        "walker.description.leg.joints.knee.stops.0",
        " (in knee_2, the mirror image of the leg as written)",
    )
    assert written_field(written, "walker.description.joints.0.axis") == ("walker.description.hip.axis", "")
    assert written_field(written, "walker.description.point_masses.0") == ("walker.description.point_masses.hip", "")
    for field in ("walker.description.legs", "walker.description.bodies.9.mass", "walker.parameters.0.value"):
        assert written_field(written, field) == (field, "")  # not a part of the description: as it is


@pytest.mark.slow
def test_fit_recovers_a_hidden_named_parameter_from_the_walkers_own_periods() -> None:
    start = load_config(PARAMETRISED, ["simulation.t_end=8"])
    hidden = {"walker.parameters.shank_mass": 0.07}
    spec = ReferenceSpec.model_validate(synthetic_reference_data(derive(start, hidden), 7, 0.0, 0, decimals=9))
    [(_, problem)] = fit_problems(start, Reference(Path("synthetic"), spec), ["walker.parameters.shank_mass=0.03:0.1"])
    result = calibrate(problem).result
    [estimate] = result.estimates
    assert result.converged and estimate.value == pytest.approx(0.07, rel=1e-4)


def test_a_mirrored_leg_goes_with_bodies_off_the_legs_and_the_hips_own_fields() -> None:
    leg = {"bodies": [{"name": "leg", "mass": "m", "inertia": "m * r**2", "com": [0.0, -0.25]}],
           "feet": [{"name": "foot", "body": "leg", "centre": [0.0, "-(l - R)"], "radius": "R"}]}  # fmt: skip
    description = {"leg": leg, "hip": {"name": "pelvis", "stops": [{"side": "upper", "angle": 1.0}]},
                   "bodies": [{"name": "torso", "mass": 2.0, "com": [0.0, 0.3]}],
                   "joints": [{"name": "waist", "parent": "leg_1", "child": "torso"}]}  # fmt: skip
    parameters = [{"name": n, "value": v} for n, v in (("m", 1.0), ("r", 0.1), ("l", 0.5), ("R", 0.15))]
    walker = {"kind": "description", "parameters": parameters, "description": description}
    config = config_from_dict({"walker": walker, "contact": {"stiffness": 1e7}})
    described = config.walker.description
    assert described is not None and [b.name for b in described.bodies] == ["leg_1", "leg_2", "torso"]  # pairs
    assert [(j.name, j.parent, j.child) for j in described.joints] == [
        ("pelvis", "leg_1", "leg_2"), ("waist", "leg_1", "torso")]  # fmt: skip
    assert described.joints[0].stops[0].angle == 1.0 and described.legs == [["leg_1"], ["leg_2"]]
    assert [f.centre for f in described.feet] == [(0.0, -0.35)] * 2
    assert described.bodies[1].inertia == pytest.approx(0.01)
    assert config.initial_keys() == (*LEG_KEYS, "torso_angle", "torso_rate") and config.walker.leg_length == 0.5


def test_a_presets_parameters_are_its_fields_under_the_same_key() -> None:
    default = CONFIGS / "round_foot_walker.yaml"
    config = load_config(default, ["walker.parameters.leg_inertia=0.004"])
    assert config.hash() == load_config(default, ["walker.leg_inertia=0.004"]).hash()
    assert "parameters" not in config.model_dump()["walker"]
    key = "walker.parameters.hip_mass"
    assert numeric_value(config, key) == 2.0 and fit_parameter(config, key, 1.5, 2.5).start == 2.0
    assert derive(config, {key: 2.5}).walker.hip_mass == 2.5  # type: ignore[union-attr]
    check_distributions(config, [parse_distribution(key, "uniform:1.8:2.2")])
    with pytest.raises(ConfigError) as caught:
        load_config(default, ["walker.parameters.thigh_mass=1"])
    assert str(caught.value) == (
        "walker.parameters: the compass walker has no parameter 'thigh_mass'; its parameters: leg_length, "
        "foot_radius, leg_mass, leg_com_from_hip, leg_inertia, leg_com_offset, foot_offset, hip_mass"
    )
