"""Any described walker as MJCF (:mod:`biped_sim.bench.mjcf`): the XML read back without MuJoCo (masses, feet,
joints, stops, springs, ring feet), its refusals, and, where MuJoCo is installed, the model MuJoCo builds of it."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from biped_sim.bench.mjcf import POINT_FOOT, RING_HALF_WIDTH, ROOT_HINGE, walker_mjcf
from biped_sim.config import Config, config_from_dict, load_config
from biped_sim.errors import ConfigError
from biped_sim.walkers.describe import describe

ROOT = Path(__file__).resolve().parents[1]
PLANAR = ["round_foot_walker.yaml", "compass_goswami.yaml", "torso_walker.yaml", "four_legged_walker.yaml"]
SPACE = ["space/kuo_compass_3d_compliant.yaml", "space/tinkertoy_compliant.yaml", "space/kuo_compass_3d.yaml"]
KNEED = ROOT / "tests" / "data" / "kneed_round_feet.yaml"


def config(name: str | Path, *overrides: str) -> Config:
    path = name if isinstance(name, Path) else ROOT / "configs" / name
    return load_config(path, list(overrides))


def total_mass(root: ET.Element) -> float:
    return sum(float(i.get("mass", "0")) for i in root.iter("inertial"))


def feet(root: ET.Element) -> list[ET.Element]:
    return [g for g in root.iter("geom") if g.get("solref") is not None]


@pytest.mark.parametrize("name", [*PLANAR, KNEED])
def test_a_planar_walker_keeps_its_mass_bodies_feet_and_stops(name: str | Path) -> None:
    cfg = config(name)
    description = describe(cfg)
    root = ET.fromstring(walker_mjcf(cfg))
    masses = sum(b.mass for b in description.bodies) + sum(p.mass for p in description.point_masses)
    assert total_mass(root) == pytest.approx(masses, rel=1e-14)
    assert sorted(g.get("name") for g in feet(root)) == sorted(f.name for f in description.feet)
    hinges = [j for j in root.iter("joint") if j.get("type") == "hinge"]
    assert len(hinges) == len(description.bodies)  # the root's and one per joint
    for joint in description.joints:
        hinge = next(j for j in hinges if j.get("name") == joint.child)
        lower, upper = joint.lower_upper()
        if joint.stops:
            written = [float(v) for v in hinge.get("range", "").split()]
            assert [v for v, ours in zip(written, (lower, upper), strict=True) if math.isfinite(ours)] == [
                v for v in (lower, upper) if math.isfinite(v)
            ]
        else:
            assert hinge.get("limited") is None


def test_the_torsos_springs_and_dampers_are_tendons_over_the_hinges_between_their_bodies() -> None:
    root = ET.fromstring(walker_mjcf(config("torso_walker.yaml")))
    tendons = {t.get("name"): t for t in root.iter("fixed")}
    elements = describe(config("torso_walker.yaml")).joint_elements()
    assert len(tendons) == len(elements)
    for joint, element, other in elements:
        tendon = tendons[f"{joint.name}.{element.name}"]
        coefs = {j.get("joint"): float(j.get("coef")) for j in tendon.iter("joint")}
        expected = {joint.child: 1.0} if other == "leg_1" else {joint.child: 1.0, other: -1.0}  # leg_1: the root
        assert coefs == expected
        assert float(tendon.get("stiffness")) == (element.stiffness or 0.0)
        assert float(tendon.get("damping")) == (element.damping or 0.0)


def test_an_element_against_the_ground_is_a_tendon_over_the_root_s_hinge_and_its_body_s_path() -> None:
    cfg = config("torso_walker.yaml")
    data = cfg.model_dump(mode="json")
    data["walker"]["description"]["joints"][0]["elements"] = [
        {"name": "spring", "law": "linear_spring", "stiffness": 10.0, "against": "ground"}
    ]
    root = ET.fromstring(walker_mjcf(config_from_dict(data)))
    (tendon,) = root.iter("fixed")
    assert {j.get("joint"): float(j.get("coef")) for j in tendon.iter("joint")} == {"torso": 1.0, ROOT_HINGE: 1.0}


def test_point_feet_are_small_spheres_whose_bottom_is_the_point() -> None:
    cfg = config("space/kuo_compass_3d.yaml", "contact.stiffness=1e7")  # 1 mm spheres: written as they are
    foot = feet(ET.fromstring(walker_mjcf(cfg)))[0]
    assert foot.get("type") == "sphere" and float(foot.get("size")) == pytest.approx(0.001)
    point = config(
        "space/kuo_compass_3d.yaml",
        "contact.stiffness=1e7",
        'walker.description.leg.feet.foot={"name": "foot", "body": "leg", "centre": [0, -1]}',
    )
    foot = feet(ET.fromstring(walker_mjcf(point)))[0]
    centre = [float(v) for v in foot.get("pos").split()]
    assert float(foot.get("size")) == pytest.approx(POINT_FOOT) and centre[2] - POINT_FOOT == pytest.approx(-1.0)


def test_ring_feet_are_flat_cylinders_about_the_rings_normal() -> None:
    cfg = config("space/tinkertoy_compliant.yaml")
    ring = cfg.walker.space.leg.foot
    root = ET.fromstring(walker_mjcf(cfg))
    left, right = feet(root)
    assert left.get("type") == right.get("type") == "cylinder"
    radius, half = (float(v) for v in left.get("size").split())
    assert radius == ring.radius and half == pytest.approx(RING_HALF_WIDTH * ring.radius)
    normal = np.array(ring.normal) / np.linalg.norm(ring.normal)
    np.testing.assert_allclose([float(v) for v in left.get("zaxis").split()], normal, atol=1e-15)
    np.testing.assert_allclose([float(v) for v in right.get("zaxis").split()], normal * [1, -1, 1], atol=1e-15)
    assert total_mass(root) == pytest.approx(2.0 * cfg.walker.space.leg.mass + cfg.walker.space.hip_mass)


RIGID_GAIT = "rigid_limit_cycle"


@pytest.mark.parametrize(
    ("name", "overrides", "message"),
    [
        ("kneed_walker_compliant.yaml", (), "walker.description.joints.1.stops.0.latch: MuJoCo has no latch"),
        ("rimless_wheel.yaml", (), "contact.stiffness: a foot without a radius has no Hertz stiffness"),
        ("simplest_walker.yaml", ("contact.stiffness=1e7",), "walker.description.bodies.leg1.mass: a body needs mass"),
        (
            "space/tinkertoy.yaml",
            ("walker.description.leg.feet.foot.shape=torus", "walker.description.leg.feet.foot.tube=0.05"),
            "walker.description.feet: a torus foot is not written as MJCF (MuJoCo has no torus)",
        ),
        (
            "space/kneed_walker_3d.yaml",
            ("dynamics=rigid", "formulation.kind=planar", "friction.spin_radius=0", f"simulation.initial={RIGID_GAIT}"),
            "walker.description.legs: a walker in space is written as MJCF with one-body legs only",
        ),
    ],
)
def test_what_mujoco_or_the_mjcf_cannot_hold_is_refused_in_one_line(name: str, overrides: tuple, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        walker_mjcf(config(name, *overrides))
    assert str(caught.value).startswith(message) and "\n" not in str(caught.value)


@pytest.mark.parametrize("name", [*PLANAR, *SPACE, KNEED])
def test_mujoco_builds_the_walker_with_its_mass(name: str | Path) -> None:
    mujoco = pytest.importorskip("mujoco")
    cfg = config(name, "contact.stiffness=1e7") if name == "space/kuo_compass_3d.yaml" else config(name)
    model = mujoco.MjModel.from_xml_string(walker_mjcf(cfg))
    assert mujoco.mj_getTotalmass(model) == pytest.approx(total_mass(ET.fromstring(walker_mjcf(cfg))), rel=1e-12)


def test_mujocos_tendon_lengths_are_the_elements_relative_angles() -> None:
    """The torso walker with its stance leg at 0.1, swing leg at -0.3 and torso at 0.2 rad (absolute): each spring's
    tendon is the torso's angle against the leg it names."""
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_string(walker_mjcf(config("torso_walker.yaml")))
    data = mujoco.MjData(model)
    angles = {"leg_1": 0.1, "leg_2": -0.3, "torso": 0.2}
    for name in ("leg_2", "torso"):
        data.qpos[model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]] = (
            angles[name] - angles["leg_1"]
        )
    data.qpos[model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "theta")]] = angles["leg_1"]
    mujoco.mj_forward(model, data)
    for _, element, other in describe(config("torso_walker.yaml")).joint_elements():
        k = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, f"waist.{element.name}")
        assert data.ten_length[k] == pytest.approx(angles["torso"] - angles[other], abs=1e-15)


# semi-axes 0.15 forward, 0.3 up the leg, 0.4 sideways (the rigid model's leg frame: 0.15, 0.4, 0.3)
ELLIPSOID = ["walker.description.leg.feet.foot.shape=ellipsoid", "walker.description.leg.feet.foot.radius=0",
             "walker.description.leg.feet.foot.axes=[0.15, 0.3, 0.4]", "contact.stiffness=1e5"]  # fmt: skip


def test_ellipsoid_feet_are_mujocos_ellipsoids() -> None:
    cfg = config("space/tinkertoy.yaml", *ELLIPSOID)
    left, right = feet(ET.fromstring(walker_mjcf(cfg)))
    assert left.get("type") == right.get("type") == "ellipsoid" and left.get("size") == "0.15 0.4 0.3"
    assert left.get("euler") is None and right.get("euler") is None  # its axes are the leg's: no turn


def test_mujocos_ellipsoid_has_its_lowest_point_where_the_rigid_model_has_it() -> None:
    """The left leg pitched and banked: MuJoCo's ellipsoid geom touches a plane at the description's lowest point
    (the rigid model's :func:`~biped_sim.rigid.space_model.foot_bottom`, found from the leg's pose)."""
    mujoco = pytest.importorskip("mujoco")
    from biped_sim.rigid.space_cycle import space_walker_model
    from biped_sim.rigid.space_model import foot_bottom
    from biped_sim.walkers.space_geometry import attitude

    cfg = config("space/tinkertoy.yaml", *ELLIPSOID)
    model = mujoco.MjModel.from_xml_string(walker_mjcf(cfg))
    data = mujoco.MjData(model)
    rotation = attitude(0.2, 0.15, -0.3)
    data.qpos[3:7] = np.roll(Rotation.from_matrix(rotation).as_quat(), 1)  # (w, x, y, z)
    mujoco.mj_kinematics(model, data)
    foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "foot0")
    axes, turn = np.array([0.15, 0.4, 0.3]), data.geom_xmat[foot].reshape(3, 3)
    shape = turn @ np.diag(axes**2) @ turn.T  # the lowest point: centre - Q e_z / sqrt(e_z Q e_z)
    lowest = data.geom_xpos[foot] - shape[:, 2] / math.sqrt(shape[2, 2])
    rigid = space_walker_model(cfg)
    bottom, _ = foot_bottom(rigid.feet[0], rotation)
    np.testing.assert_allclose(lowest, bottom, atol=1e-12)
