"""The drawing of a walker in space (:mod:`biped_sim.measure.space_pose`): each foot drawn as the shape the contact
rolls on, its drawn lowest point the contact geometry's, an ellipsoid's drawn extent its semi-axes; the compliant and
the rigid run's poses alike, from one-sample runs posed at the toy's start (no dynamics run: the drawing only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import Config, load_config
from biped_sim.io.trajectory import RunData
from biped_sim.measure.pose import FOOT_HALF_WIDTH, foot_arc_half_angle
from biped_sim.measure.space_pose import CIRCLE_POINTS, space_poses
from biped_sim.rigid.space_model import STATE_NAMES
from biped_sim.walkers.space_geometry import (
    TO_SPATIAL,
    LegGeometry,
    attitude,
    leg_geometry,
    lowest_point,
    rot_y,
    with_point_mass,
)
from biped_sim.walkers.space_walker import BODY_NAMES, start_state
from tests.test_space_compliant import GAIT

SPACE = Path(__file__).resolve().parents[1] / "configs" / "space"
FOOT = "walker.description.leg.feet.foot"
CONTACT = (0.3, -0.1)  # the rigid run's stance contact point (x downhill, y left) [m]
AXES = (0.15, 0.1236, 0.06)  # an ellipsoid foot's semi-axes along the body's x', y' (up), z' (lateral) [m]
TORUS = [f"{FOOT}.shape=torus", f"{FOOT}.radius=0.09", f"{FOOT}.tube=0.0336"]  # the toy's ring thickened
FEET = {  # the toy's walker with each foot shape: (config, overrides, the foot's curves)
    "ring": ("tinkertoy.yaml", [], 1),
    "sphere": ("tinkertoy_sphere.yaml", [], 4),
    "torus": ("tinkertoy.yaml", TORUS, 2),
    "torus_lateral": ("tinkertoy.yaml", [*TORUS, f"{FOOT}.plane=lateral", f"{FOOT}.centre=[0.0, -0.8764]"], 2),
    "torus_tilted": ("tinkertoy.yaml", [*TORUS, f"{FOOT}.normal=[0.3, 0.2, 1.0]"], 2),
    "ellipsoid": ("tinkertoy.yaml", [f"{FOOT}.shape=ellipsoid", f"{FOOT}.radius=0", f"{FOOT}.axes={list(AXES)}"], 4),
    "point": ("kuo_compass_3d.yaml", [f"{FOOT}.radius=0", f"{FOOT}.shape=arc", f"{FOOT}.centre=[0.0, -1.0]"], 1),
}

LARGE = {  # the toy's walker with a foot wider than a foot is drawn (FOOT_HALF_WIDTH leg lengths on each side)
    "ring": ("tinkertoy.yaml", [f"{FOOT}.radius=0.9", f"{FOOT}.centre=[0.0, -0.1]"], 1),
    "torus_lateral": ("tinkertoy.yaml", [f"{FOOT}.shape=torus", f"{FOOT}.plane=lateral", f"{FOOT}.radius=1.48",
                                         f"{FOOT}.tube=0.02", f"{FOOT}.centre=[0.0, 0.5]"], 2),  # the 3D kneed walker's
}  # fmt: skip


def walker(shape: str) -> tuple[Config, tuple[LegGeometry, LegGeometry]]:
    """The config of the walker with foot ``shape`` (FEET's, or LARGE's as ``large_<shape>``) and its legs as the
    drawing and the contact take them."""
    name, overrides, _ = LARGE[shape.removeprefix("large_")] if shape.startswith("large_") else FEET[shape]
    config = load_config(SPACE / name, overrides)
    space = config.walker.space
    assert config.in_space and space is not None
    return config, (with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1))


def one_sample(config: Config, dynamics: str, state: np.ndarray, names: list[str]) -> RunData:
    """A run of one sample at ``state`` (the drawing reads the state, the config and the steps, none taken)."""
    empty = np.zeros((1, 0))
    return RunData(Path("."), config, {}, np.zeros(1), state[None, :], names, empty, empty, empty, {}, np.zeros(1),
                   np.zeros(1), np.zeros((1, 3)), {"strike_time": np.zeros(0), "foot": np.zeros(0)},
                   dynamics=dynamics)  # fmt: skip


def started(shape: str, dynamics: str) -> tuple[RunData, np.ndarray]:
    """The one-sample run of the walker with foot ``shape`` at the toy's start (the rigid run's stance contact at
    CONTACT, the compliant run's at the origin, its feet not sunk) and the contact point (spatial slope frame)."""
    config, legs = walker(shape)
    if dynamics == "rigid":
        state = np.array([*(GAIT[name] for name in STATE_NAMES[:8]), *CONTACT])
        return one_sample(config, "rigid", state, list(STATE_NAMES)), TO_SPATIAL @ [*CONTACT, 0.0]
    q, _ = start_state(legs, GAIT, 0.0)
    names = [f"{c}_{body}" for body in BODY_NAMES for c in ("x", "y", "z", "e0", "e1", "e2", "e3")]
    return one_sample(config, "compliant", q.ravel(), names), np.zeros(3)


def drawn_lowest(feet: np.ndarray) -> np.ndarray:
    """(2, 3) each drawn foot's lowest point (spatial slope frame: y the normal), the first of equals."""
    return np.array([foot[np.nanargmin(foot[:, 1])] for foot in feet])


@pytest.mark.parametrize("dynamics", ["compliant", "rigid"])
@pytest.mark.parametrize("shape", list(FEET))
def test_each_foot_is_drawn_down_to_its_contact_geometrys_lowest_point(shape: str, dynamics: str) -> None:
    """At the start, the stance foot's drawn lowest point is its contact point and the swing foot's is
    space_geometry.lowest_point's, to rounding, with no drawn point lower; each foot drawn as its closed curves of
    CIRCLE_POINTS, a NaN row between two."""
    run, contact = started(shape, dynamics)
    _, legs = walker(shape)
    feet = space_poses(run).feet[0]
    stance = attitude(GAIT["heading"], GAIT["bank"], GAIT["pitch"])
    hinge = TO_SPATIAL.T @ contact - lowest_point(legs[0], stance)
    swing = TO_SPATIAL @ (hinge + lowest_point(legs[1], stance @ rot_y(GAIT["swing_angle"])))
    np.testing.assert_allclose(drawn_lowest(feet), [contact, swing], rtol=0, atol=1e-15)
    curves = FEET[shape][2]
    assert feet.shape == (2, curves * (CIRCLE_POINTS + 1) - 1, 3)
    assert np.isnan(feet[:, CIRCLE_POINTS :: CIRCLE_POINTS + 1]).all() and np.isnan(feet).sum() == 6 * (curves - 1)


@pytest.mark.parametrize("dynamics", ["compliant", "rigid"])
@pytest.mark.parametrize("shape", ["ellipsoid", "sphere"])
def test_an_ellipsoid_or_a_sphere_is_drawn_as_far_along_each_principal_axis_as_its_semi_axis(
    shape: str, dynamics: str
) -> None:
    """The drawn foot from its drawn centre, along each of the leg's axes turned to the pose (the ellipsoid's principal
    axes), reaches its semi-axis on both sides, to rounding: the ellipsoid's ``axes`` (the leg frame's), the sphere's
    radius."""
    run, _ = started(shape, dynamics)
    poses = space_poses(run)
    foot = run.config.walker.space.leg.foot  # type: ignore[union-attr]
    semi = foot.axes if shape == "ellipsoid" else (foot.radius,) * 3  # along the leg's x, y (lateral), z (up)
    stance = attitude(GAIT["heading"], GAIT["bank"], GAIT["pitch"])
    for k, turn in enumerate((stance, stance @ rot_y(GAIT["swing_angle"]))):
        reach = (poses.feet[0, k] - poses.legs[0, k, 4]) @ (TO_SPATIAL @ turn)  # along the leg's x, y, z
        np.testing.assert_allclose(np.nanmax(reach, axis=0), semi, rtol=0, atol=1e-15)
        np.testing.assert_allclose(np.nanmin(reach, axis=0), np.negative(semi), rtol=0, atol=1e-15)


@pytest.mark.parametrize("dynamics", ["compliant", "rigid"])
@pytest.mark.parametrize("shape", list(LARGE))
def test_a_ring_wider_than_a_foot_is_drawn_as_its_arc_holding_the_contact_point(shape: str, dynamics: str) -> None:
    """A ring (a torus's outer equator) of radius 0.9 or 1.5 on a leg of 1 is drawn as the arc of it about its bottom
    on the leg (foot_arc_half_angle: FOOT_HALF_WIDTH leg lengths on each side), not as its whole circle, the leg's
    line down to the arc's middle; the stance foot's contact point on the drawn arc, to the arc's pieces."""
    run, contact = started(f"large_{shape}", dynamics)
    space = run.config.walker.space  # type: ignore[union-attr]
    radius, leg_length = space.leg.foot.radius + space.leg.foot.tube, space.leg_length()
    half = foot_arc_half_angle(radius, leg_length)
    poses = space_poses(run)
    ring = poses.feet[0, 0, :CIRCLE_POINTS]  # the stance foot's ring (a torus's: its equator first)
    pieces = np.linalg.norm(np.diff(ring, axis=0), axis=1)  # an arc of `radius` over 2 half: equal chords
    np.testing.assert_allclose(pieces, 2 * radius * np.sin(half / (CIRCLE_POINTS - 1)), rtol=1e-9)
    span = np.linalg.norm(ring[-1] - ring[0])  # the chord between its ends: 2 R sin(half-angle), no closed circle
    assert span == pytest.approx(2 * FOOT_HALF_WIDTH * leg_length, rel=1e-12) and half < 0.5
    np.testing.assert_allclose(ring[CIRCLE_POINTS // 2], poses.legs[0, 0, 4], rtol=0, atol=1e-12)
    gaps = np.linalg.norm(ring - contact, axis=1)  # a torus's lowest point is its outer equator's
    assert gaps.min() < pieces[0]  # within one of its pieces
