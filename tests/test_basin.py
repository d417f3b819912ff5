"""biped-sim basin: cells at the gait walk and converge, far ones fall; outputs, resume and bad input."""

from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from biped_sim import load_config
from biped_sim.config import derive
from biped_sim.errors import ConfigError
from biped_sim.studies.basin import (
    CONVERGED,
    FELL,
    WALKS,
    BasinSpec,
    GridAxis,
    RowTask,
    _rigid_row,
    map_basin,
    parse_axis,
)

from .conftest import CONFIGS, invoke, one_line_error

SIMPLEST = CONFIGS / "simplest_walker.yaml"
GRID = ("--x", "stance_angle=0.15:0.25:3", "--y", "stance_rate=-0.5:-0.2:4", "--steps", "20")


def test_a_cell_at_the_fixed_point_converges_and_one_far_away_falls() -> None:
    config = load_config(SIMPLEST)
    # columns: far from the gait, then the fixed point (0.20031090049, -0.19983247292) to 5e-4
    spec = BasinSpec(
        config, GridAxis("stance_angle", 0.0503109, 0.2003109, 2), GridAxis("stance_rate", -0.6, -0.1998, 2)
    )
    basin = map_basin(spec, None)
    assert basin.outcome[1, 1] == CONVERGED and basin.steps[1, 1] == spec.steps
    assert basin.outcome[0, 0] == FELL and basin.steps[0, 0] < spec.steps


@pytest.mark.slow
def test_compliant_cells_walk_from_the_configured_start_and_fall_far_from_it() -> None:
    config = load_config(CONFIGS / "round_foot_walker.yaml")  # starts at (0.25, -1.6)
    spec = BasinSpec(config, GridAxis("stance_angle", 0.05, 0.25, 2), GridAxis("stance_rate", -1.6, -0.2, 2), 3)
    basin = map_basin(spec, None)
    assert basin.outcome[0, 1] != FELL and basin.steps[0, 1] == 3
    assert basin.outcome[1, 0] == FELL and basin.steps[1, 0] < 3


def test_simplest_walker_cells_start_on_the_post_impact_section() -> None:
    spec = BasinSpec(
        load_config(SIMPLEST), parse_axis("--x", "stance_angle=0.1:0.3:3"), parse_axis("--y", "stance_rate=-1:0:3")
    )
    legs = spec.cell_legs(0.3, -0.5)
    assert legs["swing_angle"] == -0.3 and legs["swing_rate"] == pytest.approx(-0.5 * math.cos(0.6), abs=1e-15)
    compass = BasinSpec(load_config(CONFIGS / "compass_goswami.yaml"), spec.x, spec.y)
    assert compass.cell_legs(0.3, -0.5)["swing_angle"] == compass.config.simulation.initial.swing_angle


@pytest.mark.parametrize("jobs", ["1", pytest.param("2", marks=pytest.mark.slow)])  # 2: on the worker pool
def test_basin_cli_writes_its_files_and_a_rerun_resumes(tmp_path: Path, jobs: str) -> None:
    out = tmp_path / "basin"
    first = invoke("basin", str(SIMPLEST), *GRID, "--jobs", jobs, "--out", str(out), "--json")
    assert first.exit_code == 0, first.stderr
    doc = json.loads(first.stdout)
    assert doc["n_cells"] == 12 and doc["rows_reused"] == 0
    assert 0 < doc["fraction_converged"] <= doc["fraction_walking"] < 1
    assert {p.name for p in out.iterdir()} == {"basin.h5", "basin.csv", "basin.png", "basin.svg", "cells"}
    with h5py.File(out / "basin.h5") as f:
        assert f["outcome"].shape == (4, 3) and f.attrs["fixed_point_stance_angle"] == pytest.approx(
            0.2003109, abs=1e-6
        )
    assert len((out / "basin.csv").read_text().splitlines()) == 13
    again = json.loads(invoke("basin", str(SIMPLEST), *GRID, "--jobs", jobs, "--out", str(out), "--json").stdout)
    assert again["rows_reused"] == 4 and again["fraction_walking"] == doc["fraction_walking"]


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (("--x", "stance_angle=0.3:0.1:3", "--y", "stance_rate=-1:0:3"), "--x"),
        (("--x", "stance_angle=0:0.3:3", "--y", "hip_rate=-1:0:3"), "--y"),
        (("--x", "stance_angle=0:0.3:3", "--y", "stance_angle=-1:0:3"), "--y"),
        (("--x", "stance_angle=0:0.3:3", "--y", "stance_rate=-1:0:3", "--steps", "0"), "--steps"),
        (("--x", "stance_angle=0:0.3:3", "--y", "stance_rate=-1:0:3", "--tolerance", "-1"), "--tolerance"),
    ],
)
def test_bad_basin_input_is_one_line_and_writes_nothing(tmp_path: Path, args: tuple[str, ...], field: str) -> None:
    out = tmp_path / "basin"
    result = invoke("basin", str(SIMPLEST), *args, "--out", str(out))
    assert result.exit_code == 2
    assert field in one_line_error(result.stderr)
    assert not out.exists()


def test_parse_axis_accepts_the_full_key() -> None:
    assert parse_axis("--x", "simulation.initial.stance_rate=-1:0:5") == GridAxis("stance_rate", -1.0, 0.0, 5)
    with pytest.raises(ConfigError, match="--x"):
        parse_axis("--x", "stance_rate=-1:0")


GOSWAMI_RIGID = ("--set", "dynamics=rigid")
KNEED_PARAMETRISED = Path(__file__).parent / "data" / "kneed_parametrised.yaml"
KNEED_START = (  # near the parametrised kneed walker's rigid fixed point
    "--set",
    "simulation.initial={stance_thigh_angle: 0.2386, stance_shank_angle: 0.2386, swing_thigh_angle: -0.2386, "
    "swing_shank_angle: -0.2386, stance_thigh_rate: -1.1096, stance_shank_rate: -1.1096, swing_thigh_rate: -0.0571, "
    "swing_shank_rate: -0.0571}",
)


def test_a_parameter_axis_walks_each_cell_with_its_value_and_converges_to_its_own_gait() -> None:
    config = load_config(CONFIGS / "compass_goswami.yaml", ["dynamics=rigid"])
    hip_mass = parse_axis("--x", "walker.parameters.hip_mass=8:10:3")  # stable gaits (11: unstable)
    spec = BasinSpec(config, hip_mass, parse_axis("--y", "stance_angle=0.15:0.3:4"), 20)
    basin = map_basin(spec, None)
    gaits = basin.parameter_gaits
    assert gaits[2] == basin.fixed_point and None not in gaits  # 10 kg: the configured walker
    assert gaits[0]["stance_angle"] != gaits[1]["stance_angle"] != gaits[2]["stance_angle"]
    light = derive(config, {"walker.hip_mass": 8.0})  # the first column: the walker with the axis's first value
    plain = map_basin(BasinSpec(light, GridAxis("stance_rate", -1.0, -0.5, 2), spec.y, 20), None)  # -1: configured
    assert np.array_equal(plain.outcome[:, 0], basin.outcome[:, 0])
    assert np.array_equal(plain.steps[:, 0], basin.steps[:, 0]) and np.any(basin.steps[:, 0] != basin.steps[:, 2])
    for column, value in enumerate(hip_mass.values):  # each column's cells end near their own value's gait
        assert spec.cell_config(value, 0.2) == derive(config, {"walker.hip_mass": float(value)})
        on_gait = [(spec.cell_config(value, 0.0), dict(gaits[column]))]
        assert _rigid_row(RowTask(spec, 0, [gaits[column]]), on_gait)[0] == [CONVERGED]
        assert _rigid_row(RowTask(spec, 0, [gaits[column - 1]]), on_gait)[0] == [WALKS]


@pytest.mark.slow  # three limit cycles of the kneed walker and the figure: about 10 s
def test_a_parameter_axis_of_a_described_walker_in_the_cli(tmp_path: Path) -> None:
    out = tmp_path / "basin"
    args = ("--x", "stance_thigh_rate=-1.2:-1.0:2", "--y", "walker.parameters.hip_mass=0.45:0.55:2", "--steps", "5")
    result = invoke("basin", str(KNEED_PARAMETRISED), *args, *KNEED_START, "--out", str(out), "--json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["y"]["key"] == "walker.parameters.hip_mass" and len(doc["parameter_gaits"]) == 2
    assert None not in doc["parameter_gaits"] and doc["fraction_walking"] > 0
    with h5py.File(out / "basin.h5") as f:
        assert f["y"].attrs["key"] == "walker.parameters.hip_mass"
        assert f["x"].attrs["key"] == "simulation.initial.stance_thigh_rate"
        assert json.loads(f.attrs["parameter_gaits"]) == doc["parameter_gaits"]
    assert (out / "basin.csv").read_text().splitlines()[
        0
    ] == "stance_thigh_rate,walker.parameters.hip_mass,outcome,steps"


@pytest.mark.parametrize(
    ("args", "field", "reason"),
    [
        (("--x", "walker.parameters.leg_mass=1:2:2", "--y", "walker.parameters.hip_mass=1:2:2"), "--y", "sweep"),
        (("--x", "walker.parameters.mass=1:2:3", "--y", "stance_rate=-1:0:3"), "--x", "leg_inertia"),
        (("--x", "walker.parameters.hip_mass=-1:2:3", "--y", "stance_rate=-1:0:3"), "--x", "hip_mass"),
        (("--x", "walker.parameters.=1:2:3", "--y", "stance_rate=-1:0:3"), "--x", "walker.parameters.NAME"),
    ],
)
def test_bad_parameter_axes_are_one_line(tmp_path: Path, args: tuple[str, ...], field: str, reason: str) -> None:
    out = tmp_path / "basin"
    result = invoke("basin", str(CONFIGS / "compass_goswami.yaml"), *args, *GOSWAMI_RIGID, "--out", str(out))
    assert result.exit_code == 2
    line = one_line_error(result.stderr)
    assert field in line and reason in line
    assert not out.exists()
