"""Pictures of every walker: poses from a run's files (compliant and rigid), the walker figure, the animation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from biped_sim import load_config, simulate
from biped_sim.io.trajectory import RunData, load_run
from biped_sim.measure.pose import Poses, run_poses
from biped_sim.plots import RIGID_RUN_FIGURES

from .conftest import CONFIGS, invoke

BUNDLED = sorted(CONFIGS.glob("*.yaml"))
SHORT = {"rigid": ["simulation.max_steps=3"], "compliant": ["simulation.t_end=0.6"]}


def short_run_directory(config: Path, out: Path, *overrides: str) -> Path:
    """A short run of ``config`` written to ``out`` (three rigid steps, or 0.6 s of compliant dynamics)."""
    dynamics = load_config(config, list(overrides)).dynamics
    result = simulate(load_config(config, [*SHORT[dynamics], *overrides]))
    result.write(out)
    return out


def stance_foot_bottoms(run: RunData, poses: Poses) -> np.ndarray:
    """(ns,) the height of the stance foot's lowest point above the flat ground: a rigid run's (leg k mod 2 in
    step k, or a wheel's spoke k mod N), a compliant run's most loaded foot (less its penetration)."""
    sk = poses.skeleton
    bottoms = np.array([poses.at(i).foot_centres[:, 1] for i in range(len(run.time))]) - sk.foot_radius
    if run.dynamics == "compliant":
        foot = np.argmax(run.normal_force, axis=1)
        rows = np.arange(len(run.time))
        return bottoms[rows, foot] + run.penetration[rows, foot]
    step = np.searchsorted(run.steps["strike_time"], run.time, side="right")
    return bottoms[np.arange(len(run.time)), step % bottoms.shape[1]]


@pytest.mark.parametrize("config", BUNDLED, ids=lambda p: p.stem)
def test_every_bundled_walker_is_drawn_standing_on_its_stance_foot_and_animated(config: Path, tmp_path: Path) -> None:
    run_dir = short_run_directory(config, tmp_path / "run")
    run = load_run(run_dir)
    poses = run_poses(run)
    bottoms = stance_foot_bottoms(run, poses)
    loaded = run.dynamics == "rigid" or np.max(run.normal_force, axis=1) > 0
    tolerance = 1e-9 if run.dynamics == "rigid" else 2e-3  # sagittal view of a spatial walker; joint drift
    np.testing.assert_allclose(bottoms[loaded], 0.0, atol=tolerance)
    out = tmp_path / "walk.gif"
    result = invoke("animate", str(run_dir), "--out", str(out), "--fps", "4", "--end", "0.5")
    assert result.exit_code == 0, result.output
    with Image.open(out) as image:
        assert image.n_frames >= 1


def test_a_rigid_hip_moves_with_the_foot_offset(tmp_path: Path) -> None:
    """The rigid hip through the stance leg to its foot's centre, off the leg's axis (the hip once missed it)."""
    config = CONFIGS / "round_foot_walker.yaml"
    run = load_run(short_run_directory(config, tmp_path / "run", "dynamics=rigid", "walker.foot_offset=0.03"))
    bottoms = stance_foot_bottoms(run, run_poses(run))
    np.testing.assert_allclose(bottoms, 0.0, atol=1e-9)


def test_plot_draws_a_rigid_run_and_the_walker_of_a_kneed_walker(tmp_path: Path) -> None:
    run_dir = short_run_directory(CONFIGS / "kneed_walker.yaml", tmp_path / "run")
    result = invoke("plot", str(run_dir))
    assert result.exit_code == 0, result.output
    names = sorted(p.name for p in (run_dir / "figures").iterdir())
    assert names == sorted(f"{name}.{fmt}" for name in RIGID_RUN_FIGURES for fmt in ("png", "svg"))


def test_a_stop_is_drawn_engaged_only_at_its_limit(tmp_path: Path) -> None:
    run = load_run(short_run_directory(CONFIGS / "kneed_walker.yaml", tmp_path / "run"))
    poses = run_poses(run)
    engaged = np.array([poses.at(i).engaged for i in range(len(run.time))])
    assert engaged[0].all()  # just after a heel strike both knees are locked straight
    assert not engaged[:, 1].all() and not engaged[:, 0].all()  # each swing knee bends in its step
