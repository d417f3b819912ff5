"""A kneed walker with round feet and a torso on hip springs that exists only as a YAML file
(tests/data/kneed_torso.yaml, issue 31): it walks in rigid and compliant dynamics, ``limit-cycle`` finds its stable
gait and ``basin`` maps the starts around it, and its named parameters are varied by a sweep, by ``uncertainty`` and
by ``fit``, which recovers a hidden torso mass from the model's own step periods. Slow tier: each is a few rigid
steps or samples, the compliant run three steps."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import derive, load_config
from biped_sim.simulate import simulate
from biped_sim.studies.fit import synthetic_reference

from .conftest import invoke
from .test_yaml_walker import swept

WALKER = Path(__file__).parent / "data" / "kneed_torso.yaml"
TORSO_MASS = "walker.parameters.torso_mass"
RIGID_PERIOD = 0.57784  # measured: the rigid gait's step period [s]

pytestmark = pytest.mark.slow


def test_limit_cycle_finds_its_stable_rigid_gait_and_basin_maps_the_starts_around_it(tmp_path: Path) -> None:
    """``limit-cycle``: the gait (measured: period 0.57784 s, multipliers 0.391 +- 0.560i (|0.683|), 0.073 +-
    0.047i, 0.036; the torso 0.197 rad forward of the slope normal just after the strike). ``basin`` over the stance
    thigh's angle (0.2, 0.3, 0.4 rad, the knee bent or overstretched off 0.3) and the torso's (-0.4, 0.2, 0.8 rad):
    the cell nearest the fixed point comes back to the gait within 15 steps, its column walks with the torso 0.6 rad
    off, and the other columns fall."""
    result = invoke("limit-cycle", str(WALKER), "--json")
    assert result.exit_code == 0, result.stderr
    cycle = json.loads(result.stdout)
    assert cycle["stable"] and cycle["max_multiplier_modulus"] < 0.7
    assert cycle["step_period"] == pytest.approx(RIGID_PERIOD, rel=1e-4)
    assert 0.15 < cycle["fixed_point"]["torso_angle"] < 0.25  # leaning forward, held by the springs
    grid = ("--x", "stance_thigh_angle=0.2:0.4:3", "--y", "torso_angle=-0.4:0.8:3", "--steps", "15")
    out = tmp_path / "basin"
    result = invoke("basin", str(WALKER), *grid, "--tolerance", "1e-3", "--jobs", "1", "--out", str(out))
    assert result.exit_code == 0, result.stderr
    with (out / "basin.csv").open() as f:
        outcome = {(round(float(r["stance_thigh_angle"]), 2), round(float(r["torso_angle"]), 2)): r["outcome"]
                   for r in csv.DictReader(f)}  # fmt: skip
    assert outcome[0.3, 0.2] == "converged" and outcome[0.3, -0.4] == outcome[0.3, 0.8] == "walks"
    assert {outcome[thigh, torso] for thigh in (0.2, 0.4) for torso in (-0.4, 0.2, 0.8)} == {"fell"}


def test_the_compliant_walker_walks_the_rigid_gait() -> None:
    """Compliant dynamics from the same start: three steps within 1.5 % of the rigid period (measured: 0.5802, 0.5837,
    0.5821 s), the springs' and dampers' energy in a closed audit."""
    result = simulate(load_config(WALKER, ["dynamics=compliant", "simulation.t_end=2.4"]))
    periods = np.array(result.summary["step_periods"])
    assert result.status == "walking" and len(periods) >= 3
    assert np.allclose(periods, RIGID_PERIOD, rtol=0.015)
    assert result.summary["energy_dissipated"]["elements"] > 0
    assert result.summary["energy_residual_max_relative"] < 1e-6


def test_a_sweep_and_uncertainty_vary_the_torso(tmp_path: Path) -> None:
    rows = swept(tmp_path, WALKER, "walker.parameters.torso_stiffness", [0.1, 0.12])
    assert {r["status"] for r in rows} == {"walking"} and rows[0]["mean_period_s"] != rows[1]["mean_period_s"]
    args = ("--param", f"{TORSO_MASS}=uniform:0.08:0.12", "--samples", "4", "--jobs", "1")
    args += ("--set", "simulation.t_end=3")
    result = invoke("uncertainty", str(WALKER), *args, "--out", str(tmp_path / "uncertainty"), "--json")
    assert result.exit_code == 0, result.stderr
    stats = json.loads(result.stdout)["statistics"]
    assert stats["status_counts"] == {"walking": 4} and stats["outputs"]["steady_period"]["sd"] > 0


def test_fit_recovers_a_hidden_torso_mass_from_the_walkers_own_step_periods(tmp_path: Path) -> None:
    reference = tmp_path / "reference.yaml"
    reference.write_text(synthetic_reference(derive(load_config(WALKER), {TORSO_MASS: 0.12}), 6, 0.0, seed=0))
    args = ("--reference", str(reference), "--param", f"{TORSO_MASS}=0.05:0.2", "--jobs", "1")
    result = invoke("fit", str(WALKER), *args, "--out", str(tmp_path / "fit"), "--json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["converged"] and doc["parameters"][TORSO_MASS] == pytest.approx(0.12, rel=1e-4)
