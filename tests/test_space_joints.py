"""The general description in space: joints about any body-fixed axis (a torso rolling on its spring), full inertia
tensors, centres of mass off the sagittal plane, mirrored legs, and the planar models' one-line refusals."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from biped_sim import config_from_dict, simulate
from biped_sim.errors import ConfigError
from biped_sim.measure.steps import StepTable
from biped_sim.multibody.dispatch import system_foot_contact
from biped_sim.multibody.hinge import HingeElements, hinge_angle
from biped_sim.multibody.spatial import IN_PLANE
from biped_sim.walkers import build_model

from .conftest import ROOT

TORSO = ROOT / "configs" / "torso_walker.yaml"
KNEED = ROOT / "configs" / "kneed_walker_compliant.yaml"
KNEED_3D = ROOT / "configs" / "space" / "kneed_walker_3d.yaml"
KNEED_3D_SETTLED = ROOT / "configs" / "space" / "kneed_walker_3d_settled.yaml"
TENSOR = {"xx": 0.012, "yy": 0.008, "zz": 0.01, "xy": 0.001, "xz": 0.0005, "yz": -0.0007}


def _rolling_torso(**changes: object) -> dict:
    """The torso walker whose torso rolls (a joint about x') on a spring and a damper, its full inertia tensor and
    its centre of mass 2 cm to the right, the spring stiffer than gravity's pull (10 N m/rad), started
    at a roll of 0.15 rad and 0.5 rad/s (its keys: the joint's)."""
    data = yaml.safe_load(TORSO.read_text())
    torso = data["walker"]["description"]["bodies"][0]
    torso.pop("inertia")
    torso.update(inertia_tensor=TENSOR, com_lateral=0.02)
    waist = data["walker"]["description"]["joints"][0]
    waist["axis"] = [1.0, 0.0, 0.0]
    waist["elements"] = [e for e in waist["elements"] if "against" not in e]
    data["simulation"]["initial"].update(torso_angle=0.15, torso_rate=0.5)
    next(p for p in data["walker"]["parameters"] if p["name"] == "torso_stiffness")["value"] = 10.0
    data["formulation"] = {"kind": "spatial"}
    for key, value in changes.items():
        data.setdefault(key, {}).update(value)  # type: ignore[call-overload]
    return data


@pytest.mark.slow  # 0.6 s at rtol 1e-10 in Euler parameters
def test_a_torso_rolling_on_its_spring_starts_at_its_keys_and_its_energy_audit_closes() -> None:
    """A swinging 3D tree: the roll joint's angle and rate start at the torso's keys, the torso rolls on its spring
    (both ways past its rest), and the audit (kinetic, potential, the spring's energy, the damper's and the
    contacts' work) closes to the integrator's tolerance over the first step."""
    result = simulate(
        config_from_dict(_rolling_torso(integrator={"rtol": 1e-10, "atol": 1e-12}, simulation={"t_end": 0.6}))
    )
    elements = result.model.system.elements
    assert isinstance(elements, HingeElements)
    start = hinge_angle(result.model.y0, elements.index, elements.frame, 0)
    assert start == pytest.approx((0.15, 0.5), abs=1e-12)
    roll = np.array([hinge_angle(y, elements.index, elements.frame, 0)[0] for y in result.run.y])
    assert roll.max() > 0.15 and roll.min() < -0.03  # swinging on its spring, past its rest
    assert result.summary["energy_dissipated"]["elements"] > 0.0
    assert np.max(np.abs(result.energy.residual)) < 1e-8 * np.max(np.abs(result.energy.kinetic))


def test_the_planar_models_refuse_a_joint_about_another_axis_naming_it() -> None:
    for changes in ({"formulation": {"kind": "planar"}}, {"formulation": {"kind": "minimal"}}):
        with pytest.raises(ConfigError, match=r"^walker\.description\.joints\.waist\.axis: only in space") as error:
            config_from_dict(_rolling_torso(**changes))
        assert "\n" not in str(error.value)


def test_a_joint_about_another_axis_above_the_stance_foot_starts_at_zero() -> None:
    """Knees that roll (about x'): the swing knee starts at its keys' angle, the stance knee (above the stance foot,
    which its turn would lift off the ground) at 0, one line naming the key otherwise."""
    data = yaml.safe_load(KNEED.read_text())
    for joint in data["walker"]["description"]["joints"][1:]:
        joint["axis"] = [1.0, 0.0, 0.0]
    initial = data["simulation"]["initial"]
    initial.update(stance_shank_angle=0.0, stance_shank_rate=0.0, swing_shank_angle=0.1, swing_shank_rate=0.2)
    data["formulation"] = {"kind": "spatial"}
    model = build_model(config_from_dict(data))
    stops = model.system.stops
    knees = [hinge_angle(model.y0, stops.index, stops.frame, s) for s in range(2)]
    assert knees == [pytest.approx((0.0, 0.0), abs=1e-12), pytest.approx((0.1, 0.2), abs=1e-12)]
    initial.update(stance_shank_angle=0.1)
    with pytest.raises(ConfigError, match=r"^simulation\.initial\.stance_shank_angle: a joint about another axis"):
        build_model(config_from_dict(data))


def test_a_mirrored_leg_mirrors_its_centre_of_mass_tensor_and_axes() -> None:
    """The second leg is the first's image across the sagittal plane: com_lateral, the tensor's xz and yz products
    and the axes' x' and y' components negated (a turn's sense), the rest kept."""
    data = yaml.safe_load(TORSO.read_text())
    leg = data["walker"]["description"]["leg"]
    leg["bodies"][0].pop("inertia")
    leg["bodies"].append({"name": "arm", "mass": 0.2, "inertia_tensor": TENSOR, "com_lateral": 0.05})
    leg["joints"] = [{"name": "shoulder", "parent": "leg", "child": "arm", "axis": [0.6, 0.0, 0.8]}]
    leg["bodies"][0]["inertia_tensor"] = TENSOR
    data["walker"]["description"]["leg"]["feet"][0]["lateral"] = 0.01
    data["formulation"] = {"kind": "spatial"}
    keys = [f"{s}_{r}_{w}" for s in ("stance", "swing") for r in ("leg", "arm") for w in ("angle", "rate")]
    data["simulation"]["initial"] = dict.fromkeys(keys, 0.0)
    description = config_from_dict(data).walker.description
    bodies = {b.name: b for b in description.bodies}
    assert (bodies["arm_1"].com_lateral, bodies["arm_2"].com_lateral) == (0.05, -0.05)
    first, second = bodies["arm_1"].inertia_tensor.matrix(), bodies["arm_2"].inertia_tensor.matrix()
    assert second == pytest.approx(np.diag([1, 1, -1]) @ first @ np.diag([1, 1, -1]))
    joints = {j.name: j for j in description.joints}
    assert (joints["shoulder_1"].axis, joints["shoulder_2"].axis) == ((0.6, 0.0, 0.8), (-0.6, -0.0, 0.8))


def _kneed_3d(**foot: object) -> dict:
    """The 3D kneed walker (configs/space/kneed_walker_3d.yaml), its foot changed by ``foot``."""
    data = yaml.safe_load(KNEED_3D.read_text())
    data["walker"]["description"]["leg"]["feet"][0].update(foot)
    return data


@pytest.mark.parametrize(
    "foot",
    [
        {},  # the bundled torus in the lateral plane: 2 cm fore-aft, 1.5 m sideways
        {"plane": "sagittal", "centre": [0.0, -0.45], "radius": 0.03, "tube": 0.02},
        {"shape": "sphere", "centre": [0.0, -0.48], "radius": 0.02, "tube": 0.0, "plane": "sagittal"},
    ],
)
def test_a_round_foot_in_space_starts_sunk_by_the_static_penetration(foot: dict) -> None:
    """Torus (both planes) and sphere feet are the spatial formulation's shapes; the walker starts on its stance
    foot's lowest point sunk by exactly the static penetration (their sagittal sections are arcs), its legs the
    hip width apart, free in roll and yaw (no planar joint)."""
    model = build_model(config_from_dict(_kneed_3d(**foot)))
    delta = system_foot_contact(model.y0, model.system, 0)[0]
    assert delta == pytest.approx(model.meta["static_penetration"], rel=1e-9)
    assert IN_PLANE not in model.system.con_type
    assert model.system.con_vecs[0, 2] == pytest.approx(-0.1)  # the hip joint's point on thigh_1: the hip width


def test_an_ellipsoid_foot_is_the_formulations_quadric_in_the_body_frame() -> None:
    model = build_model(config_from_dict(_kneed_3d(shape="ellipsoid", plane="sagittal", centre=[0.0, -0.47],
                                                   radius=0.0, tube=0.0, axes=[0.02, 0.03, 0.1])))  # fmt: skip
    assert np.diag(model.system.foot_quadric[0]) == pytest.approx([0.0004, 0.0009, 0.01])
    assert model.leg_length == pytest.approx(1.0)  # the hip to the bottom of its y' semi-axis


def test_the_planar_models_refuse_a_foot_of_another_shape_naming_it() -> None:
    data = _kneed_3d()
    data["formulation"] = {"kind": "planar"}
    with pytest.raises(ConfigError, match=r"^walker\.description\.leg\.feet\.foot\.shape: only in space") as error:
        config_from_dict(data)
    assert "\n" not in str(error.value)


@pytest.mark.slow  # 12 s of a walk in Euler parameters (BDF: 340,000 right-hand sides)
def test_the_3d_kneed_walker_walks_twenty_steps_at_a_steady_heading() -> None:
    """Chen's kneed walker with a 0.1 m hip width on lateral torus feet and spin friction walks 12 s without
    falling, left and right feet in turn, its step width, sway, heading and bank in the step table. Its heading
    holds: the mean heading of consecutive steps moves by less than 0.01 rad a step over the second half (measured
    +0.0014; without spin friction -0.042, and the walker falls at 14.3 s), and its right and left steps are
    alike: periods within 2 % (0.5229 and 0.5261 s over the last four of each), lengths within 5 % (0.468 and
    0.453 m). The heading at strike alternates (-0.147 at the right foot's, +0.048 at the left's): the whole walker
    yaws to and fro, its four bodies' headings one (the hinge's: its legs cannot yaw apart)."""
    result = simulate(config_from_dict(yaml.safe_load(KNEED_3D.read_text())))
    assert result.status == "walking" and result.summary["n_steps"] >= 20
    steps = result.steps
    assert list(steps.foot[:20]) == [1, 0] * 10
    for column in (steps.width, steps.sway, steps.heading, steps.bank):
        assert np.all(np.isfinite(column[:-1]))
    assert np.all(steps.width[:-1] > 0.0) and np.max(np.abs(steps.bank)) < 0.1
    pair_heading = (steps.heading[1:] + steps.heading[:-1]) / 2.0
    late = pair_heading[len(pair_heading) // 2 :]
    assert abs(np.polyfit(np.arange(late.size), late, 1)[0]) < 0.01
    for column, tolerance in ((steps.period, 0.02), (steps.length, 0.05)):
        right, left = _right_and_left(steps, column)
        assert abs(left - right) < tolerance * right
    assert _unsettled(steps)[0] > 1e-3  # not settled: its periods still wander (0.035 s over the last 8 strikes)
    right, left = _right_and_left(steps, steps.heading)
    assert right < -0.1 and left > 0.0
    yaw = result.attitude["yaw"]
    assert np.max(np.abs(yaw - yaw[:, :1])) < 1e-8


def _right_and_left(steps: StepTable, column: np.ndarray) -> tuple[float, float]:
    """A step table's column averaged over the last four complete steps of the right foot (foot 0, the written
    leg's) and of the left."""
    right, left = (column[:-1][steps.foot[:-1] == foot][-4:].mean() for foot in (0, 1))
    return float(right), float(left)


def _unsettled(steps: StepTable, last: int = 8) -> tuple[float, float]:
    """How far a walk is from a settled gait over its last ``last`` complete steps: the largest change of a step's
    period from the step two before (left and right steps may differ: a period-two gait repeats every other step)
    and the largest move of the mean heading of two consecutive steps from one pair to the next."""
    period, heading = steps.period[:-1], steps.heading[:-1]  # the last step is cut by t_end
    pair_heading = (heading[1:] + heading[:-1]) / 2.0
    period_change = np.max(np.abs(period[-last:] - period[-last - 2 : -2]))
    return float(period_change), float(np.max(np.abs(np.diff(pair_heading)[-last:])))


@pytest.mark.slow  # 35 s of a walk (BDF: some 900,000 right-hand sides)
def test_the_retuned_3d_kneed_walker_settles_into_a_repeating_gait() -> None:
    """configs/space/kneed_walker_3d_settled.yaml (hips 0.065 m apart, feet 1.65 m round sideways, r_s = 9 mm, slope
    0.0557) settles: over the last 8 strikes of 35 s each step's period is within 1 ms of the step two before and the
    mean heading of consecutive steps moves by less than 1 mrad a step (measured 0.40 ms and 0.70 mrad; the bundled
    walker at 35 s: 9.6 ms and 2.0 mrad, settled only after 138 strikes, 73 s). Its left and right steps are alike
    (periods 0.5600 and 0.5603 s) and its mean heading near the fall line (-0.017 rad, returning by 3 % a step)."""
    data = yaml.safe_load(KNEED_3D_SETTLED.read_text())
    data["simulation"]["t_end"] = 35.0
    result = simulate(config_from_dict(data))
    assert result.status == "walking" and list(result.steps.foot[:60]) == [1, 0] * 30
    period_change, heading_move = _unsettled(result.steps)
    assert period_change < 1e-3 and heading_move < 1e-3
    steps = result.steps
    right, left = _right_and_left(steps, steps.period)
    assert abs(left - right) < 1e-3
    assert abs(steps.heading[-3] + steps.heading[-2]) / 2.0 < 0.03


@pytest.mark.slow  # dopri5's 1.2 s of walk: 700,000 right-hand sides
def test_the_3d_kneed_walker_s_stiff_method_strikes_where_dopri5_does() -> None:
    """The bundled walker integrates by BDF (its friction's regularisation makes the walk stiff); dopri5 at the same
    tolerances strikes at the same times over its first two steps, to 1e-6 s, and in the same state to 1e-5."""
    data = yaml.safe_load(KNEED_3D.read_text())
    data["simulation"]["t_end"] = 1.2
    runs = {}
    for method in ("bdf", "dopri5"):
        data["integrator"]["method"] = method
        runs[method] = simulate(config_from_dict(data))
    stiff, explicit = runs["bdf"], runs["dopri5"]
    assert stiff.status == explicit.status == "walking" and len(stiff.steps.period) == len(explicit.steps.period) >= 2
    np.testing.assert_allclose(stiff.steps.strike_time, explicit.steps.strike_time, rtol=0.0, atol=1e-6)
    for column in ("stance_angle", "swing_angle", "heading", "bank", "sway"):
        np.testing.assert_allclose(getattr(stiff.steps, column), getattr(explicit.steps, column), rtol=0.0, atol=1e-5)


@pytest.mark.slow  # 1.5 s of walk by BDF
def test_a_stiff_run_with_knees_at_their_stops_holds_those_events_and_walks_on(monkeypatch: pytest.MonkeyPatch) -> None:
    """With the hips 0.12 m apart the knees' stop events sit within round-off of zero after a restart, and scipy's root
    search found no sign change where its step saw one: the run raised a traceback. The segment is now retried with
    those events held on their side (the knee stops' rows), and the run walks."""
    from biped_sim.integrate import stiff

    held: list[np.ndarray] = []
    retry = stiff.WatchedEvents.retry_holding

    def noted_retry(watched: stiff.WatchedEvents, error: ValueError, y: np.ndarray) -> bool:
        again = retry(watched, error, y)
        held.append(watched.held.copy())
        return again

    monkeypatch.setattr(stiff.WatchedEvents, "retry_holding", noted_retry)
    data = yaml.safe_load(KNEED_3D.read_text())
    data["walker"]["parameters"][0]["value"] = 0.12  # hip_width
    data["simulation"]["t_end"] = 1.5
    result = simulate(config_from_dict(data))
    assert result.status == "walking" and result.summary["n_steps"] >= 2
    assert held and all(list(np.flatnonzero(h)) == [4, 5] for h in held)  # the two knee stops' events
