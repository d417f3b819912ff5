"""`dynamics: rigid` runs: Garcia's fixed point repeats, impact losses, energy balance, files, CLI, sweeps."""

from __future__ import annotations

import json
import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from biped_sim import load_config, simulate
from biped_sim.cli import app
from biped_sim.errors import ConfigError
from biped_sim.report import build_report
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.start import INTEGRATOR
from biped_sim.simulate.rigid import RigidRunResult
from biped_sim.sweep import check_buildable, load_sweep, run_sweep
from biped_sim.testing import write_reference, write_sweep

from .conftest import CONFIGS

SIMPLEST = CONFIGS / "simplest_walker.yaml"
RIMLESS = CONFIGS / "rimless_wheel.yaml"
THETA_STAR, THETA_DOT_STAR = 0.20031090049483, -0.19983247291764  # MODEL.md 8, slope 0.009
RIGID_DATASETS = (
    "time", "state", "state_names", "energy/kinetic", "energy/potential", "energy/dissipated_impact",
    "energy/dissipated_elements", "energy/push_work", "energy/residual", "hip", "steps/strike_time", "steps/foot",
    "steps/period", "steps/length", "steps/slip",
    "steps/stance_angle", "steps/stance_rate", "steps/swing_angle", "steps/swing_rate", "strikes/time",
    "strikes/pre_impact", "strikes/post_impact",
)  # fmt: skip


def rigid_run(path: Path, *overrides: str) -> RigidRunResult:
    result = simulate(load_config(path, list(overrides)))
    assert isinstance(result, RigidRunResult)
    return result


def invoke(*args: str) -> tuple[int, str, str]:
    out = CliRunner().invoke(app, list(args))
    return out.exit_code, out.stdout, out.stderr


def garcia_start() -> list[str]:
    """Garcia's fixed point just after heel strike; the swing state from the heel-strike map (MODEL.md 8)."""
    return [
        f"simulation.initial.stance_angle={THETA_STAR!r}",
        f"simulation.initial.stance_rate={THETA_DOT_STAR!r}",
        f"simulation.initial.swing_angle={-THETA_STAR!r}",
        f"simulation.initial.swing_rate={math.cos(2 * THETA_STAR) * THETA_DOT_STAR!r}",
    ]


def test_simplest_walker_on_garcias_fixed_point_repeats_it_step_after_step() -> None:
    config = load_config(SIMPLEST, [*garcia_start(), "simulation.t_end=60", "output.sample_rate=20"])
    cycle = rigid_limit_cycle(config)
    result = rigid_run(SIMPLEST, *garcia_start(), "simulation.t_end=60", "output.sample_rate=20")
    assert result.status == "walking" and len(result.step_periods) >= 13
    np.testing.assert_allclose(result.step_periods, cycle.step_period, rtol=0, atol=1e-8)
    np.testing.assert_allclose(result.step_lengths, cycle.step_length, rtol=0, atol=1e-8)
    for state in result.post_impact_states:  # the Poincaré section: just after each strike
        assert state["stance_angle"] == pytest.approx(THETA_STAR, abs=1e-9)
        assert state["stance_rate"] == pytest.approx(THETA_DOT_STAR, abs=1e-9)
        assert state["swing_angle"] == pytest.approx(-state["stance_angle"], abs=1e-13)
    for state in result.heel_strike_states:  # touchdown (pre-impact), as the compliant model records them
        for key, value in cycle.touchdown.items():
            assert state[key] == pytest.approx(value, abs=1e-8), key
    assert list(result.steps.foot[:4]) == [1, 0, 1, 0]
    assert result.summary["energy_residual_max_relative"] < 1e-10
    assert result.summary["slip_per_step"] == [0.0] * len(result.step_periods)


def test_rimless_wheel_impacts_keep_cos2_2alpha_of_the_kinetic_energy() -> None:
    result = rigid_run(RIMLESS, "simulation.max_steps=6", "output.sample_rate=100")
    assert len(result.strike_time) == 6 and result.t_final == result.strike_time[-1]
    alpha = math.pi / 8
    kept = math.cos(2 * alpha) ** 2
    kinetic_before = 0.5 * result.walker.leg_length**2 * result.strike_pre[:, 1] ** 2  # hub mass 1, point contact
    # the booked losses jump at the strike samples, by the analytic loss of each impact
    jumps = np.diff(result.energy.dissipated_impact)
    jump_times = result.time[1:][jumps != 0]
    np.testing.assert_array_equal(jump_times, result.strike_time)
    np.testing.assert_allclose(jumps[jumps != 0], (1 - kept) * kinetic_before, rtol=1e-12)
    post = 0.5 * result.walker.leg_length**2 * result.strike_post[:, 1] ** 2
    np.testing.assert_allclose(post / kinetic_before, kept, rtol=1e-12)
    losses = result.summary["energy_dissipated"]
    assert losses["impact"] == pytest.approx(np.sum((1 - kept) * kinetic_before), rel=1e-12)
    assert losses["normal"] == losses["impact"] and losses["friction"] == 0.0
    assert list(result.steps.foot) == [1, 2, 3, 4, 5, 6]  # spokes of an 8-spoke wheel


def test_round_foot_compass_energy_balances_and_the_hip_rolls_on_continuously() -> None:
    result = rigid_run(
        CONFIGS / "round_foot_walker.yaml", "dynamics=rigid", "simulation.t_end=3", "output.sample_rate=200"
    )
    assert result.status == "walking" and len(result.strike_time) >= 5
    assert result.summary["energy_residual_max_relative"] < 1e-10
    assert result.summary["energy_dissipated"]["impact"] > 0.01  # the balance is not trivially zero
    # the hip moves continuously through the strikes: no sample-to-sample jump beyond its speed bound
    walker = result.walker
    R, l = walker.foot_radius, walker.leg_length
    theta, theta_dot = result.state[:, 0], result.state[:, walker.n_q]
    hip_speed = np.abs((R + (l - R) * np.cos(theta)) * theta_dot)
    gaps = np.diff(result.time)
    assert np.all(np.abs(np.diff(result.hip[:, 0])) <= 1.01 * np.maximum(hip_speed[:-1], hip_speed[1:]) * gaps + 1e-12)
    assert result.hip[-1, 0] == pytest.approx(np.sum(result.step_lengths), rel=0.3)  # the walker got somewhere


def test_fall_ends_the_run_with_its_time() -> None:
    result = rigid_run(SIMPLEST, "simulation.initial.stance_rate=-0.02", "output.sample_rate=20")
    assert result.status == "fell" and result.summary["stop_time"] == result.t_final
    assert result.time[-1] == result.t_final < result.config.simulation.t_end


def test_cli_run_writes_the_documented_files_identically_twice(tmp_path: Path) -> None:
    outs = [tmp_path / "a", tmp_path / "b"]
    for out in outs:
        code, stdout, stderr = invoke(
            "run", str(SIMPLEST), "--set", "simulation.t_end=20", "--set", "output.sample_rate=20", "--out", str(out)
        )
        assert code == 0, stderr
        assert "walking: 5 steps" in stdout and "rigid model, nondimensional: g = l = 1" in stdout
        assert sorted(p.name for p in out.iterdir()) == ["config.yaml", "steps.csv", "summary.json", "trajectory.h5"]
    summary = json.loads((outs[0] / "summary.json").read_text())
    assert summary["dynamics"] == "rigid" and summary["integrator"] == INTEGRATOR
    assert summary["constraint_violation_max"] == {"position": 0.0, "velocity": 0.0}
    assert len((outs[0] / "steps.csv").read_text().splitlines()) == summary["n_steps"] + 1
    with h5py.File(outs[0] / "trajectory.h5") as first, h5py.File(outs[1] / "trajectory.h5") as second:
        assert first.attrs["dynamics"] == "rigid" and first.attrs["config_hash"] == summary["config_hash"]
        assert list(first["state_names"].asstr()[:]) == ["stance_angle", "swing_angle", "stance_rate", "swing_rate"]
        assert first["time"].attrs["units"] == "1 (g = l = 1)"
        np.testing.assert_array_equal(first["strikes/time"][:], summary["step_times"])
        for name in RIGID_DATASETS:
            assert "units" in first[name].attrs, name
            if name != "state_names":  # strings: compared above
                assert first[name][()].tobytes() == second[name][()].tobytes(), name
        assert "contact" not in first


@pytest.mark.parametrize(
    ("config", "override", "expected"),
    [
        (SIMPLEST, "simulation.initial.stance_angle=1.5", "simulation.initial.stance_angle: beyond"),
        (SIMPLEST, "simulation.initial.stance_angle=-0.1", "stance leg must not be past the slope normal"),
        (RIMLESS, "simulation.initial.stance_angle=0.5", "stance spoke must be within pi/N"),
    ],
)
def test_bad_rigid_start_is_one_line_exit_2_and_writes_nothing(
    tmp_path: Path, config: Path, override: str, expected: str
) -> None:
    out = tmp_path / "out"
    code, _, stderr = invoke("run", str(config), "--set", override, "--out", str(out))
    assert code == 2
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0]
    assert not out.exists()


def test_plot_draws_a_rigid_run_and_compare_reads_its_periods(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    code, _, stderr = invoke("run", str(RIMLESS), "--set", "simulation.max_steps=4", "--out", str(run_dir), "-q")
    assert code == 0, stderr
    code, stdout, stderr = invoke("plot", str(run_dir))
    assert code == 0 and "4 figures" in stdout, stderr
    reference = write_reference(tmp_path / "reference.yaml", [0.6, 0.7, 0.7])
    code, _, stderr = invoke("compare", str(run_dir), "--reference", str(reference), "--out", str(tmp_path / "cmp"))
    assert code == 0, stderr
    times = json.loads((run_dir / "summary.json").read_text())["step_times"]
    steps = pd.read_csv(tmp_path / "cmp" / "compare_steps.csv")
    np.testing.assert_allclose(steps["model period [s]"], np.diff([0.0, *times])[:3], rtol=1e-6)


def test_sweep_over_the_simplest_walkers_slope(tmp_path: Path) -> None:
    path = write_sweep(
        tmp_path,
        "s",
        base=SIMPLEST,
        set_={"simulation.t_end": 20.0, "output.sample_rate": 10.0},
        grid={"ground.slope": [0.006, 0.009]},
    )
    sweep = load_sweep(path)
    check_buildable(sweep)
    with ThreadPoolExecutor(max_workers=1) as executor:
        outcome = run_sweep(sweep, tmp_path / "sweep", executor)
    rows = outcome.rows
    assert [row["status"] for row in rows] == ["walking", "walking"]
    assert all(3.8 < row["mean_period_s"] < 4.0 and row["step_control"] == INTEGRATOR for row in rows)
    assert rows[0]["energy_dissipated_normal_J"] < rows[1]["energy_dissipated_normal_J"]  # steeper: harder strikes
    assert math.isnan(rows[0]["max_penetration_m"])
    report = build_report(tmp_path / "sweep")  # tables and the parameter figures; no contact time series
    assert "period_vs_slope" in report.figures and "contact_forces" not in report.figures
    assert (report.out_dir / "figures" / "period_vs_slope.png").is_file()

    bad = write_sweep(tmp_path, "bad", base=SIMPLEST, grid={"simulation.initial.stance_angle": [0.2, -0.1]})
    with pytest.raises(ConfigError, match=r"run 2 .*simulation.initial.stance_angle"):
        check_buildable(load_sweep(bad))
