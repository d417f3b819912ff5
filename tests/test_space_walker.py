"""The walker in space (a described walker of the rigid model's form): its rigid data, flow and strike, its gait."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from biped_sim.config import Config, config_from_dict, load_config
from biped_sim.config.space_description import SpaceFoot
from biped_sim.errors import ConfigError
from biped_sim.rigid import space_dynamics as dyn
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.space_cycle import SpaceSection, space_branch, space_limit_cycle, space_walker_model
from biped_sim.rigid.space_kernels import space_flow, space_params
from biped_sim.rigid.space_model import MIRROR, SpaceModel, foot_bottom, space_model, swing_clearance
from tests.conftest import invoke, one_line_error

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
TINKERTOY = CONFIGS / "space" / "tinkertoy.yaml"
FOOT, LEG = "walker.description.leg.feet.foot", "walker.description.leg.bodies.leg"
KUO_RADII = (0.001, 0.1, 0.2, 0.3, 0.4, 0.5)  # the feet's radii [m], along one branch of gaits
KUO_POINT_MULTIPLIER = -6.585415  # its point feet's unstable (lateral) multiplier
KUO_LARGEST = (6.585415, 5.936549, 5.416117, 5.008537, 4.717795, 4.616600)  # the largest modulus at each radius
STATE = np.array([0.05, 0.1, -0.2, 0.35, 0.1, 0.4, -0.05, -0.3, 0.3, 0.1])  # heading .. hinge rate, contact x, y
# the tinkertoy (the rigid model's data: a plane normal off the axes, a description's `normal`) on a torus foot
# in its leg's y-z plane: curved 0.3 fore-aft, 0.5 sideways, tilted off the axes
TORUS = {"shape": "torus", "radius": 0.2, "tube": 0.3, "normal": (1.0, 0.2, 0.1), "centre": (0.02, 0.01, -0.5)}
# ... on an ellipsoid foot, semi-axes 0.15 forward, 0.4 sideways, 0.3 up (curved 0.075 fore-aft, 0.53 sideways)
ELLIPSOID = {"shape": "ellipsoid", "axes": (0.15, 0.4, 0.3), "centre": (0.02, 0.01, -0.7)}
FEET: dict[str, dict[str, Any]] = {"tinkertoy_ring": {}, "torus": TORUS, "ellipsoid": ELLIPSOID}


def toy_model(foot: dict[str, Any]) -> SpaceModel:
    """The tinkertoy's rigid model with its foot's fields changed to ``foot`` (none: its ring)."""
    config = load_config(TINKERTOY)
    space = config.walker.space
    if foot:
        leg = space.leg.model_copy(update={"foot": SpaceFoot(**foot)})
        space = space.model_copy(update={"leg": leg})
    return space_model(space, config.gravity, config.ground.slope)


def compass_in_space(hip_width: float = 0.0) -> dict[str, Any]:
    """Goswami's compass (configs/compass_goswami.yaml) as a walker in space: zero hip width, the legs' mass on
    their axes, its 1 mm round feet as spheres (a planar walker's gait is the sagittal special case)."""
    body = {"name": "leg", "mass": 5.0, "com": [0.0, -0.5], "inertia_tensor": {"xx": 0.1, "yy": 0.1, "zz": 0.0}}
    foot = {"name": "foot", "body": "leg", "shape": "sphere", "radius": 0.001, "centre": [0.0, -0.999]}
    leg = {"bodies": [body], "feet": [foot]}
    hip = {"name": "hip", "body": "leg_1", "mass": 10.0, "lateral": -0.5 * hip_width}
    description = {"leg": leg, "hip": {"lateral": -hip_width}, "point_masses": [hip]}
    return {"dynamics": "rigid", "gravity": 9.81, "ground": {"slope": 0.0523598775598},
            "walker": {"kind": "description", "description": description}}  # fmt: skip


def test_the_tinkertoy_loads_as_a_walker_in_space() -> None:
    config = load_config(TINKERTOY)
    assert config.walker.kind == "description" and config.in_space
    assert config.walker.leg_length == pytest.approx(1.0)
    model = space_walker_model(config)
    stance, swing = model.parts
    np.testing.assert_allclose(stance.com, [0.0, 0.1812 + 0.6969, -0.6863])
    np.testing.assert_allclose(swing.com, MIRROR @ stance.com)
    np.testing.assert_allclose(swing.inertia, MIRROR @ stance.inertia @ MIRROR)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        (f"{FOOT}.shape=torus", f"{FOOT}.tube: a torus foot needs a tube"),
        (f"{FOOT}.tube=0.1", f"{FOOT}.tube: a torus foot needs a tube"),
        (f"{FOOT}.axes=[1, 1, 1]", f"{FOOT}.axes: an ellipsoid foot needs"),
        (f"{FOOT}.shape=ellipsoid", f"{FOOT}.radius: an ellipsoid foot has"),
        (f"{FOOT}.plane=lateral", f"{FOOT}.plane: only a torus's ring"),
        (
            f"{FOOT}.centre=[0, 0.5]",
            f"{FOOT}.centre: the foot's bottom",
        ),
        (f"{LEG}.mass=0", f"{LEG}.mass: the rigid model in space"),
        (
            f"{LEG}.inertia_tensor.xx=0.5",
            f"{LEG}.inertia_tensor.xx: not",
        ),
        ("walker.space={}", "walker.space: unknown key"),
    ],
)
def test_a_bad_walker_in_space_is_one_line_naming_its_field(override: str, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        load_config(TINKERTOY, [override])
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_a_walker_in_space_refuses_the_planar_paths() -> None:
    from biped_sim.rigid.build import rigid_walker

    with pytest.raises(ConfigError, match=r"^walker: a walker in space"):
        rigid_walker(load_config(TINKERTOY))


def test_a_torus_foot_rests_on_its_tube() -> None:
    """Upright, the torus's bottom is its tube's radius below its ring's, straight down; the leg 0.5 + 0.2 + 0.3."""
    model = toy_model({**TORUS, "normal": (0.0, 1.0, 0.0), "centre": (0.0, 0.0, -0.5)})
    assert model.leg_length == pytest.approx(1.0)
    bottom, d = foot_bottom(model.feet[0], np.eye(3))
    np.testing.assert_allclose(bottom, model.feet[0].centre - [0.0, 0.0, 0.5], atol=1e-15)
    np.testing.assert_allclose(d, [0.0, 0.0, -1.0], atol=1e-15)


def test_a_round_ellipsoid_rolls_as_a_sphere() -> None:
    """An ellipsoid of equal semi-axes r is the sphere of radius r: the same flow (contact point, accelerations)."""
    centre = (0.0, 0.0, -0.8764)
    sphere = {"shape": "sphere", "radius": 0.1236, "centre": centre}
    ellipsoid = {"shape": "ellipsoid", "axes": (0.1236, 0.1236, 0.1236), "centre": centre}
    flows = [dyn.flow(toy_model(foot), STATE) for foot in (sphere, ellipsoid)]
    np.testing.assert_allclose(flows[1], flows[0], rtol=1e-13, atol=1e-14)


@pytest.mark.parametrize("feet", list(FEET))
def test_the_velocities_are_the_positions_rates(feet: str) -> None:
    """Every part's velocity (Kane's A u) is the time derivative of its position, the contact point rolling."""
    model = toy_model(FEET[feet])
    rate, h = dyn.flow(model, STATE), 1e-6

    def positions(x: np.ndarray) -> np.ndarray:
        return np.array([dyn.ground_point(x) + m.r for m in dyn.part_motions(model, x)])

    numeric = (positions(STATE + h * rate) - positions(STATE - h * rate)) / (2 * h)
    np.testing.assert_allclose(numeric, [m.v for m in dyn.part_motions(model, STATE)], atol=1e-9)


def test_the_strike_keeps_the_angular_momenta() -> None:
    """About the new contact point (the whole walker) and about the hinge (the trailing leg), to rounding; the
    walker mirrored, positions and inertias continue."""
    model = space_walker_model(load_config(TINKERTOY))
    section = SpaceSection(model)
    x = section.from_section(section.to_section(STATE * [1, 1, -1, 1, 1, 1, 1, 1, 0, 0]))  # swing foot ahead, down
    x[8:] = 0.3, 0.1
    assert abs(swing_clearance(model, x)) < 1e-14
    before, x_plus = dyn.part_motions(model, x), dyn.strike(model, x)
    after = dyn.part_motions(model, x_plus)
    contact = dyn.ground_point(x_plus)
    np.testing.assert_allclose(contact, MIRROR @ (dyn.ground_point(x) + dyn.swing_foot_point(model, x)), atol=1e-15)
    old = [before[1], before[0]]  # mirrored: the landing (right) leg is the new (left) stance leg
    for o, n in zip(old, after, strict=True):
        np.testing.assert_allclose(MIRROR @ (dyn.ground_point(x) + o.r), contact + n.r, atol=1e-15)

    def momentum(motions: list[dyn.PartMotion], base: np.ndarray, mirror: np.ndarray, det: float) -> np.ndarray:
        return sum(np.cross(mirror @ (base + m.r) - contact, mirror @ (m.mass * m.v)) + det * mirror @ (m.inertia @ m.w)
                   for m in motions)  # fmt: skip

    total_before = momentum(old, dyn.ground_point(x), MIRROR, -1.0)
    np.testing.assert_allclose(momentum(after, contact, np.eye(3), 1.0), total_before, atol=1e-15)
    hinge_point = contact + dyn.pose(model, x_plus).origin  # the hinge's midpoint
    axis = dyn.pose(model, x_plus).hinge

    def trailing(m: dyn.PartMotion, base: np.ndarray, mirror: np.ndarray, det: float) -> float:
        arm = mirror @ (base + m.r) - hinge_point
        return axis @ (np.cross(arm, mirror @ (m.mass * m.v)) + det * mirror @ (m.inertia @ m.w))

    assert trailing(after[1], contact, np.eye(3), 1.0) == pytest.approx(
        trailing(old[1], dyn.ground_point(x), MIRROR, -1.0), abs=1e-15
    )


@pytest.mark.slow
@pytest.mark.parametrize("feet", list(FEET))
def test_the_compiled_flow_is_the_reference_flow(feet: str) -> None:
    model = toy_model(FEET[feet])
    np.testing.assert_allclose(space_flow(space_params(model), STATE), dyn.flow(model, STATE), rtol=1e-13, atol=1e-14)


@pytest.mark.slow
@pytest.mark.parametrize("walker", [*FEET, "compass_sphere"])
def test_the_swing_keeps_its_energy(walker: str) -> None:
    """Energy through 2 natural periods of the stance phase (the rolling foot's contact point moving) to 1e-10."""
    compass = config_from_dict(compass_in_space(0.2)) if walker == "compass_sphere" else None
    model = space_walker_model(compass) if compass else toy_model(FEET[walker])
    params = space_params(model)
    sol = solve_ivp(lambda t, x: space_flow(params, x), (0.0, 0.6), STATE, method="DOP853", rtol=1e-13, atol=1e-13)
    energies = [dyn.energy(model, x) for x in sol.y.T]
    assert np.ptp(energies) < 1e-10 * max(1.0, abs(energies[0]))


@pytest.mark.slow
def test_a_planar_walker_in_space_walks_its_planar_gait() -> None:
    """Goswami's compass written in space: the sagittal fixed point to 1e-9, its multipliers to 1e-6 (the lateral
    ones are the space model's own)."""
    planar = rigid_limit_cycle(
        load_config(CONFIGS / "compass_goswami.yaml", ["dynamics=rigid", "simulation.initial=rigid_limit_cycle"])
    )
    cycle = space_limit_cycle(config_from_dict(compass_in_space()))
    assert planar.converged and cycle.converged
    point = cycle.fixed_point
    angle, rate, swing = (planar.fixed_point[k] for k in ("stance_angle", "stance_rate", "swing_rate"))
    # the planar angles are + foot downhill, the pitch + top downhill; the hinge is swing minus stance pitch
    expected = [-angle, -rate, 2 * angle, rate - swing]
    actual = [point["pitch"], point["omega_y"], point["swing_angle"], point["swing_rate"]]
    np.testing.assert_allclose(actual, expected, atol=1e-9)
    assert max(abs(point[k]) for k in ("heading", "bank", "omega_x", "omega_z")) < 1e-15  # the sagittal plane
    assert cycle.step_period == pytest.approx(planar.step_period, abs=1e-9)
    names = list(cycle.section_names)
    sagittal = [names.index(n) for n in ("pitch", "omega_y", "swing_rate")]
    block = cycle.jacobian[np.ix_(sagittal, sagittal)]
    multipliers = np.sort_complex(np.linalg.eigvals(block))
    np.testing.assert_allclose(multipliers, np.sort_complex(planar.multipliers), atol=1e-6)


def test_a_walker_in_space_takes_no_guess() -> None:
    result = invoke("limit-cycle", str(TINKERTOY), "--guess", "[0.1, 0.2, 0.3, 0.4]")
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith("error: --guess: a walker in space finds its gait without a guess")


@pytest.mark.slow
def test_the_tinkertoy_walks_stably() -> None:
    """Coleman et al.'s toy (configs/space/tinkertoy.yaml) found without a guess by `biped-sim limit-cycle`: the
    README's gait (the search walks the scan, which falls sideways, then continues the sagittal twin's gait)."""
    result = invoke("limit-cycle", str(TINKERTOY), "--json")
    assert result.exit_code == 0, result.output
    cycle = json.loads(result.stdout)
    assert cycle["stable"] and cycle["walker"] == "description"
    assert cycle["step_period"] == pytest.approx(1.00711404, abs=1e-8)
    assert cycle["step_length"] == pytest.approx(0.46483907, abs=1e-8)
    point = cycle["fixed_point"]
    expected = {"heading": 0.09866766, "bank": -0.00924861, "pitch": -0.16016583, "swing_angle": 0.29424124,
                "omega_x": -0.06623178, "omega_y": 0.46696908, "omega_z": -0.13656793,
                "swing_rate": -0.39255917}  # fmt: skip
    assert point == pytest.approx(expected, abs=1e-8)
    moduli = sorted(abs(complex(*m)) for m in cycle["multipliers"])
    np.testing.assert_allclose(moduli, [0.21839504, 0.70796054, 0.70796054, 0.83139588, 0.83139588, 0.83915586,
                                        0.83915586], atol=1e-6)  # fmt: skip


def kuo_compass(radius: float) -> Config:
    """configs/space/kuo_compass_3d.yaml with sphere feet of ``radius``, their bottom 1 m below the hip."""
    return load_config(CONFIGS / "space" / "kuo_compass_3d.yaml", [f"walker.parameters.foot_radius={radius}"])


@pytest.mark.slow
def test_the_kuo_compass_rocks_unstably_until_its_feet_are_round_enough() -> None:
    """Its point-footed gait's unstable mode is the lateral rocking (the eigenvector's largest part the roll rate,
    then the bank); rounder feet shrink that multiplier, along one branch of gaits (README's table)."""
    cycles = space_branch([kuo_compass(r) for r in KUO_RADII])
    assert [c.converged for c in cycles] == [True] * len(KUO_RADII)
    values, vectors = np.linalg.eig(cycles[0].jacobian)
    k = int(np.argmax(np.abs(values)))
    assert values[k] == pytest.approx(KUO_POINT_MULTIPLIER, abs=1e-5)
    roll = np.abs(np.real(vectors[:, k]))
    names = list(cycles[0].section_names)
    assert np.argmax(roll) == names.index("omega_x") and roll[names.index("bank")] > roll[names.index("pitch")]
    largest = [c.max_multiplier_modulus for c in cycles]
    assert largest == pytest.approx(KUO_LARGEST, abs=1e-5)
