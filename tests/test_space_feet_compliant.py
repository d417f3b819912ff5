"""Compliant torus and ellipsoid feet in the spatial formulation (:func:`~biped_sim.multibody.spatial_feet.
foot_bottom`): their lowest point against the ground where geometry puts it, their limits (a torus of no tube is
the ring, of no ring radius the sphere; an ellipsoid of equal axes the sphere), a body resting on one at the Hertz
static sinkage, and a rocking body's energy audit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim.config import IntegratorConfig, MaterialsConfig, load_config
from biped_sim.contact.normal import hertz_stiffness
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.euler_parameters import rotate
from biped_sim.multibody.spatial import SpatialSystem
from biped_sim.multibody.spatial_feet import foot_bottom, foot_kinematics
from biped_sim.multibody.spatial_kernels import mechanical_energy
from biped_sim.simulate import prepare_model, simulate
from biped_sim.simulate.compliant import summarize
from biped_sim.studies.friction_checks import dry_limit_parameters
from biped_sim.studies.incline import default_contact, spatial_sphere
from biped_sim.walkers import build_model
from biped_sim.walkers.model import standing_start
from tests.test_space_compliant import GAIT, TINKERTOY, tinkertoy

FOOT = "walker.description.leg.feet.foot"

RADIUS, TUBE = 0.08, 0.03  # [m] the ring's radius and the torus's tube
AXES = (0.12, 0.05, 0.08)  # [m] the ellipsoid's semi-axes along the body's x', y' (up), z': resting on the shortest
SAGITTAL = np.array([0.0, 0.0, 1.0])
UP = np.array([0.0, 1.0, 0.0])  # a disc's axis: its plane the body's x'-y' plane
# a generic attitude (not unit: the kernels take |p| != 1 as the integration leaves it) and rates
P = np.array([0.93, 0.21, -0.17, 0.26])
STATE = np.array([0.01, 0.2, -0.03, *P, 0.3, -0.1, 0.2, 0.05, -0.4, 0.3, 0.2])
INTEGRATOR = IntegratorConfig(method="dopri5", rtol=1e-10, atol=1e-13, max_step=1e-3)


def one_body(axis: np.ndarray = SAGITTAL, radius: float = RADIUS, tube: float = 0.0, axes: tuple = ()) -> SpatialSystem:
    """A free body of the incline checks (mass 1, its foot's centre at its centre of mass) with a disc of ``axis``
    and ``radius`` (axis 0: a sphere), a torus's ``tube`` or an ellipsoid of ``axes``; default contact and Hertz
    stiffness of the foot's upright bottom."""
    system, _, _ = spatial_sphere("ambrosio", dry_limit_parameters(1.0), 0.0)
    if axes:
        hertz = axes[0] * axes[2] / axes[1]  # upright (y' up): curved ax^2 / ay and az^2 / ay
    else:
        hertz = math.sqrt((radius + tube) * tube) if tube else radius
    normal, _, _ = default_contact(hertz, 9.81)
    quadric = np.diag(np.square(axes))[None] if axes else np.zeros((1, 3, 3))
    return system._replace(
        foot_axis=axis[None],
        foot_radius=np.array([radius]),
        foot_tube=np.array([tube]),
        foot_quadric=quadric,
        normal_params=normal,
    )


def kinematics(system: SpatialSystem) -> np.ndarray:
    """foot_kinematics at the generic state (bristles and work zero)."""
    return np.array(foot_kinematics(np.concatenate([STATE, np.zeros(4)]), system, 0))


def rotation(p: np.ndarray) -> np.ndarray:
    """The unit rotation of parameters p (rotate's columns over |p|^2)."""
    return np.array([rotate(tuple(p), tuple(e)) for e in np.eye(3)]).T / (p @ p)


def test_a_torus_without_tube_is_the_ring_and_without_ring_radius_the_sphere() -> None:
    ring = kinematics(one_body())
    np.testing.assert_allclose(kinematics(one_body(tube=1e-300)), ring, rtol=1e-15, atol=1e-17)
    sphere = kinematics(one_body(np.zeros(3), RADIUS))
    np.testing.assert_allclose(kinematics(one_body(radius=0.0, tube=RADIUS)), sphere, rtol=1e-15, atol=1e-17)


def test_an_ellipsoid_of_equal_axes_is_the_sphere() -> None:
    sphere = kinematics(one_body(np.zeros(3), RADIUS))
    np.testing.assert_allclose(
        kinematics(one_body(np.zeros(3), 0.0, axes=(RADIUS,) * 3)), sphere, rtol=1e-14, atol=1e-16
    )


def test_the_ellipsoid_s_bottom_lies_on_it_where_its_normal_is_the_ground_s() -> None:
    """(P - c)^T Q_w^-1 (P - c) = 1 with Q_w = A Q A^T, and the outward normal Q_w^-1 (P - c) along -y; the lever
    A s' = P - r to rounding (also off the unit sphere of parameters)."""
    system = one_body(np.zeros(3), 0.0, axes=AXES)
    centre, bottom, lever = foot_bottom(tuple(P), system, 0)
    a = rotation(P)
    q_w = a @ np.diag(np.square(AXES)) @ a.T
    u = np.linalg.solve(q_w, np.array(bottom) * 1.0)
    assert np.array(bottom) @ u == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(u / np.linalg.norm(u), [0.0, -1.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(rotate(tuple(P), lever), np.add(centre, bottom), atol=1e-16)


def test_the_torus_s_bottom_is_its_lowest_point() -> None:
    """Against the torus sampled densely on its surface (c + (R + r cos v) e(u) + r sin v a): no point is lower, and
    the nearest sample is within the grid's sag of the bottom."""
    system = one_body(tube=TUBE)
    _, bottom, _ = foot_bottom(tuple(P), system, 0)
    a = rotation(P)
    axis, e1, e2 = a @ SAGITTAL, a @ np.array([1.0, 0.0, 0.0]), a @ np.array([0.0, 1.0, 0.0])
    u, v = np.meshgrid(np.linspace(0.0, 2 * np.pi, 2001), np.linspace(0.0, 2 * np.pi, 2001))
    ring = np.cos(u)[..., None] * e1 + np.sin(u)[..., None] * e2
    points = (RADIUS + TUBE * np.cos(v))[..., None] * ring + (TUBE * np.sin(v))[..., None] * axis
    heights = points[..., 1].ravel()
    assert heights.min() >= bottom[1] - 1e-15
    assert heights.min() - bottom[1] < 1e-5
    nearest = points.reshape(-1, 3)[np.argmin(heights)]
    assert np.linalg.norm(nearest - np.array(bottom)) < 1e-3


def settled(
    system: SpatialSystem,
    height: float,
    sinkage: float,
    spin: tuple = (0.0, 0.0, 0.0),
    attitude: tuple = (1.0, 0.0, 0.0, 0.0),
    normal: np.ndarray = UP,
) -> tuple:
    """(system, run) of the body released at rest (or at ``spin``) upright (or at ``attitude``), its bottom ``height``
    above its centre (along ``normal``, the ground's at the origin), sunk 1.5 times ``sinkage``, run 1 s."""
    q = np.array([[*((height - 1.5 * sinkage) * normal), *attitude]])
    qd = np.array([[0.0, 0.0, 0.0, 0.0, *(0.5 * w for w in spin)]])
    y0, modes0 = standing_start(system, q, qd, (0,), 1e-2)  # its damping near critical
    return integrate_model(system, y0, modes0, INTEGRATOR, t_end=1.0, sample_rate=100.0)


@pytest.mark.parametrize(
    ("system", "height", "hertz"),
    [
        (one_body(tube=TUBE), RADIUS + TUBE, math.sqrt((RADIUS + TUBE) * TUBE)),
        (one_body(np.zeros(3), 0.0, axes=AXES), AXES[1], AXES[0] * AXES[2] / AXES[1]),
    ],
    ids=["torus", "ellipsoid"],
)
def test_a_torus_or_ellipsoid_at_rest_sinks_to_the_hertz_static_sinkage(
    system: SpatialSystem, height: float, hertz: float
) -> None:
    m = MaterialsConfig()
    k = hertz_stiffness(m.foot.youngs_modulus, m.foot.poisson_ratio, m.ground.youngs_modulus, m.ground.poisson_ratio,
                        hertz)  # fmt: skip
    sinkage = (9.81 / k) ** (2.0 / 3.0)
    run = settled(system, height, sinkage)
    assert run.status == "walking"
    assert foot_kinematics(run.y[-1], system, 0)[0] == pytest.approx(sinkage, rel=1e-9)


def test_a_rocking_ellipsoid_s_energy_audit_closes() -> None:
    """Released spinning about a tilted axis, it rocks and slides on its bottom: E(t) - E(0) + W(t) stays at
    1e-11 of its energy scale m g a_y (measured 6e-14)."""
    system = one_body(np.zeros(3), 0.0, axes=AXES)
    run = settled(system, AXES[1], 1e-5, spin=(1.5, 0.4, 2.0))
    assert run.status == "walking"
    total = np.array(
        [sum(mechanical_energy(y, system, modes)) + y[-2] + y[-1] for y, modes in zip(run.y, run.modes, strict=True)]
    )
    assert np.ptp(total) < 1e-11 * 9.81 * AXES[1]


@pytest.mark.parametrize("shape", ["torus", "ellipsoid"])
def test_the_compliant_tinkertoy_stands_on_a_torus_or_ellipsoid_foot_at_its_static_sinkage(shape: str) -> None:
    """The builder turns the foot into the body frame: the stance foot's bottom at rest, sunk by the static
    penetration of the foot's Hertz radius, its contact point at the origin."""
    feet = {
        "torus": [f"{FOOT}.shape=torus", f"{FOOT}.radius=0.0836", f"{FOOT}.tube=0.04"],
        "ellipsoid": [f"{FOOT}.shape=ellipsoid", f"{FOOT}.radius=0", f"{FOOT}.axes=[0.15, 0.1236, 0.06]"],
    }  # fmt: skip
    model = build_model(tinkertoy(*feet[shape]), GAIT)
    stance = foot_kinematics(model.y0, model.system, 0)
    assert stance[0] == pytest.approx(model.meta["static_penetration"], abs=1e-14)
    assert np.abs(stance[1:6]).max() < 1e-14


# the toy on a torus of tube 0.04 (tests/test_space_feet.py's tinkertoy_torus: the ring's sagittal radius kept) and on
# an ellipsoid of the same curvatures at its bottom (sagittal section the ring's circle, lateral radius
# 0.0703^2 / 0.1236 = 0.04): their rigid gaits continued from the ring's (space_branch; largest multiplier 0.891851,
# 0.891845), to 10 digits, and periods
FEET_GAITS = {
    "torus": (
        (f"{FOOT}.shape=torus", f"{FOOT}.radius=0.0836", f"{FOOT}.tube=0.04"),
        {"heading": 0.0986775523, "bank": -0.0092990084, "pitch": -0.1602524846, "swing_angle": 0.2942753680,
         "omega_x": -0.0662955525, "omega_y": 0.4670420087, "omega_z": -0.1366943630, "swing_rate": -0.3928620197},
        1.0066117993,
    ),
    "ellipsoid": (
        (f"{FOOT}.shape=ellipsoid", f"{FOOT}.radius=0", f"{FOOT}.axes=[0.1236, 0.1236, 0.0703]"),
        {"heading": 0.0986775491, "bank": -0.0092989917, "pitch": -0.160252456, "swing_angle": 0.2942753569,
         "omega_x": -0.0662955366, "omega_y": 0.467041976, "omega_z": -0.1366943235, "swing_rate": -0.3928619259},
        1.0066119537,
    ),
}  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize("shape", list(FEET_GAITS))
def test_on_torus_or_ellipsoid_feet_the_first_compliant_step_approaches_the_rigid_one_as_the_contact_stiffens(
    shape: str,
) -> None:
    """The toy on tori or ellipsoids from its rigid gait at K = 1e5, 1e6, 1e7: the first step's period error against
    the rigid period falls with each decade (as on rings, tests/test_space_compliant.py; measured on tori 2.7e-3,
    6.4e-4, 2.3e-4, on ellipsoids the same to 2 digits: the first step is sagittal, their sagittal radius the ring's),
    and the energy audit closes."""
    foot, gait, period = FEET_GAITS[shape]
    errors = []
    for stiffness in (1e5, 1e6, 1e7):
        initial = "simulation.initial=" + repr(gait).replace("'", '"')
        config = load_config(TINKERTOY, [*foot, initial, f"contact.stiffness={stiffness}", "simulation.t_end=1.5"])
        result = simulate(config, model=prepare_model(config))
        assert summarize(result)["energy_residual_max_relative"] < 1e-6
        errors.append(abs(result.heel_strike_times[0] - period) / period)
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 3e-4
