"""Leg splay written as plain geometry (configs/space/tinkertoy_splayed.yaml): each leg's centre of mass, foot centre,
inertia tensor and ring normal turned about its forward axis in the description, through named parameters, is the
rigid model's leg so turned, and walks its gait; a foot's ring plane at any normal, mirrored, refused where it
cannot be, and its planar arc."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim.config import FootSpec, load_config
from biped_sim.config.space_description import SpaceDescription
from biped_sim.errors import ConfigError
from biped_sim.rigid.limit_cycle import RIGID_TOLERANCE, map_jacobian, newton_fixed_point
from biped_sim.rigid.space_cycle import SpaceMap, space_limit_cycle
from biped_sim.rigid.space_model import SpaceModel, space_model
from biped_sim.walkers.described import foot_in_space
from tests.conftest import CONFIGS
from tests.test_space_compliant import GAIT

TOY = CONFIGS / "space" / "tinkertoy.yaml"
SPLAYED = CONFIGS / "space" / "tinkertoy_splayed.yaml"
SPLAY = 0.05  # the config's
FOOT = "walker.description.leg.feet.foot"


def turned(space: SpaceDescription, splay: float) -> SpaceDescription:
    """The model's data of ``space`` with its leg turned outward by ``splay`` about its forward axis x through its
    hip point, in its own frame (x forward, y away from the other leg, z up): the turn the rigid model's own
    ``SpaceDescription.splay`` made (removed after 9ed9a5d, where this gave its gaits to the bit)."""
    c, s = math.cos(splay), math.sin(splay)
    turn = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])  # outward: the foot toward +y
    leg, foot = space.leg, space.leg.foot
    tensor = turn @ leg.inertia.matrix() @ turn.T
    inertia = leg.inertia.model_copy(update={"xx": tensor[0, 0], "yy": tensor[1, 1], "zz": tensor[2, 2],
                                             "xy": tensor[0, 1], "xz": tensor[0, 2], "yz": tensor[1, 2]})  # fmt: skip
    foot = foot.model_copy(update={"centre": tuple(turn @ foot.centre), "normal": tuple(turn @ foot.normal)})
    leg = leg.model_copy(update={"com": tuple(turn @ leg.com), "inertia": inertia, "foot": foot})
    return space.model_copy(update={"leg": leg})


def toy_model(space: SpaceDescription) -> SpaceModel:
    return space_model(space, 1.0, 0.0702)


def cycle(model: SpaceModel) -> tuple[np.ndarray, np.ndarray]:
    """The gait by Newton from the toy's (its section point) and its multipliers, sorted."""
    step_map = SpaceMap(model)
    z, converged, _, _ = newton_fixed_point(step_map, step_map.section.of_keys(GAIT), RIGID_TOLERANCE)
    assert converged
    return z, np.sort_complex(np.linalg.eigvals(map_jacobian(step_map, z)))


def test_the_splayed_toy_at_zero_splay_is_the_toy_to_the_bit() -> None:
    """Splay 0: cos 1 and sin 0 leave every number as written (floats compared exactly, with the zeros' signs)."""
    flat = load_config(SPLAYED, ["walker.parameters.splay=0"]).walker.space
    assert repr(flat) == repr(load_config(TOY).walker.space)


def test_a_splay_written_as_data_is_the_model_turned_and_walks_its_gait() -> None:
    """The description's splayed leg (expressions in sin and cos of a named parameter, mirrored into the second
    leg) is the model's leg turned in its own frame: parts and feet to rounding; the same fixed point to 1e-9 and
    multipliers to 1e-6, found by Newton from the toy's gait."""
    described = toy_model(load_config(SPLAYED).walker.space)
    reference = toy_model(turned(load_config(TOY).walker.space, SPLAY))
    for ours, theirs in zip(described.parts, reference.parts, strict=True):
        np.testing.assert_allclose(ours.com, theirs.com, rtol=0, atol=1e-15)
        np.testing.assert_allclose(ours.inertia, theirs.inertia, rtol=0, atol=1e-15)
    for ours, theirs in zip(described.feet, reference.feet, strict=True):
        np.testing.assert_allclose(ours.centre, theirs.centre, rtol=0, atol=1e-15)
        np.testing.assert_allclose(ours.normal, theirs.normal, rtol=0, atol=1e-15)
    np.testing.assert_allclose(described.feet[0].normal, [0.0, math.cos(SPLAY), math.sin(SPLAY)], atol=1e-15)
    assert described.feet[1].centre[1] == pytest.approx(-(0.5 * 0.3624 + math.sin(SPLAY) * 0.8764))  # outward, mirrored
    (z, multipliers), (z_ref, multipliers_ref) = cycle(described), cycle(reference)
    np.testing.assert_allclose(z, z_ref, rtol=0, atol=1e-9)
    np.testing.assert_allclose(multipliers, multipliers_ref, rtol=0, atol=1e-6)
    assert max(abs(multipliers)) < 1.0  # splayed by 0.05 rad, the toy still walks stably


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ([f"{FOOT}.normal=[0, 0, 0]"], "walker.description.feet.0.normal: a ring's plane normal must not be zero"),
        ([f"{FOOT}.normal=[0, 2, 0]"], "walker.description.feet.0.normal: a ring across the leg"),
        ([f"{FOOT}.normal=[0, 0, 1]", f"{FOOT}.plane=sagittal"], "walker.description.feet.0.normal: give the ring's"),
        ([f"{FOOT}.shape=sphere", f"{FOOT}.normal=[0, 0, 1]"], "walker.description.feet.0.normal: only a ring's plane"),
    ],
)
def test_a_bad_ring_normal_is_one_line_naming_it(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError) as error:
        load_config(TOY, overrides)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_a_planar_model_refuses_a_ring_out_of_its_plane() -> None:
    """An arc whose normal is off z' is a foot in space: the planar formulation names it; along z' it is planar."""
    walker = CONFIGS.parent / "tests" / "data" / "kneed_compliant_parametrised.yaml"
    with pytest.raises(ConfigError, match=r"^walker\.description\.feet\.foot_1\.normal: only in space") as error:
        load_config(walker, ["walker.description.leg.feet.foot.normal=[0, 0.1, 1]"])
    assert "\n" not in str(error.value)
    load_config(walker, ["walker.description.leg.feet.foot.normal=[0, 0, -2]"])  # the sagittal plane


def test_the_second_leg_mirrors_the_normal_and_the_rigid_data_keep_one_plane() -> None:
    """The mirrored leg's normal has its z' component negated; the rigid model's data (the left leg, x' z' y') take
    either leg's as the same plane, whatever the sign written."""
    config = load_config(SPLAYED)
    first, second = config.walker.description.feet
    assert first.normal == pytest.approx((0.0, math.sin(SPLAY), math.cos(SPLAY)))
    assert second.normal == pytest.approx((0.0, math.sin(SPLAY), -math.cos(SPLAY)))
    assert first.in_space(1.0) == second.in_space(-1.0)
    flipped = second.model_copy(update={"normal": tuple(-n for n in second.normal)})
    assert flipped.in_space(-1.0) == second.in_space(-1.0)


@pytest.mark.parametrize("normal", [(0.0, 0.3, 1.0), (0.2, 0.0, 1.0), (0.3, -0.4, 0.8), (1.0, 0.0, 0.0)])
def test_a_tilted_ring_rolls_in_the_plane_on_its_osculating_arc(normal: tuple[float, float, float]) -> None:
    """The planar arc of a ring of any normal: the ring's own lowest point (its depth below the centre and its place
    fore-aft, the leg pitched by theta about z') and the arc's agree upright to rounding and to third order in
    theta (ratio of the errors at theta and theta / 2 near 8 or better); the lateral ring's is its point."""
    foot = FootSpec(name="f", body="b", centre=(0.01, -0.9), radius=0.1, shape="torus", tube=0.02, normal=normal)
    (cx, cy), radius = foot.sagittal_arc()
    n = np.array(foot.plane_normal)

    def ring_bottom(theta: float) -> np.ndarray:
        """The torus's lowest point (x, y) in the slope frame, the body pitched by theta (its -y' toward +x)."""
        up = np.array([-math.sin(theta), math.cos(theta), 0.0])  # the slope normal in the body frame
        w = up - (up @ n) * n
        d = -w / np.linalg.norm(w)
        rotate = np.array([[math.cos(theta), math.sin(theta)], [-math.sin(theta), math.cos(theta)]])
        return rotate @ (np.array(foot.centre) + foot.radius * d[:2]) - np.array([0.0, foot.tube])

    def arc_bottom(theta: float) -> np.ndarray:
        rotate = np.array([[math.cos(theta), math.sin(theta)], [-math.sin(theta), math.cos(theta)]])
        return rotate @ np.array([cx, cy]) - np.array([0.0, radius])

    np.testing.assert_allclose(arc_bottom(0.0), ring_bottom(0.0), rtol=0, atol=1e-14)
    errors = [abs(arc_bottom(t)[1] - ring_bottom(t)[1]) for t in (0.1, 0.05)]
    assert errors[0] < 1e-3 and (errors[0] < 1e-14 or errors[0] / errors[1] > 7.0)


@pytest.mark.slow  # the search without a guess, about 5 CPU s
def test_the_splayed_toy_is_found_without_a_guess_from_its_sagittal_twin() -> None:
    """`biped-sim limit-cycle configs/space/tinkertoy_splayed.yaml`: the scan's walks fall, the sagittal twin's gait
    (its ring's tilt scaled away with the rest of the lateral geometry) continues to the walker's, the one Newton
    finds from the toy's gait; stable, step period 0.89878459."""
    found = space_limit_cycle(load_config(SPLAYED))
    assert found.converged and "sagittal twin" in found.start
    z, _ = cycle(toy_model(load_config(SPLAYED).walker.space))
    np.testing.assert_allclose(found.section_point, z, rtol=0, atol=1e-9)
    assert found.step_period == pytest.approx(0.89878459, abs=1e-8) and found.stable


def test_the_spatial_formulation_takes_a_ring_normal_as_its_disc_axis() -> None:
    """A described walker off the rigid model's form (compliant, spatial) gets the unit normal as its disc's axis."""
    foot = FootSpec(name="f", body="b", centre=(0.0, -0.9), radius=0.1, normal=(0.0, 0.3, 0.4))
    assert tuple(foot_in_space(foot)[2:5]) == pytest.approx((0.0, 0.6, 0.8), abs=1e-15)
