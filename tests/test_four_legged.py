"""Liu's four-legged machine is a walker description, built by the one builder like every walker."""

from __future__ import annotations

import numpy as np

from biped_sim.config import Config, config_from_dict, load_config
from biped_sim.contact.response import ARMED, TOUCHING
from biped_sim.multibody.spatial import IN_PLANE
from biped_sim.walkers import BuiltModel, build_model
from biped_sim.walkers.describe import describe

from .conftest import CONFIGS

FOUR = CONFIGS / "four_legged_walker.yaml"
OFFSETS = ["walker.leg_com_offset=0.02", "walker.foot_offset=0.01"]


def _as_description(config: Config) -> Config:
    """``config`` with its walker written out as its description (``walker.kind: description``)."""
    data = config.model_dump(mode="json")
    data["walker"] = {"kind": "description", "description": describe(config).model_dump(mode="json")}
    return config_from_dict(data)


def _arrays(model: BuiltModel) -> dict[str, np.ndarray]:
    system = {f: getattr(model.system, f) for f in model.system._fields}
    return {f: v for f, v in system.items() if isinstance(v, np.ndarray)} | {"y0": model.y0, "modes0": model.modes0}


def test_the_four_legged_preset_is_its_description_bit_for_bit() -> None:
    config = load_config(FOUR, ["formulation.kind=minimal", *OFFSETS])
    preset, written = _arrays(build_model(config)), _arrays(build_model(_as_description(config)))
    assert preset.keys() == written.keys()
    assert all(preset[k].tobytes() == written[k].tobytes() for k in preset)


def test_the_machine_stands_on_both_feet_of_its_outer_pair_each_with_its_same_side_partner() -> None:
    model = build_model(load_config(FOUR, OFFSETS))
    system = model.system
    assert np.array_equal(model.modes0[:4, ARMED], [1, 1, 0, 0])
    assert np.array_equal(model.modes0[:4, TOUCHING], [1, 1, 0, 0])
    assert np.array_equal(system.foot_partner, [2, 3, 0, 1])
    assert np.array_equal(system.foot_center[:, 2], [0.12, -0.12, 0.06, -0.06])
    assert IN_PLANE not in system.con_type  # feet apart: roll and yaw are free, no planar joint to the ground
    assert system.body_inertia[0, 0, 1] != 0.0 and system.body_inertia[0, 0, 0] != system.body_inertia[0, 2, 2]


def test_a_compass_on_one_foot_per_leg_is_held_in_its_plane() -> None:
    system = build_model(load_config(CONFIGS / "round_foot_walker.yaml", ["formulation.kind=spatial"])).system
    assert IN_PLANE in system.con_type and np.array_equal(system.foot_partner, [1, 0])
    assert np.array_equal(system.body_inertia[0], np.eye(3) * system.body_inertia[0, 2, 2])
