"""Joint stops, springs and dampers in the spatial formulation (multibody.hinge): a revolute joint's angle read
from Euler parameters, and planar walkers with knees, latches and a torso on hip springs lifted into space."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from biped_sim import config_from_dict, load_config, simulate
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.multibody.euler_parameters import e_mul, g_mul
from biped_sim.multibody.hinge import HingeElements, HingeStops, hinge_angle, hinge_couple, hinge_index
from biped_sim.multibody.spatial import IN_PLANE
from biped_sim.walkers import build_model

from .conftest import ROOT

KNEED = ROOT / "configs" / "kneed_walker_compliant.yaml"
TORSO = ROOT / "configs" / "torso_walker.yaml"
TIGHT = ("integrator.rtol=1e-10", "integrator.atol=1e-12")


def _attitude(axis: np.ndarray, angle: float) -> np.ndarray:
    """Unit Euler parameters of a turn by ``angle`` about the unit ``axis``."""
    return np.array([math.cos(angle / 2), *(math.sin(angle / 2) * axis)])


def _two_bodies(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """y of two bodies joined by a revolute joint about the child's axis a_c, the hinge frame (a_c, u_c, u_p) and
    the joint angle: the parent at a random attitude, the child turned from it by theta about the axis."""
    rng = np.random.default_rng(seed)
    a_c = rng.normal(size=3)
    a_c /= np.linalg.norm(a_c)
    u_c = np.cross(a_c, rng.normal(size=3))
    u_c /= np.linalg.norm(u_c)
    p_p = rng.normal(size=4)
    p_p /= np.linalg.norm(p_p)
    theta = rng.uniform(-2.5, 2.5)
    # the parent's frame: the child at theta = 0 has the parent's attitude composed with a fixed turn r0
    p_0 = _attitude(np.array([0.0, 0.0, 1.0]), rng.uniform(-1, 1))
    p_c = _compose(_compose(p_p, p_0), _attitude(a_c, theta))
    u_p = _rotate(p_0, u_c)
    y = np.zeros(28)
    y[3:7], y[10:14] = p_c, p_p
    y[17:21], y[24:28] = rng.normal(size=4), rng.normal(size=4)
    for k in (17, 24):  # rates tangent to the unit sphere
        p = y[k - 14 : k - 10]
        y[k : k + 4] -= p * (p @ y[k : k + 4])
    return y, np.array([[*a_c, *u_c, *u_p]]), np.array([hinge_index(0, 1, 2)]), theta


def _compose(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The Euler parameters of the turn q followed by p (the quaternion product p q)."""
    return np.array([p[0] * q[0] - p[1:] @ q[1:], *(p[0] * q[1:] + q[0] * p[1:] + np.cross(p[1:], q[1:]))])


def _rotate(p: np.ndarray, s: np.ndarray) -> np.ndarray:
    """A(p) s."""
    return _compose(_compose(p, np.array([0.0, *s])), p * [1, -1, -1, -1])[1:]


@pytest.mark.parametrize("seed", range(4))
def test_the_hinge_angle_is_the_turn_about_the_axis_and_its_couple_does_its_work(seed: int) -> None:
    """theta from two attitudes is the turn between them, thetadot its rate along the axis, and the couple's
    generalized forces on both bodies' Euler parameters have the power tau thetadot."""
    y, frame, index, theta = _two_bodies(seed)
    angle, rate = hinge_angle(y, index, frame, 0)
    assert angle == pytest.approx(theta, abs=1e-12)
    omega = [2 * np.array(e_mul(tuple(y[k - 14 : k - 10]), tuple(y[k : k + 4]))) for k in (17, 24)]
    axis = _rotate(y[3:7], frame[0, :3])
    assert rate == pytest.approx((omega[0] - omega[1]) @ axis, abs=1e-12)
    force = np.zeros(28)
    hinge_couple(y, index, frame, 0, 0.7, force)
    assert force[:14] @ y[14:] == pytest.approx(0.7 * rate, abs=1e-12)
    body = 2 * np.array(g_mul(tuple(y[3:7]), tuple(y[17:21])))  # the child's body-frame rate: the moment along a_c
    assert force[3:7] @ y[17:21] == pytest.approx(0.7 * body @ frame[0, :3], abs=1e-12)


def _lifted(path: object, t_end: float, work: str) -> tuple[object, object]:
    """A bundled planar walker's compliant run in the planar and in the spatial formulation: the same steps, the
    planar step times to 1e-9 s, the joints' dissipation ``work`` alike and positive, the spatial audit closed."""
    planar, spatial = (
        simulate(load_config(path, [f"simulation.t_end={t_end}", *TIGHT, f"formulation.kind={kind}"]))
        for kind in ("planar", "spatial")
    )
    assert planar.status == spatial.status == "walking"
    assert planar.summary["step_feet"] == spatial.summary["step_feet"] and planar.summary["n_steps"] >= 2
    np.testing.assert_allclose(spatial.summary["step_times"], planar.summary["step_times"], rtol=0, atol=1e-9)
    dissipated = spatial.summary["energy_dissipated"][work]
    assert dissipated == pytest.approx(planar.summary["energy_dissipated"][work], rel=1e-7) and dissipated > 0.0
    assert np.max(np.abs(spatial.energy.residual)) < 1e-8 * np.max(np.abs(spatial.energy.kinetic))
    assert spatial.summary["lateral"]["roll_max"] < 1e-12
    return planar, spatial


@pytest.mark.slow  # 8 s: a kneed walk at rtol 1e-10 in both formulations
def test_the_kneed_walker_lifted_into_space_walks_its_planar_gait_with_latching_knees() -> None:
    """Chen's kneed walker (latching knee stops, W_stop) in Euler parameters."""
    _, spatial = _lifted(KNEED, 1.2, "stops")
    assert isinstance(spatial.model.system.stops, HingeStops)
    assert spatial.summary["energy_dissipated"]["stops"] > 0.03  # the knee strikes and latches


@pytest.mark.slow
def test_the_torso_walker_lifted_into_space_keeps_its_torso_on_its_springs() -> None:
    """A torso on hip springs and dampers (joint elements, one pair against the other leg, W_element) in Euler
    parameters."""
    _, spatial = _lifted(TORSO, 1.6, "elements")
    assert isinstance(spatial.model.system.elements, HingeElements)


def test_a_mirrored_leg_with_a_hip_width_stands_beside_the_first_in_space() -> None:
    """The mirrored leg's ``hip`` lateral (a named parameter) is the hip width: the second leg's bodies beside the
    first's, its feet the mirror image of the first's, no planar joint to the ground (roll and yaw free)."""
    data = yaml.safe_load(TORSO.read_text())
    walker = data["walker"]
    walker["parameters"].append({"name": "hip_width", "value": 0.12, "unit": "m"})
    walker["description"]["hip"] = {"lateral": "-hip_width"}
    walker["description"]["leg"]["feet"][0]["lateral"] = "hip_width / 4"
    model = build_model(config_from_dict({**data, "formulation": {"kind": "spatial"}}))
    layout = formulation_of(model.system).layout_of(model.system)
    lateral = {name: model.y0[layout.position(b)][2] for b, name in enumerate(model.body_names)}
    assert lateral == pytest.approx({"leg_1": 0.0, "leg_2": -0.12, "torso": 0.0}, abs=1e-15)
    feet = dict(zip(model.foot_names, model.system.foot_center[:, 2], strict=True))
    assert feet == pytest.approx({"foot_1": 0.03, "foot_2": -0.03}, abs=1e-15)
    assert IN_PLANE not in model.system.con_type
    hip = model.system.con_vecs[0]  # the hip joint's point on leg_1, 0.12 to its left, is leg_2's origin
    assert hip[2] == pytest.approx(-0.12) and hip[5] == 0.0
