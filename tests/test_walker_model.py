"""The walker model that every study can vary (issue 31): a described walker's named list items addressed by
name (or index) in ``--set``, sweeps, ``fit --param`` and ``uncertainty --param``."""

from __future__ import annotations

import pytest

from biped_sim.config import derive, load_config
from biped_sim.errors import ConfigError
from biped_sim.studies.fit.parameters import fit_parameter, numeric_value
from biped_sim.studies.uncertainty.distributions import check_distributions, parse_distribution
from biped_sim.sweep.spec import load_sweep

from .conftest import CONFIGS

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
