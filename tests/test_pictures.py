"""Pictures of every walker: poses from a run's files (compliant and rigid), the walker figure, the animation."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from PIL import Image

from biped_sim import load_config, simulate
from biped_sim.contact.ground import ground_height_at
from biped_sim.contact.profile import profile_arrays
from biped_sim.io.trajectory import RunData, load_run
from biped_sim.measure.pose import FOOT_ARC_HALF_ANGLE, FOOT_HALF_WIDTH, Poses, Skeleton, run_poses, skeleton
from biped_sim.measure.space_pose import space_poses
from biped_sim.picture import GROUND_COLOUR, OFF_LEG_COLOUR, WalkerPicture, body_colour, draw_ground, draw_space_ground
from biped_sim.plots import RIGID_RUN_FIGURES, walker_figure
from biped_sim.walkers.describe import describe

from .conftest import CONFIGS, invoke

BUNDLED = sorted(CONFIGS.glob("*.yaml"))
SHORT = {"rigid": ["simulation.max_steps=3", "output.sample_rate=100"], "compliant": ["simulation.t_end=0.6"]}


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


@pytest.mark.parametrize(
    ("config", "overrides"),
    [(config, ()) for config in BUNDLED] + [(CONFIGS / "round_foot_walker.yaml", ("formulation.kind=minimal",))],
    ids=[config.stem for config in BUNDLED] + ["round_foot_walker_minimal"],
)
def test_every_bundled_walker_is_drawn_standing_on_its_stance_foot_and_animated(
    config: Path, overrides: tuple[str, ...], tmp_path: Path
) -> None:
    run_dir = short_run_directory(config, tmp_path / "run", *overrides)
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


@pytest.fixture(scope="module")
def kneed_run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three steps of Chen's rigid kneed walker from its limit cycle (read-only; figures may go below it)."""
    return short_run_directory(CONFIGS / "kneed_walker.yaml", tmp_path_factory.mktemp("kneed") / "run")


def test_plot_draws_a_rigid_run_and_the_walker_of_a_kneed_walker(kneed_run_dir: Path) -> None:
    result = invoke("plot", str(kneed_run_dir))
    assert result.exit_code == 0, result.output
    names = sorted(p.name for p in (kneed_run_dir / "figures").iterdir())
    assert names == sorted(f"{name}.{fmt}" for name in RIGID_RUN_FIGURES for fmt in ("png", "svg"))


def test_the_walker_figure_holds_every_pose_whole(kneed_run_dir: Path) -> None:
    ax = walker_figure(load_run(kneed_run_dir)).axes[0]
    (x_lo, x_hi), (y_lo, y_hi) = ax.get_xlim(), ax.get_ylim()
    points = np.hstack([np.vstack(line.get_data()) for line in ax.get_lines()])
    assert points.shape[1] > 6 * 8  # six poses, each body and foot
    assert np.all((points[0] >= x_lo) & (points[0] <= x_hi) & (points[1] >= y_lo) & (points[1] <= y_hi))


def test_a_stop_is_drawn_engaged_only_at_its_limit(kneed_run_dir: Path) -> None:
    poses = run_poses(load_run(kneed_run_dir))
    engaged = np.array([poses.at(i).engaged for i in range(len(poses.time))])
    assert engaged[0].all()  # just after a heel strike both knees are locked straight
    assert not engaged[:, 1].all() and not engaged[:, 0].all()  # each swing knee bends in its step


def test_a_wheel_is_drawn_as_spokes_from_its_hub(tmp_path: Path) -> None:
    run = load_run(short_run_directory(CONFIGS / "rimless_wheel.yaml", tmp_path / "run"))
    pose = run_poses(run).at(0)
    (spokes,) = pose.segments
    np.testing.assert_array_equal(spokes[0::2], np.repeat(pose.hip[None], len(spokes) // 2, axis=0))
    np.testing.assert_allclose(spokes[1::2], pose.foot_centres, atol=1e-15)
    np.testing.assert_allclose(np.hypot(*(spokes[1::2] - pose.hip).T), run.config.walker.leg_length, rtol=1e-12)


def test_a_body_off_the_legs_is_drawn_from_the_hip_to_its_centre_of_mass(tmp_path: Path) -> None:
    """A torso (a third body on the hip, no legs of its own) in compliant dynamics: grey, up to its mass."""
    config = yaml.safe_load((CONFIGS / "kneed_walker_compliant.yaml").read_text())
    description = config["walker"]["description"]
    description["bodies"].append({"name": "torso", "mass": 0.3, "inertia": 1e-3, "com": [0.0, 0.2]})
    description["joints"].append({"name": "waist", "parent": "thigh_1", "child": "torso"})
    path = tmp_path / "torso.yaml"
    path.write_text(yaml.safe_dump(config))
    run = load_run(short_run_directory(path, tmp_path / "run", "simulation.t_end=0.2"))
    poses = run_poses(run)
    torso = poses.skeleton.names.index("torso")
    assert poses.skeleton.leg_of[torso] == -1 and body_colour(poses.skeleton, torso) == OFF_LEG_COLOUR
    for i in (0, len(run.time) - 1):
        pose = poses.at(i)
        segment = pose.segments[torso]
        np.testing.assert_array_equal(segment[0], pose.hip)
        angle = pose.angles[torso]
        np.testing.assert_allclose(segment[1] - pose.hip, 0.2 * np.array([-np.sin(angle), np.cos(angle)]), atol=1e-15)


def test_a_rigid_walker_stands_on_a_ground_profile(tmp_path: Path) -> None:
    """Down a 5 mm step, one foot is on the profile at every sample (the hip carries the stance level)."""
    step_down = "ground.profile={kind: steps, steps: [{at: 0.2, height: -0.005}]}"
    config = CONFIGS / "round_foot_walker.yaml"
    run = load_run(short_run_directory(config, tmp_path / "run", "dynamics=rigid", step_down))
    assert len(run.steps["strike_time"]) >= 2 and run.hip[-1, 1] < run.hip[0, 1]  # strikes: the step was taken
    poses = run_poses(run)
    centres = np.array([poses.at(i).foot_centres for i in range(len(run.time))])
    vertices, ends = profile_arrays(run.config.ground.profile, run.config.ground.slope)
    ground = ground_height_at(centres[:, :, 0].ravel(), vertices, ends).reshape(centres.shape[:2])
    gap = centres[:, :, 1] - poses.skeleton.foot_radius - ground
    np.testing.assert_allclose(np.abs(gap).min(axis=1), 0.0, atol=1e-12)


SPACE_COMPLIANT = sorted((CONFIGS / "space").glob("*_compliant.yaml"))  # rigid walkers in space have no run yet
# a sagittal start for every walker in space (its own gait needs the rigid search: minutes); a fall is a result
SPACE_START = {"heading": 0.0, "bank": 0.0, "pitch": -0.2, "swing_angle": 0.4, "omega_x": 0.0, "omega_y": 0.5,
               "omega_z": 0.0, "swing_rate": -0.4}  # fmt: skip


# the fast tier draws one walker in space (the same drawing code serves all); the slow tier the others
SPACE_CASES = [pytest.param(c, id=c.stem, marks=[pytest.mark.slow] * (i > 0)) for i, c in enumerate(SPACE_COMPLIANT)]


@pytest.mark.parametrize("config", SPACE_CASES)
def test_every_bundled_walker_in_space_is_drawn_in_3d_and_animated(config: Path, tmp_path: Path) -> None:
    """A short run: its 3D poses put the hinge on the hip channel, the animation shows the sagittal and 3D views
    side by side, and the walker figure draws it."""
    start = "simulation.initial=" + repr(SPACE_START).replace("'", '"')
    run_dir = short_run_directory(config, tmp_path / "run", start, "simulation.t_end=0.3")
    run = load_run(run_dir)
    np.testing.assert_allclose(space_poses(run).hip, run.hip, rtol=0, atol=1e-12)
    out = tmp_path / "walk.gif"
    result = invoke("animate", str(run_dir), "--out", str(out), "--fps", "10", "--end", "0.2")
    assert result.exit_code == 0, result.output
    with Image.open(out) as image:
        assert image.n_frames == 3 and image.size == (800, 320)
    assert len(walker_figure(run).axes) == 2


def drawn_foot(config: Path, overrides: list[str], angles: list[float]) -> tuple[np.ndarray, np.ndarray, Skeleton]:
    """The first foot as WalkerPicture draws it (world frame, its sector's closing points to the centre dropped) with
    the walker's bodies at ``angles`` and its hip at the origin, the drawn arc's centre (world frame) and the
    skeleton."""
    sk = skeleton(describe(load_config(config, overrides)))
    pose = Poses.from_angles(sk, np.zeros(1), np.zeros((1, 2)), np.array([angles])).at(0)
    fig = Figure()
    picture = WalkerPicture(fig.add_subplot(), sk, 0.0)
    picture.place(pose)
    points = np.column_stack(picture.feet[0].get_data())
    return points[1:-1], points[0], sk


def test_a_foot_as_round_as_the_leg_is_drawn_as_a_foot_holding_its_contact_point() -> None:
    """A foot of radius 0.45 on a leg of 0.5 is drawn as the arc of it no wider than FOOT_HALF_WIDTH leg lengths on
    each side of its bottom (not 0.8 rad of it, 0.32 m on each side), the contact point below its centre on it at a
    stance angle of 0.3 rad."""
    arc, centre, sk = drawn_foot(CONFIGS / "round_foot_walker.yaml", ["walker.foot_radius=0.45"], [0.3, -0.3])
    radius, half = sk.foot_radius[0], sk.foot_half_angle[0]
    assert radius == 0.45 and half == pytest.approx(math.asin(FOOT_HALF_WIDTH * 0.5 / 0.45))
    np.testing.assert_allclose(np.hypot(*(arc - centre).T), radius, rtol=1e-12)
    across = (arc - centre) @ np.array([math.cos(0.3), math.sin(0.3)])  # along the leg's x axis, turned by 0.3 rad
    assert np.max(np.abs(across)) == pytest.approx(FOOT_HALF_WIDTH * 0.5, rel=1e-12)
    contact = centre - np.array([0.0, radius])  # straight below the centre on level ground
    gaps = np.hypot(*(arc - contact).T)
    assert gaps.min() < radius * 2 * half / 24  # within one of the arc's 24 pieces


def test_a_lateral_torus_foot_is_drawn_in_the_sagittal_view_as_its_tube() -> None:
    """The 3D kneed walker's feet, tori 1.5 m round sideways and 2 cm fore-aft: its sagittal view draws the 2 cm arc
    the foot rolls on fore-aft (its sagittal section), down at the foot's bottom, not a sector of the 1.5 m ring."""
    config = CONFIGS / "space" / "kneed_walker_3d.yaml"
    arc, centre, sk = drawn_foot(config, [], [0.0] * 4)
    assert sk.foot_radius[0] == pytest.approx(0.02) and sk.foot_half_angle[0] == FOOT_ARC_HALF_ANGLE
    np.testing.assert_allclose(np.hypot(*(arc - centre).T), 0.02, rtol=1e-12)
    assert np.min(arc[:, 1]) == pytest.approx(-load_config(config).walker.leg_length, abs=1e-12)


def test_the_3d_ground_is_the_house_ground_colour_as_the_planar_ground() -> None:
    """The slope plane under a walker in space has the planar ground's fill colour, unshaded (plot_surface's light
    source turned the pale grey into a dark one), on any view."""
    fig = Figure()
    ax3d = fig.add_subplot(projection="3d")
    surface = draw_space_ground(ax3d, 0.05, (-1.0, 1.0), (-0.5, 0.5))
    fig.canvas.draw()  # the 3D artists' colours are set at drawing
    np.testing.assert_allclose(surface.get_facecolor(), [to_rgba(GROUND_COLOUR)], rtol=0, atol=1e-12)
    planar = fig.add_subplot()
    draw_ground(planar, load_config(CONFIGS / "round_foot_walker.yaml"), -1.0, 1.0, 0.1)
    assert to_rgba(planar.patches[0].get_facecolor()) == to_rgba(GROUND_COLOUR)
