"""For notebook users: a run, a sweep, an uncertainty study and an MFPT curve print one short line and convert to
pandas (so that ``simulate(...)`` to a plot is three lines)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from biped_sim import load_config, simulate
from biped_sim.measure.steps import STEP_COLUMNS
from biped_sim.studies.uncertainty.distributions import parse_param
from biped_sim.studies.uncertainty.mfpt import mfpt_curve
from biped_sim.studies.uncertainty.study import UncertaintySpec, output_names, run_study
from biped_sim.sweep import load_sweep, read_sweep, run_sweep
from biped_sim.testing import write_sweep

from .conftest import CONFIGS

SIMPLEST = CONFIGS / "simplest_walker.yaml"


def test_a_run_prints_one_line_and_its_step_table_converts() -> None:
    result = simulate(load_config(CONFIGS / "round_foot_walker.yaml", ["simulation.t_end=1.2"]))
    text = repr(result)
    assert "\n" not in text and len(text) < 120
    assert text.startswith("<RunResult walking: 3 heel strikes in 1.200 s, mean period 0.39")
    frame = result.to_pandas()
    assert list(frame.columns) == [name for name, _ in STEP_COLUMNS]
    assert list(frame.index) == [1, 2, 3] and frame.attrs["units"]["period"] == "s"
    np.testing.assert_array_equal(frame["period"].to_numpy()[:-1], result.step_periods)
    assert np.isnan(frame["period"].iloc[-1])  # the last strike's step has not ended


def test_a_nondimensional_run_says_so_and_a_fall_gives_its_reason() -> None:
    walking = repr(simulate(load_config(SIMPLEST, ["simulation.t_end=10"])))
    assert walking.endswith("g = l = 1>") and " s," not in walking
    fallen = simulate(load_config(SIMPLEST, ["ground.slope=0.2", "simulation.t_end=30"]))
    assert fallen.status == "fell" and repr(fallen).endswith(f"({fallen.status_reason})>")


def test_a_sweep_outcome_is_its_table(tmp_path: Path) -> None:
    sweep = load_sweep(write_sweep(tmp_path, "nb", set_={"simulation.t_end": 0.5}, grid={"ground.slope": [0.01]}))
    with ThreadPoolExecutor(max_workers=1) as executor:
        outcome = run_sweep(sweep, tmp_path / "out", executor)
    assert repr(outcome) == f"<SweepOutcome {tmp_path / 'out'}: 1 runs (1 walking)>"
    _, table = read_sweep(tmp_path / "out")
    assert outcome.to_pandas().equals(table)


def test_an_uncertainty_study_gives_its_statistics_and_samples() -> None:
    config = load_config(SIMPLEST, ["simulation.t_end=20"])
    study = run_study(UncertaintySpec(config, (parse_param("ground.slope=uniform:0.006:0.012"),), samples=4), None)
    text = repr(study)
    assert text.startswith("<Uncertainty of ground.slope: 4 samples, P(walking) 1.000 [") and "\n" not in text
    stats = study.to_pandas()
    assert list(stats.index) == list(output_names(config))
    assert stats.loc["steady_period", "mean"] == study.stats["outputs"]["steady_period"]["mean"]
    assert {"n", "sd", "q0.05", "q0.95", "min", "max"} <= set(stats.columns)
    samples = study.samples_frame()
    assert len(samples) == 4 and list(samples["status"]) == ["walking"] * 4
    np.testing.assert_array_equal(samples["ground.slope"].to_numpy(), study.values[:, 0])


def test_an_mfpt_curve_is_one_row_per_level() -> None:
    curve = mfpt_curve(load_config(CONFIGS / "rimless_wheel.yaml"), "slope", [0.0, 0.04], seeds=4, cap=50)
    frame = curve.to_pandas()
    assert list(frame["roughness"]) == [0.0, 0.04] and {"mfpt", "ci", "falls", "chain_mfpt"} <= set(frame.columns)
    assert repr(curve).startswith("<MfptCurve on slope ground, 4 walks per level capped at 50 steps: MFPT [")
