"""Leg splay written as plain geometry (configs/space/tinkertoy_splayed.yaml, kuo_compass_3d_splayed.yaml): each leg's
centre of mass, foot centre, inertia tensor and ring normal turned about its forward axis in the description, through
named parameters, is the rigid model's leg so turned, and walks its gait; the Kuo-type compass splayed stays unstable
(docs/guide/rigid.md's multipliers against the splay); a foot's ring plane at any normal, mirrored, refused where it
cannot be, and its planar arc."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim.config import Config, FootSpec, load_config
from biped_sim.config.space_description import SpaceDescription
from biped_sim.errors import ConfigError
from biped_sim.rigid.limit_cycle import RIGID_TOLERANCE, LimitCycle, map_jacobian, newton_fixed_point
from biped_sim.rigid.space_cycle import SpaceMap, space_branch, space_limit_cycle, space_walker_model
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
        ([f"{FOOT}.normal=[0, 0, 0]"], f"{FOOT}.normal: a ring's plane normal must not be zero"),
        ([f"{FOOT}.normal=[0, 2, 0]"], f"{FOOT}.normal: a ring across the leg"),
        ([f"{FOOT}.normal=[0, 0, 1]", f"{FOOT}.plane=sagittal"], f"{FOOT}.normal: give the ring's"),
        ([f"{FOOT}.shape=sphere", f"{FOOT}.normal=[0, 0, 1]"], f"{FOOT}.normal: only a ring's plane"),
    ],
)
def test_a_bad_ring_normal_is_one_line_naming_it(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError) as error:
        load_config(TOY, overrides)
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_a_planar_model_refuses_a_ring_out_of_its_plane() -> None:
    """An arc whose normal is off z' is a foot in space: the planar formulation names it; along z' it is planar."""
    walker = CONFIGS.parent / "tests" / "data" / "kneed_compliant_parametrised.yaml"
    with pytest.raises(ConfigError, match=r"^walker\.description\.leg\.feet\.foot\.normal: only in space") as error:
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


KUO = CONFIGS / "space" / "kuo_compass_3d.yaml"
KUO_SPLAYED = CONFIGS / "space" / "kuo_compass_3d_splayed.yaml"
# point feet, along one branch of gaits from the unsplayed one (Newton reaches 0.15 from 0.1 in steps of 0.01, not at
# once): the largest multiplier where docs/guide/rigid.md prints it, a real flip or, at 0.05, a complex pair's modulus,
# and the largest part of its eigenvector (rocking, pitch rate with roll and hinge rates, then a yaw mode)
KUO_SPLAYS = (0.0, 0.02, 0.05, 0.1, 0.11, 0.12, 0.13, 0.14, 0.15)
KUO_LARGEST = {0.0: -6.585415, 0.02: -3.394953, 0.1: 3.082100, 0.15: 3.058578}
KUO_PAIR = (0.05, 2.455372)
KUO_MODE = {0.0: "omega_x", 0.02: "omega_x", 0.05: "omega_y", 0.1: "swing_rate", 0.15: "omega_z"}
# feet rounded sideways (lateral radius 1 m, fore-aft 1 mm or 0.3 m; 0.5 m, fore-aft 1 mm) and splayed, outward and
# inward: the largest modulus along the branch from the unsplayed gait (itself continued from point feet, as
# docs/guide/rigid.md's table)
LATERAL = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)  # the feet's lateral radius [m] stepped up
BOTH_SPLAYS = {"out": (0.02, 0.05, 0.1), "in": (-0.02, -0.05, -0.1, -0.15, -0.2, -0.25, -0.3, -0.35, -0.4, -0.45, -0.5)}
BOTH_LARGEST = {
    (1.0, 0.001, "out"): (1.800348, 1.823291, 1.831840),
    (1.0, 0.001, "in"): (1.746223, 1.686541, 1.541644, 1.279368, 1.140465, 1.343986, 1.443056, 1.485184, 1.491591,
                         1.476866, 1.451649),
    (1.0, 0.3, "out"): (2.007288, 2.076860, 2.156232),
    (1.0, 0.3, "in"): (1.899520, 1.816475, 1.693931, 1.607416, 1.558493, 1.535295, 1.519774, 1.494574, 1.448006,
                       1.374784, 1.273541),
    (0.5, 0.001, "out"): (1.999085, 1.513243, 1.736807),  # feet that splay: the least near 0.05, still above 1
}  # fmt: skip


def kuo_splayed(splay: float, *overrides: str) -> Config:
    """configs/space/kuo_compass_3d_splayed.yaml at ``splay`` (point feet: 1 mm spheres), with ``overrides``."""
    return load_config(KUO_SPLAYED, [f"walker.parameters.splay={splay}", *overrides])


def rounded(lateral: float, tube: float = 0.001) -> list[str]:
    """The overrides of a torus foot in the leg's y'-z' plane (tests/test_space_feet.py's), curved ``lateral``
    sideways and ``tube`` fore-aft, its bottom 1 m below the hip and its centre on the splayed leg's axis."""
    return [f"walker.parameters.foot_radius={lateral}", f"{FOOT}.shape=torus", f"{FOOT}.radius={lateral - tube}",
            f"{FOOT}.tube={tube}", f"{FOOT}.plane=lateral"]  # fmt: skip


def kuo_turned(splay: float) -> SpaceModel:
    """The Kuo-type compass's rigid model with its leg turned by the model's own turn (:func:`turned`)."""
    config = load_config(KUO)
    return space_model(turned(config.walker.space, splay), config.gravity, config.ground.slope)  # type: ignore[arg-type]


def test_the_splayed_kuo_compass_at_zero_splay_is_the_compass_to_the_bit() -> None:
    """Splay 0: the rigid model's data of kuo_compass_3d.yaml, floats compared exactly with their zeros' signs."""
    assert repr(kuo_splayed(0.0).walker.space) == repr(load_config(KUO).walker.space)


@pytest.mark.parametrize("splay", [0.05, 0.15, -0.1])
def test_the_kuo_compass_splayed_as_data_is_its_model_turned(splay: float) -> None:
    """Its parts and feet are the model's leg turned (a sphere's centre and radius: its normal is not read); a torus
    of lateral radius 1 m is centred at the hip point, so the turn leaves it: there splay moves the legs' mass only."""
    described, reference = space_walker_model(kuo_splayed(splay)), kuo_turned(splay)
    for ours, theirs in zip(described.parts, reference.parts, strict=True):
        np.testing.assert_allclose(ours.com, theirs.com, rtol=0, atol=1e-15)
        np.testing.assert_allclose(ours.inertia, theirs.inertia, rtol=0, atol=1e-15)
    for ours, theirs in zip(described.feet, reference.feet, strict=True):
        assert (ours.shape, ours.radius) == (theirs.shape, theirs.radius)
        np.testing.assert_allclose(ours.centre, theirs.centre, rtol=0, atol=1e-15)
    assert described.feet[0].centre[1] == pytest.approx(0.05 + math.sin(splay) * 0.999)  # outward for splay > 0
    torus = space_walker_model(kuo_splayed(splay, *rounded(1.0)))
    assert [tuple(foot.centre) for foot in torus.feet] == [(0.0, 0.05, 0.0), (0.0, -0.05, 0.0)]
    assert [tuple(part.com) for part in torus.parts] == [tuple(part.com) for part in described.parts]


def largest(cycle: LimitCycle) -> tuple[complex, str]:
    """The multiplier of largest modulus and the section coordinate of its eigenvector's largest part."""
    values, vectors = np.linalg.eig(cycle.jacobian)
    k = int(np.argmax(np.abs(values)))
    return complex(values[k]), cycle.section_names[int(np.argmax(np.abs(vectors[:, k])))]


@pytest.mark.slow  # two searches without a guess and nine Newton solves, about 5 CPU s
def test_splay_changes_the_kuo_compass_unstable_mode_but_does_not_stabilise_it() -> None:
    """Point feet splayed outward along one branch: the rocking's flip shrinks (-6.59 -> -3.39 at 0.02 rad), a
    complex pair takes over (2.455372 at 0.05), then a real yaw mode (3.08 at 0.1, 3.06 at 0.15); the largest
    modulus stays above 1 at every splay. At 0.05 (the config's) the search without a guess finds the same gait, and
    the old model's turn (:func:`turned`) has it too."""
    cycles = space_branch([kuo_splayed(s) for s in KUO_SPLAYS])
    assert [c.converged for c in cycles] == [True] * len(KUO_SPLAYS)
    assert all(c.max_multiplier_modulus > 1.0 for c in cycles)
    found = {s: largest(c) for s, c in zip(KUO_SPLAYS, cycles, strict=True)}
    for splay, value in KUO_LARGEST.items():
        assert found[splay][0].real == pytest.approx(value, abs=1e-6) and found[splay][0].imag == 0.0
    splay, modulus = KUO_PAIR
    assert abs(found[splay][0]) == pytest.approx(modulus, abs=1e-6) and abs(found[splay][0].imag) > 1.0
    assert {s: found[s][1] for s in KUO_MODE} == KUO_MODE
    pair = cycles[KUO_SPLAYS.index(splay)]
    searched = space_limit_cycle(kuo_splayed(splay))  # the config's gait, found without a guess: the same
    assert searched.converged and "sagittal twin" in searched.start
    np.testing.assert_allclose(searched.section_point, pair.section_point, rtol=0, atol=1e-9)
    assert searched.step_period == pytest.approx(0.67101559, abs=1e-8)
    step_map = SpaceMap(kuo_turned(splay))
    z, converged, _, _ = newton_fixed_point(step_map, pair.section_point, RIGID_TOLERANCE)
    assert converged
    np.testing.assert_allclose(z, pair.section_point, rtol=0, atol=1e-9)
    multipliers = np.sort_complex(np.linalg.eigvals(map_jacobian(step_map, z)))
    np.testing.assert_allclose(multipliers, np.sort_complex(pair.multipliers), rtol=0, atol=1e-6)


@pytest.mark.slow  # a branch of 10 to 23 gaits each, 3 to 5 CPU s each
@pytest.mark.parametrize(("lateral", "tube", "side"), list(BOTH_LARGEST))
def test_splay_on_feet_rounded_sideways_leaves_the_kuo_compass_unstable(lateral: float, tube: float, side: str) -> None:
    """Lateral radius ``lateral``, fore-aft ``tube``: from point feet (1 mm) or the 0.3 m sphere, the lateral radius
    stepped up to ``lateral``, then the splay stepped out or in; the largest modulus at each splay, above 1 at every
    one."""
    head = [kuo_splayed(0.0, f"walker.parameters.foot_radius={r}") for r in LATERAL if r <= tube]  # spheres
    head += [kuo_splayed(0.0, *rounded(v, tube)) for v in LATERAL if tube < v <= lateral]
    splays = BOTH_SPLAYS[side]
    cycles = space_branch([kuo_splayed(0.0), *head, *(kuo_splayed(s, *rounded(lateral, tube)) for s in splays)])
    assert [c.converged for c in cycles] == [True] * (1 + len(head) + len(splays))
    moduli = [c.max_multiplier_modulus for c in cycles[1 + len(head) :]]
    assert moduli == pytest.approx(BOTH_LARGEST[lateral, tube, side], abs=1e-6)
    assert min(moduli) > 1.0
