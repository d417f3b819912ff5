"""The rigid walker in space with a torso: its form from a description (and what it refuses), its flow (compiled
against the reference, the energy and the dampers' work it keeps), its heel strike (the momenta it keeps), the planar
torso walkers' gaits written in space, a run's energy balance and drawing."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from scipy.integrate import solve_ivp

from biped_sim.bench.mjcf import space_mjcf
from biped_sim.config import config_from_dict, load_config
from biped_sim.errors import ConfigError
from biped_sim.measure.space_pose import space_poses
from biped_sim.rigid import space_dynamics as dyn
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.space_cycle import space_cycle_from, space_walker_model
from biped_sim.rigid.space_kernels import KNEE_FREE, space_flow, space_params
from biped_sim.rigid.space_model import KNEE_ANGLE, KNEE_RATE, MIRROR, TORSO_FRAME, SpaceModel, pose
from biped_sim.simulate import simulate
from biped_sim.walkers.space_geometry import TO_SPATIAL
from tests.test_space_pose import one_sample

ROOT = Path(__file__).resolve().parents[1]
TORSO_WALKER = ROOT / "configs" / "torso_walker.yaml"
KNEED_TORSO = ROOT / "tests" / "data" / "kneed_torso.yaml"
WAIST = "walker.description.joints.waist"


def in_space(path: Path) -> dict[str, Any]:
    """A planar torso walker (its file) written in space, rigid: each body given an inertia about its own axis and
    the forward axis (0.01 kg m^2: moments the sagittal plane never turns) beside its planar one about the lateral
    axis; its contact, friction and integrator (compliant dynamics') dropped."""
    data = yaml.safe_load(path.read_text())
    description = data["walker"]["description"]
    for body in description["leg"]["bodies"] + description["bodies"]:
        body["inertia_tensor"] = {"xx": 0.01, "yy": 0.01, "zz": body.pop("inertia")}  # z' the lateral axis
    for key in ("contact", "friction", "integrator", "formulation"):
        data.pop(key, None)
    data["dynamics"], data["simulation"]["initial"] = "rigid", "rigid_limit_cycle"
    return data


def with_waist(data: dict[str, Any], **changes: Any) -> dict[str, Any]:
    """``data`` with its torso's joint changed."""
    data = copy.deepcopy(data)
    waist = data["walker"]["description"]["joints"][0]
    waist.update(changes)
    return data


@pytest.fixture(scope="module")
def model() -> SpaceModel:
    return space_walker_model(config_from_dict(in_space(TORSO_WALKER)))


@pytest.fixture(scope="module")
def kneed() -> SpaceModel:
    return space_walker_model(config_from_dict(in_space(KNEED_TORSO)))


def random_states(model: SpaceModel, n: int, seed: int) -> np.ndarray:
    """Seeded states near walking: attitude and angles within 0.3 rad, rates within 1.5 rad/s, a torso within
    0.5 rad and 2 rad/s, a flexed knee; the elements' work 0."""
    rng = np.random.default_rng(seed)
    x = np.zeros((n, model.n_state))
    x[:, :4] = rng.uniform(-0.3, 0.3, (n, 4))
    x[:, 4:8] = rng.uniform(-1.5, 1.5, (n, 4))
    x[:, 8:10] = rng.uniform(-1.0, 1.0, (n, 2))
    x[:, model.torso_angle], x[:, model.torso_angle + 1] = rng.uniform(-0.5, 0.5, n), rng.uniform(-2.0, 2.0, n)
    if model.knee:
        x[:, KNEE_ANGLE], x[:, KNEE_RATE] = rng.uniform(0.0, 0.6, n), rng.uniform(-1.5, 1.5, n)
    return x


def test_the_torso_walker_written_in_space_takes_the_rigid_form_with_its_elements_paired(model: SpaceModel) -> None:
    torso = config_from_dict(in_space(TORSO_WALKER)).walker.space.torso
    assert torso is not None and torso.mass == 1.5 and torso.com == (0.0, 0.1)
    assert sorted((e.law, e.stiffness, e.damping) for e in torso.elements) == [
        ("linear_damper", 0.0, 0.15),
        ("linear_spring", 2.5, 0.0),
    ]
    assert [part.frame for part in model.parts] == [0, 1, 0, TORSO_FRAME] and model.swapped == [1, 0, 2, 3]
    assert model.state_names[model.torso_angle :] == ("torso_angle", "torso_rate", "element_work")


def _drop_element(data: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    data["walker"]["description"]["joints"][0]["elements"].pop(1)  # spring_2, against the second leg
    return data


def _grounded(data: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    for element in data["walker"]["description"]["joints"][0]["elements"]:
        element["against"] = "ground"
    return data


def _leaning(data: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    data["walker"]["description"]["bodies"][0]["com_lateral"] = 0.05
    return data


def _many_springs(data: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    data["walker"]["description"]["joints"][0]["elements"] = [
        {"name": f"spring_{k}_{leg}", "law": "linear_spring", "stiffness": 1.0, "against": leg}
        for k in range(9)
        for leg in ("leg_1", "leg_2")
    ]
    return data


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (_drop_element, f"{WAIST}.elements:"),
        (_many_springs, f"{WAIST}.elements:"),
        (_grounded, f"{WAIST}.elements.spring_1.against:"),
        (_leaning, "walker.description.bodies.torso.com_lateral:"),
        (lambda d: with_waist(d, at=[0.0, 0.1]), f"{WAIST}.at:"),
        (lambda d: with_waist(d, stops=[{"side": "upper", "angle": 0.5}]), f"{WAIST}.stops:"),
    ],
)
def test_a_torso_the_rigid_model_lacks_is_refused_naming_the_field(change: Any, field: str) -> None:
    with pytest.raises(ConfigError) as error:
        config_from_dict(change(in_space(TORSO_WALKER)))
    assert str(error.value).startswith(field) and "the rigid model in space" in str(error.value)


def test_a_torso_in_space_is_not_written_as_mjcf_silently_without_it() -> None:
    with pytest.raises(ConfigError, match=r"walker\.description\.bodies: a walker in space is written as MJCF without"):
        space_mjcf(config_from_dict(in_space(TORSO_WALKER)))


def test_a_torso_in_space_starts_its_compliant_run_from_its_bodies_angles() -> None:
    data = in_space(TORSO_WALKER) | {"dynamics": "compliant", "formulation": {"kind": "spatial"}}
    with pytest.raises(ConfigError) as error:
        config_from_dict(data)
    assert str(error.value).startswith("simulation.initial: a kneed walker or a torso in space starts its compliant")


@pytest.mark.parametrize("free", [True, False])
def test_the_compiled_flow_is_the_reference_on_random_states(kneed: SpaceModel, model: SpaceModel, free: bool) -> None:
    """The torso alone and with knees (free or locked), 20 seeded states each."""
    for walker in (model, kneed):
        params = space_params(walker)
        params[KNEE_FREE] = 1.0 if free and walker.knee else 0.0
        for x in random_states(walker, 20, seed=2026120511):
            if walker.knee and not free:
                x[KNEE_RATE] = 0.0
            reference = dyn.flow(walker, x, free)
            np.testing.assert_allclose(space_flow(params, x), reference, rtol=1e-12, atol=1e-12)


def _springs_only(data: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(data)
    elements = data["walker"]["description"]["joints"][0]["elements"]
    elements[:] = [e for e in elements if e["law"] == "linear_spring"]
    return data


@pytest.mark.parametrize("dampers", [False, True])
def test_energy_and_the_dampers_work_balance_through_a_swing(kneed: SpaceModel, dampers: bool) -> None:
    """Springs alone: the energy (the springs' in it) is kept to 1e-10 through a swing with the knee free; with the
    dampers, the energy plus their integrated work is, and the work grows."""
    walker = kneed if dampers else space_walker_model(config_from_dict(_springs_only(in_space(KNEED_TORSO))))
    x0 = random_states(walker, 1, seed=2026120512)[0]
    sol = solve_ivp(lambda t, x: dyn.flow(walker, x, True), (0.0, 0.3), x0, method="DOP853", rtol=1e-13, atol=1e-13)
    work = sol.y[walker.torso_angle + 2]
    balance = [dyn.energy(walker, x) + w for x, w in zip(sol.y.T, work, strict=True)]
    assert np.ptp(balance) < 1e-10 * abs(balance[0])
    assert (work[-1] > 1e-3) if dampers else (work[-1] == 0.0)
    assert np.ptp(sol.y[walker.torso_angle]) > 0.05 and np.ptp(sol.y[KNEE_ANGLE]) > 0.05


def _about_hinge(walker: SpaceModel, x: np.ndarray, parts: list[int]) -> float:
    """Parts ``parts``'s angular momentum about the hinge axis through the hinge's midpoint."""
    where = pose(walker, x)
    motions = [dyn.part_motions(walker, x)[k] for k in parts]
    return float(where.hinge @ dyn.angular_momentum(motions, where.origin))


def test_the_heel_strike_keeps_the_momenta_about_the_new_contact_and_the_hinge(kneed: SpaceModel) -> None:
    """The whole walker's angular momentum about the landing foot, the trailing leg's and the torso's about the hinge
    axis (the torso's joint takes no impulse but along it), to rounding; the torso keeps its attitude."""
    for x in random_states(kneed, 5, seed=2026120513):
        x[3], x[KNEE_ANGLE], x[KNEE_RATE] = -0.5, 0.0, 0.0  # the swing foot ahead, the knee locked
        landing = dyn.swing_foot_point(kneed, x)
        plus = dyn.strike(kneed, x)
        whole = MIRROR @ dyn.angular_momentum(dyn.part_motions(kneed, x), landing)
        np.testing.assert_allclose(-dyn.angular_momentum(dyn.part_motions(kneed, plus), np.zeros(3)), whole, atol=1e-12)
        for old, new in (([0, 1], [2, 3]), ([5], [5])):  # the trailing leg (the new swing leg), the torso
            assert -_about_hinge(kneed, plus, new) == pytest.approx(-_about_hinge(kneed, x, old), abs=1e-12)
        turned = [pose(kneed, y).rotations[TORSO_FRAME] for y in (x, plus)]
        np.testing.assert_allclose(turned[1], MIRROR @ turned[0] @ MIRROR, atol=1e-12)


def planar_expected(point: dict[str, float], leg: str) -> dict[str, float]:
    """The section point in space of a planar fixed point (``leg``: its legs' keys' stem, 'stance' or
    'stance_thigh'): pitch and rates about y are minus the planar angles; the hinge and torso angles are from the
    stance leg."""
    stance, rate = point[f"{leg}_angle"], point[f"{leg}_rate"]
    swing = leg.replace("stance", "swing")
    return {
        "pitch": -stance, "omega_y": -rate, "swing_angle": stance - point[f"{swing}_angle"],
        "swing_rate": rate - point[f"{swing}_rate"], "torso_angle": stance - point["torso_angle"],
        "torso_rate": rate - point["torso_rate"],
    }  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize(("path", "leg"), [(TORSO_WALKER, "stance"), (KNEED_TORSO, "stance_thigh")])
def test_a_planar_torso_walker_in_space_walks_its_planar_gait(path: Path, leg: str) -> None:
    """The bundled torso walker and the kneed one with a torso written in space: the sagittal fixed point to 1e-9,
    the period to 1e-9 s, the sagittal multipliers to 1e-6 (Newton from the planar gait shifted 0.01 rad in pitch)."""
    overrides = ["dynamics=rigid"] if path == TORSO_WALKER else []
    planar = rigid_limit_cycle(load_config(path, overrides))
    expected = planar_expected(planar.fixed_point, leg)
    cycle = space_cycle_from(config_from_dict(in_space(path)), dict(expected, pitch=expected["pitch"] + 0.01))
    assert cycle is not None and cycle.converged
    np.testing.assert_allclose([cycle.fixed_point[k] for k in expected], list(expected.values()), atol=1e-9)
    assert cycle.step_period == pytest.approx(planar.step_period, abs=1e-9)
    names = list(cycle.section_names)
    sagittal = [names.index(n) for n in ("pitch", "omega_y", "swing_rate", "torso_angle", "torso_rate")]
    multipliers = np.sort_complex(np.linalg.eigvals(cycle.jacobian[np.ix_(sagittal, sagittal)]))
    np.testing.assert_allclose(multipliers, np.sort_complex(planar.multipliers), atol=1e-6)


@pytest.mark.slow
def test_a_rigid_run_with_a_torso_closes_its_energy_balance_with_the_dampers_work() -> None:
    """The kneed torso walker in space run from its planar gait's start: knee strikes, heel strikes and the
    dampers' work in the balance, to 1e-9 m g l."""
    planar = rigid_limit_cycle(load_config(KNEED_TORSO))
    data = in_space(KNEED_TORSO)
    start = planar_expected(planar.fixed_point, "stance_thigh")
    lateral = {"heading": 0.0, "bank": 0.0, "omega_x": 0.0, "omega_z": 0.0}
    data["simulation"] |= {"t_end": 1.5, "initial": lateral | start}
    result = simulate(config_from_dict(data))
    assert result.status == "walking" and len(result.trace.strike_time) >= 2
    energy = result.energy
    assert np.max(np.abs(energy.residual)) < 1e-9 * result.energy_scale
    assert energy.dissipated_elements[-1] > 0.0 and len(result.trace.stop_losses) >= 2
    names = list(result.trajectory().state_names)
    assert np.ptp(result.state[:, names.index("torso_angle")]) > 0.05


def test_a_torso_is_drawn_from_the_hinge_to_its_centre_of_mass(model: SpaceModel) -> None:
    x = np.zeros(model.n_state)
    x[2], x[3], x[5], x[7], x[model.torso_angle] = -0.2, 0.4, 1.0, -0.5, 0.3
    config = config_from_dict(in_space(TORSO_WALKER))
    poses = space_poses(one_sample(config, "rigid", x, list(model.state_names)))
    where = pose(model, x)
    expected = [where.origin, where.point(TORSO_FRAME, model.parts[-1].com)]
    np.testing.assert_allclose(poses.torso[0], np.array(expected) @ TO_SPATIAL.T, atol=1e-12)


def test_a_push_on_the_hip_with_the_knee_free_and_bent_keeps_the_momenta_its_joints_leave(kneed: SpaceModel) -> None:
    """An impulse p on the hinge's midpoint, the swing knee free and bent: the walker's angular momentum about the
    contact point changes by r_hip x p (the ground's impulse acts there), the swing shank's about the knee axis and
    the torso's about the hinge axis are kept (their joints take no impulse about their axes), to rounding."""
    rng = np.random.default_rng(2026120514)
    for x in random_states(kneed, 5, seed=2026120515):
        impulse = rng.uniform(-0.5, 0.5, 3)
        after, _ = dyn.hip_push(kneed, x, impulse, knee_free=True)
        where = pose(kneed, x)
        change = dyn.angular_momentum(dyn.part_motions(kneed, after), np.zeros(3))
        change -= dyn.angular_momentum(dyn.part_motions(kneed, x), np.zeros(3))
        np.testing.assert_allclose(change, np.cross(where.origin, impulse), atol=1e-12)
        knee = where.point(1, kneed.knee.point)
        for parts, about in (([3], knee), ([5], where.origin)):  # the swing shank, the torso
            momenta = [dyn.angular_momentum([dyn.part_motions(kneed, y)[k] for k in parts], about) for y in (x, after)]
            assert where.hinge @ momenta[1] == pytest.approx(where.hinge @ momenta[0], abs=1e-12)
        assert after[KNEE_RATE] != x[KNEE_RATE]  # the free knee takes part of the push
