"""A walker that exists only as a YAML file (tests/data/kneed_round_feet.yaml: kneed legs written once and mirrored,
round feet, named parameters) reaches every study: its gait and basin, a sweep, ``uncertainty`` and ``fit`` vary
its named parameters through the commands, and the fit recovers a hidden value of one from the model's own step
periods."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from biped_sim.config import derive, load_config
from biped_sim.studies.fit import synthetic_reference
from biped_sim.studies.limit_cycle import limit_cycle

from .conftest import invoke

WALKER = Path(__file__).parent / "data" / "kneed_round_feet.yaml"
RADIUS = "walker.parameters.foot_radius"
START = (  # off the gait (0.264, -1.217, ..., -0.131), so that the first steps say more than the cycle's period
    "simulation.initial={stance_thigh_angle: 0.25, stance_thigh_rate: -1.15, stance_shank_angle: 0.25, "
    "stance_shank_rate: -1.15, swing_thigh_angle: -0.25, swing_thigh_rate: -0.1, swing_shank_angle: -0.25, "
    "swing_shank_rate: -0.1}"
)


def test_the_yaml_walker_finds_a_stable_gait_that_its_foot_radius_moves() -> None:
    config = load_config(WALKER)
    cycle, larger = limit_cycle(config), limit_cycle(derive(config, {RADIUS: 0.12}))
    assert cycle.converged and cycle.stable and larger.converged
    assert larger.step_period != cycle.step_period and larger.fixed_point != cycle.fixed_point


def swept(tmp_path: Path, walker: Path, key: str, values: list[float]) -> list[dict[str, str]]:
    """The rows of ``biped-sim sweep`` over ``key`` at ``values`` on ``walker``, 3 s each, run in this process."""
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(
        f"name: sweep\nbase: {walker}\nset:\n  simulation.t_end: 3.0\ngrid:\n  {key}: {values}\n"
        f"output: {tmp_path / 'out'}\n"
    )
    result = invoke("sweep", str(sweep), "--jobs", "1")
    assert result.exit_code == 0, result.stderr
    with (tmp_path / "out" / "sweep.csv").open() as f:
        return list(csv.DictReader(f))


def test_a_sweep_runs_the_yaml_walker_over_its_named_parameter(tmp_path: Path) -> None:
    rows = swept(tmp_path, WALKER, RADIUS, [0.08, 0.12])
    assert [float(r[RADIUS]) for r in rows] == [0.08, 0.12] and {r["status"] for r in rows} == {"walking"}
    assert rows[0]["mean_period_s"] != rows[1]["mean_period_s"]


def test_uncertainty_samples_the_yaml_walkers_named_parameter(tmp_path: Path) -> None:
    out = tmp_path / "uncertainty"
    args = ("--param", f"{RADIUS}=uniform:0.08:0.12", "--samples", "4", "--jobs", "1", "--set", "simulation.t_end=3")
    result = invoke("uncertainty", str(WALKER), *args, "--out", str(out), "--json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    stats = doc["statistics"]
    assert stats["n_samples"] == 4 and stats["status_counts"] == {"walking": 4}
    assert stats["outputs"]["steady_period"]["sd"] > 0  # the radius moves the period


@pytest.mark.slow  # a fit: tens of rigid runs (about a minute on the loaded machine)
def test_fit_recovers_a_hidden_foot_radius_from_the_walkers_own_step_periods(tmp_path: Path) -> None:
    hidden = derive(load_config(WALKER, [START]), {RADIUS: 0.11})
    reference = tmp_path / "reference.yaml"
    reference.write_text(synthetic_reference(hidden, 6, 0.0, seed=0))
    args = ("--reference", str(reference), "--param", f"{RADIUS}=0.06:0.14", "--set", START, "--jobs", "1")
    result = invoke("fit", str(WALKER), *args, "--out", str(tmp_path / "fit"), "--json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["converged"] and doc["parameters"][RADIUS] == pytest.approx(0.11, rel=1e-4)
