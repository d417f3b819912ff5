"""Configuration schema: defaults, overrides, YAML quirks and one-line errors naming the field."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from biped_sim.config import config_from_dict, load_config, parse_yaml
from biped_sim.errors import ConfigError

from .conftest import CONFIGS, DEFAULT_CONFIG

# Each bundled config file: (dynamics, walker kind, formulation) it declares.
BUNDLED = {
    "compass_goswami": ("compliant", "compass", "planar"),
    "four_legged_walker": ("compliant", "four_legged", "spatial"),
    "kneed_walker": ("rigid", "description", "planar"),
    "kneed_walker_compliant": ("compliant", "description", "planar"),
    "rimless_wheel": ("rigid", "rimless_wheel", "planar"),
    "round_foot_walker": ("compliant", "compass", "planar"),
    "simplest_walker": ("rigid", "simplest", "planar"),
    "torso_walker": ("compliant", "description", "planar"),
}


def test_every_bundled_config_loads_as_the_model_it_names() -> None:
    paths = sorted(CONFIGS.glob("*.yaml"))
    assert [path.stem for path in paths] == sorted(BUNDLED)  # a new or renamed config is listed here too
    for path in paths:
        config = load_config(path)
        assert (config.dynamics, config.walker.kind, config.formulation.kind) == BUNDLED[path.stem], path.name


def test_schema_defaults_are_the_default_walker() -> None:
    # the bundled file spells out the default materials; otherwise it is the schema's defaults
    assert config_from_dict({}, ["contact.materials={}"]).hash() == load_config(DEFAULT_CONFIG).hash()


def test_yaml_reads_exponent_floats_and_keeps_on_a_string() -> None:
    data = parse_yaml("a: 1e7\nb: 2.5e-3\nc: on\nd: true\n")
    assert data == {"a": 1e7, "b": 2.5e-3, "c": "on", "d": True}


def test_set_override_parses_value_as_yaml() -> None:
    config = load_config(
        DEFAULT_CONFIG, ["ground.slope=0.03", "contact.model=hertz", "contact.materials=null", "contact.stiffness=2e7"]
    )
    assert config.ground.slope == 0.03
    assert config.contact.model == "hertz"


def test_hash_ignores_output_dir_but_not_physics() -> None:
    base = config_from_dict({})
    assert config_from_dict({"output": {"dir": "/tmp/elsewhere"}}).hash() == base.hash()
    assert config_from_dict({}, ["ground.slope=0.021"]).hash() != base.hash()


@pytest.mark.parametrize(
    ("overrides", "field", "reason"),
    [
        (["walker.leg_masss=1"], "walker.leg_masss", "unknown key"),
        (["contact.model=flores2"], "contact.model", "unknown name 'flores2'"),
        (["friction.model=stribeck"], "friction.model", "unknown name"),
        (["walker.leg_mass=-1"], "walker.leg_mass", "greater than 0"),
        (["walker.foot_radius=-0.1"], "walker.foot_radius", "greater than or equal to 0"),
        (["walker.foot_radius=0.6"], "walker.foot_radius", "smaller than walker.leg_length"),
        (["integrator.dt=0"], "integrator.dt", "greater than 0"),
        (["integrator.dt=-1e-3"], "integrator.dt", "greater than 0"),
        (["ground.slope=0.9"], "ground.slope", "friction cone"),
        (["walker.foot_radius=0", "contact.materials={}"], "contact.stiffness", "point feet"),
        (["contact.stiffness=1e6", "contact.materials={}"], "contact.stiffness", "not both"),
    ],
)
def test_bad_values_name_field_and_reason(overrides: list[str], field: str, reason: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(DEFAULT_CONFIG, overrides)
    assert info.value.field == field
    assert reason in info.value.reason
    assert "\n" not in str(info.value)


def test_missing_file_and_malformed_yaml(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no such config file"):
        load_config(tmp_path / "absent.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("walker:\n  leg_length: [0.5\n")
    with pytest.raises(ConfigError, match=r"malformed YAML \(line"):
        load_config(bad)


@settings(max_examples=40, deadline=None)
@given(
    field=st.sampled_from(["walker.leg_mass", "walker.leg_length", "gravity", "integrator.dt", "integrator.rtol"]),
    value=st.floats(max_value=0.0, allow_nan=False),
)
def test_non_positive_physical_quantities_are_rejected(field: str, value: float) -> None:
    with pytest.raises(ConfigError) as info:
        config_from_dict({}, [f"{field}={value!r}"])
    assert info.value.field == field


def test_derive_sets_dotted_keys_and_validates_the_variant() -> None:
    from biped_sim.config import derive

    base = load_config(DEFAULT_CONFIG)
    variant = derive(base, {"ground.slope": 0.0125, "contact.model": "hunt_crossley"})
    assert (variant.ground.slope, variant.contact.model) == (0.0125, "hunt_crossley")
    assert variant.walker == base.walker and base.ground.slope != 0.0125  # the base is untouched
    with pytest.raises(ConfigError, match=r"walker\.leg_length"):
        derive(base, {"walker.leg_length": -1.0})
