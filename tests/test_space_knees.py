"""The rigid walker in space with knees: its form from a description, its flow (compiled against the reference, the
energy it keeps), its knee and heel strikes (the momenta they keep), the planar kneed walker's gait, a run."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from biped_sim.config import config_from_dict, load_config
from biped_sim.config.space_description import SPACE_STATE_KEYS
from biped_sim.errors import ConfigError
from biped_sim.measure.space_pose import space_poses
from biped_sim.rigid import space_dynamics as dyn
from biped_sim.rigid.limit_cycle import StepFailedError, rigid_limit_cycle
from biped_sim.rigid.space_cycle import SpaceMap, scan, space_cycle_from, space_limit_cycle, space_walker_model
from biped_sim.rigid.space_kernels import KNEE_FREE, space_flow, space_params
from biped_sim.rigid.space_model import KNEE_ANGLE, KNEE_RATE, MIRROR, SpaceModel, pose
from biped_sim.simulate import simulate
from biped_sim.walkers.space_geometry import TO_SPATIAL
from tests.test_space_pose import drawn_lowest, one_sample

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
KNEED_3D = CONFIGS / "space" / "kneed_walker_3d.yaml"
KNEE = "walker.description.leg.joints.knee"


def kneed_in_space(hip_width: float = 0.0) -> dict[str, Any]:
    """Chen's kneed walker (configs/kneed_walker.yaml) as a walker in space: point feet, its point masses on the
    legs' axes, each body given an inertia about the leg's axis and the forward axis (0.01 kg m^2: moments the
    sagittal plane never turns, which keep the legs' spin about their common axis from being massless when they
    pass each other) and none about the lateral axis, the planar walker's."""
    inertia = {"xx": 0.01, "yy": 0.01, "zz": 0.0}  # in the body's frame: z' is the lateral axis
    thigh = {"name": "thigh", "mass": 0.5, "com": [0.0, -0.325], "inertia_tensor": inertia}
    shank = {"name": "shank", "mass": 0.05, "com": [0.0, -0.125], "inertia_tensor": inertia}
    knee = {"name": "knee", "parent": "thigh", "child": "shank", "at": [0.0, -0.5], "stops": [{"side": "upper"}]}
    foot = {"name": "foot", "body": "shank", "centre": [0.0, -0.5]}
    leg = {"bodies": [thigh, shank], "joints": [knee], "feet": [foot]}
    hip = {"name": "hip", "body": "thigh_1", "mass": 0.5, "lateral": -0.5 * hip_width}
    description = {"leg": leg, "hip": {"lateral": -hip_width}, "point_masses": [hip]}
    return {"dynamics": "rigid", "gravity": 9.81, "ground": {"slope": 0.0504},
            "walker": {"kind": "description", "description": description}}  # fmt: skip


def kneed_3d_rigid(extra: list[str] | None = None) -> Any:
    """configs/space/kneed_walker_3d.yaml in rigid dynamics (its contact and friction laws aside)."""
    overrides = [
        "dynamics=rigid",
        "formulation.kind=planar",
        "friction.spin_radius=0",
        "simulation.initial=rigid_limit_cycle",
    ]
    return load_config(KNEED_3D, overrides + (extra or []))


@pytest.fixture(scope="module")
def model() -> SpaceModel:
    return space_walker_model(kneed_3d_rigid())


def random_states(model: SpaceModel, n: int, seed: int) -> np.ndarray:
    """Seeded states near walking: attitude and angles within 0.3 rad, rates within 1.5 rad/s, a flexed knee."""
    rng = np.random.default_rng(seed)
    x = np.zeros((n, model.n_state))
    x[:, :4] = rng.uniform(-0.3, 0.3, (n, 4))
    x[:, 4:8] = rng.uniform(-1.5, 1.5, (n, 4))
    x[:, 8:10] = rng.uniform(-1.0, 1.0, (n, 2))
    x[:, KNEE_ANGLE], x[:, KNEE_RATE] = rng.uniform(0.0, 0.6, n), rng.uniform(-1.5, 1.5, n)
    return x


def test_the_3d_kneed_walker_takes_the_rigid_form_with_its_hip_masses_lumped_into_the_thighs(
    model: SpaceModel,
) -> None:
    knee = kneed_3d_rigid().walker.space.leg.knee
    assert knee is not None and knee.flexion == 1
    np.testing.assert_allclose(knee.at, [0.0, 0.0, -0.5])
    np.testing.assert_allclose(knee.com, [0.0, 0.0, -0.625])  # 0.125 below the knee
    thigh = kneed_3d_rigid().walker.space.leg
    assert thigh.mass == pytest.approx(0.75)  # 0.5 and the 0.25 kg hip mass on its top
    np.testing.assert_allclose(thigh.com, [0.0, 0.0, -0.5 * 0.325 / 0.75], atol=1e-15)
    frames = [part.frame for part in model.parts]
    assert frames == [0, 0, 1, 2] and model.swapped == [2, 3, 0, 1]
    np.testing.assert_allclose(model.knee.point, [0.0, -0.05, -0.5])  # the right leg's, 0.05 m to the right


@pytest.mark.parametrize(
    ("override", "message"),
    [
        (f"{KNEE}.stops=[{{side: upper, angle: 0.1}}]", f"{KNEE}.stops: the rigid model in space takes two legs"),
        (f"{KNEE}.axis=[1, 0, 0]", f"{KNEE}.axis: the rigid model in space takes two legs"),
    ],
)
def test_a_knee_the_rigid_model_lacks_is_refused_naming_the_field(override: str, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        kneed_3d_rigid([override])
    assert str(error.value).startswith(message)


def test_a_kneed_walker_in_space_starts_its_compliant_run_from_its_bodies_angles() -> None:
    with pytest.raises(ConfigError) as error:
        load_config(KNEED_3D, ["simulation.initial=rigid_limit_cycle"])
    assert str(error.value).startswith("simulation.initial: a kneed walker or a torso in space starts its compliant")


@pytest.mark.parametrize("free", [True, False])
def test_the_compiled_flow_is_the_reference_on_random_states(model: SpaceModel, free: bool) -> None:
    params = space_params(model)
    params[KNEE_FREE] = 1.0 if free else 0.0
    for x in random_states(model, 20, seed=2026120501):
        if not free:
            x[KNEE_RATE] = 0.0
        np.testing.assert_allclose(space_flow(params, x), dyn.flow(model, x, free), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("free", [True, False])
def test_energy_is_conserved_through_a_swing_with_the_knee_free_or_locked(model: SpaceModel, free: bool) -> None:
    x0 = random_states(model, 1, seed=2026120502)[0]
    x0[KNEE_RATE] *= free
    sol = solve_ivp(lambda t, x: dyn.flow(model, x, free), (0.0, 0.3), x0, method="DOP853", rtol=1e-13, atol=1e-13)
    energies = [dyn.energy(model, x) for x in sol.y.T]
    assert np.ptp(energies) < 1e-10 * abs(energies[0])
    assert np.ptp(sol.y[KNEE_ANGLE]) > (0.05 if free else -1.0) and (free or np.ptp(sol.y[KNEE_ANGLE]) == 0.0)


def _hinge_momentum(model: SpaceModel, x: np.ndarray, legs: list[int]) -> float:
    """The swing leg's (parts ``legs``) angular momentum about the hinge axis."""
    where = pose(model, x)
    motions = [dyn.part_motions(model, x)[k] for k in legs]
    return float(where.hinge @ dyn.angular_momentum(motions, where.origin))


def test_the_knee_strike_keeps_the_momenta_its_impulses_leave_and_loses_energy(model: SpaceModel) -> None:
    """The knee's lock acts at the knee and the stance foot: the whole walker's angular momentum about the contact
    point and the swing leg's about the hinge axis are kept, to rounding; kinetic energy is lost."""
    for x in random_states(model, 10, seed=2026120503):
        x[KNEE_ANGLE] = 0.0
        x[KNEE_RATE] = -abs(x[KNEE_RATE])  # straightening
        after = dyn.knee_strike(model, x)
        assert after[KNEE_RATE] == 0.0
        before_l = dyn.angular_momentum(dyn.part_motions(model, x), np.zeros(3))
        np.testing.assert_allclose(
            dyn.angular_momentum(dyn.part_motions(model, after), np.zeros(3)), before_l, atol=1e-13
        )
        assert _hinge_momentum(model, after, [2, 3]) == pytest.approx(_hinge_momentum(model, x, [2, 3]), abs=1e-13)
        assert dyn.energy(model, after) < dyn.energy(model, x)


def test_the_heel_strike_of_a_kneed_walker_keeps_the_momenta_about_the_new_contact_and_the_hinge(
    model: SpaceModel,
) -> None:
    x = random_states(model, 1, seed=2026120504)[0]
    x[3], x[KNEE_ANGLE], x[KNEE_RATE] = -0.5, 0.0, 0.0  # the swing foot ahead, the knee locked
    landing = dyn.swing_foot_point(model, x)
    before = dyn.part_motions(model, x)
    plus = dyn.strike(model, x)
    after = dyn.part_motions(model, plus)
    whole = MIRROR @ dyn.angular_momentum(before, landing)  # the model's frame is mirrored after the strike
    np.testing.assert_allclose(-dyn.angular_momentum(after, np.zeros(3)), whole, atol=1e-12)
    trailing = [before[k] for k in (0, 1)]
    axis, hinge = pose(model, x).hinge, pose(model, x).origin
    trailing_after = [after[k] for k in (2, 3)]
    new = pose(model, plus)
    assert -new.hinge @ dyn.angular_momentum(trailing_after, new.origin) == pytest.approx(
        -(MIRROR @ axis) @ (MIRROR @ dyn.angular_momentum(trailing, hinge)), abs=1e-12
    )
    assert plus[KNEE_ANGLE] == plus[KNEE_RATE] == 0.0


@pytest.mark.slow
def test_the_planar_kneed_walker_in_space_walks_its_planar_gait() -> None:
    """Chen's kneed walker written in space: the sagittal fixed point to 1e-9, the period to 1e-9 s, the sagittal
    multipliers to 1e-6 (Newton from the planar gait shifted 0.01 rad in pitch)."""
    planar = rigid_limit_cycle(load_config(CONFIGS / "kneed_walker.yaml"))
    point = planar.fixed_point
    angle, rate, swing = point["stance_thigh_angle"], point["stance_thigh_rate"], point["swing_thigh_rate"]
    expected = {"pitch": -angle, "omega_y": -rate, "swing_angle": 2 * angle, "swing_rate": rate - swing}
    guess = dict(expected, pitch=expected["pitch"] + 0.01)
    cycle = space_cycle_from(config_from_dict(kneed_in_space()), guess)
    assert cycle is not None and cycle.converged
    np.testing.assert_allclose([cycle.fixed_point[k] for k in expected], list(expected.values()), atol=1e-9)
    assert cycle.step_period == pytest.approx(planar.step_period, abs=1e-9)
    names = list(cycle.section_names)
    sagittal = [names.index(n) for n in ("pitch", "omega_y", "swing_rate")]
    multipliers = np.sort_complex(np.linalg.eigvals(cycle.jacobian[np.ix_(sagittal, sagittal)]))
    np.testing.assert_allclose(multipliers, np.sort_complex(planar.multipliers), atol=1e-6)


@pytest.mark.slow
def test_a_rigid_run_of_the_3d_kneed_walker_closes_its_energy_balance_through_knee_and_heel_strikes() -> None:
    config = kneed_3d_rigid(["simulation.t_end=1.5", "output.sample_rate=200"])
    result = simulate(copy.deepcopy(config))
    assert result.status == "walking" and len(result.trace.strike_time) >= 3
    energy = result.energy
    assert np.max(np.abs(energy.residual)) < 1e-9 * result.energy_scale
    knee = list(result.trajectory().state_names).index("swing_knee")
    assert np.max(result.state[:, knee]) > 0.1  # the swing knee bends
    assert len(result.trace.stop_losses) >= 3 and all(loss > 0.0 for _, loss in result.trace.stop_losses)


def degenerate_start() -> dict[str, Any]:
    """The kneed walker in space with no inertia at all (every mass on the legs' common axis when they pass each
    other: their spin about it unresisted) on a start whose legs come into line within the step."""
    data = kneed_in_space()
    for body in data["walker"]["description"]["leg"]["bodies"]:
        body["inertia_tensor"] = {"xx": 0.0, "yy": 0.0, "zz": 0.0}
    gait = {"pitch": -0.05, "swing_angle": 0.1, "omega_y": 3.13209195, "swing_rate": -1.87925517}
    data["simulation"] = {"t_end": 2.0, "initial": dict.fromkeys(SPACE_STATE_KEYS, 0.0) | gait}
    return data


def test_singular_equations_end_a_run_diverged_and_a_search_step_failed() -> None:
    config = config_from_dict(degenerate_start())
    result = simulate(copy.deepcopy(config))
    assert result.status == "diverged" and result.status_reason.startswith("the equations of motion became singular")
    step_map = SpaceMap(space_walker_model(config))
    with pytest.raises(StepFailedError, match="singular"):
        step_map.step(step_map.section.of_keys(config.simulation.initial))


@pytest.mark.slow
def test_the_3d_kneed_walker_made_rigid_finds_a_gait_without_a_guess_laterally_unstable() -> None:
    """The bundled 3D kneed walker in rigid dynamics: its gait found from its sagittal twin's (docs/guide/rigid.md's
    figures), turned off the downhill heading (rolling without slip leaves the stance foot's spin free) and
    unstable (a multiplier outside the unit circle)."""
    cycle = space_limit_cycle(kneed_3d_rigid())
    assert cycle.converged and cycle.start.startswith("the sagittal twin's gait")
    assert cycle.step_period == pytest.approx(0.46366, abs=1e-5)
    assert cycle.fixed_point["heading"] == pytest.approx(0.5392, abs=1e-4)
    assert max(abs(cycle.multipliers)) == pytest.approx(4.788, abs=1e-3)


@pytest.mark.slow
def test_nearly_singular_equations_end_a_step_stiff_not_a_hang() -> None:
    """The legs without inertia about their own axes (but the forward one): the step map's hinge phase ends with
    the legs in line, where their common spin is all but unresisted and the integrator's steps shrink without end;
    the phase gives up after ``MAX_ATTEMPTS`` steps (the step ``stiff``, the search's step failed)."""
    data = degenerate_start()
    for body in data["walker"]["description"]["leg"]["bodies"]:
        body["inertia_tensor"] = {"xx": 0.01, "yy": 0.0, "zz": 0.01}  # yy: about the leg's axis (y' up the leg)
    step_map = SpaceMap(space_walker_model(config_from_dict(data)))
    z = next(z for label, z in scan(step_map.model, step_map.section) if label.endswith("omega_y 3.132"))  # pitch -0.05
    with pytest.raises(StepFailedError, match="stiff"):
        step_map.step(z)


def test_a_bent_swing_knee_is_drawn_with_its_foot_where_the_model_puts_it(model: SpaceModel) -> None:
    """A rigid run's sample with the swing knee bent 0.5 rad: the swing foot drawn about the knee, its lowest drawn
    point the model's swing foot bottom (the dynamics' pose), to rounding; the shank's drawn length kept."""
    x = np.zeros(model.n_state)
    x[2], x[3], x[5], x[7], x[KNEE_ANGLE] = -0.2, 0.4, 1.0, -0.5, 0.5
    run = one_sample(kneed_3d_rigid(), "rigid", x, list(model.state_names))
    poses = space_poses(run)
    np.testing.assert_allclose(drawn_lowest(poses.feet[0])[1], TO_SPATIAL @ dyn.swing_foot_point(model, x), atol=1e-12)
    straight = space_poses(one_sample(kneed_3d_rigid(), "rigid", x * (np.arange(len(x)) != KNEE_ANGLE), []))
    shank = [np.linalg.norm(p.legs[0, 1, 4] - p.legs[0, 1, 3]) for p in (poses, straight)]
    assert shank[0] == pytest.approx(shank[1], abs=1e-12) and not np.allclose(
        poses.legs[0, 1, 4], straight.legs[0, 1, 4]
    )
