"""Ground profiles (issue 12): the contact geometry against hand-computed cases, the profile schema, a walker
on a flat polyline against the flat ground, and the energy balance on a step down."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from biped_sim import simulate
from biped_sim.animate import WalkerDrawing
from biped_sim.config import config_from_dict
from biped_sim.contact.ground import (
    FLAT_ENDS,
    FLAT_VERTICES,
    FlatGround,
    ProfileGround,
    ground_contact,
    ground_contacts,
    ground_height,
    ground_window,
)
from biped_sim.contact.profile import FlatProfile, StepsProfile, profile_arrays, profile_outline
from biped_sim.contact.response import guard_arms
from biped_sim.errors import ConfigError
from biped_sim.io.trajectory import load_run
from biped_sim.multibody.minimal import tree_system
from biped_sim.multibody.planar import foot_contact
from biped_sim.studies.limit_cycle import compliant_limit_cycle
from biped_sim.testing import default_walker
from biped_sim.walkers import build_model

LEVEL = np.zeros(2)
STEP_DOWN = "ground.profile={kind: steps, steps: [{at: 0.45, height: -0.005}]}"


def touching(cx: float, cy: float, radius: float, vertices: np.ndarray, ends: np.ndarray = LEVEL) -> list[tuple]:
    """The penetrating features of a circle, deepest first: (delta, P_x, P_y, n_x, n_y, sign)."""
    first, count = ground_window(cx, radius, vertices)
    features = [ground_contacts(cx, cy, radius, vertices, ends, first, count, f) for f in range(count)]
    return sorted((f for f in features if f[0] > 0.0), reverse=True)


def test_circle_on_a_sloped_segment() -> None:
    vertices = np.array([[0.0, 0.0], [1.0, 0.1]])
    n = np.array([-0.1, 1.0]) / math.sqrt(1.01)
    on_line, radius, depth = np.array([0.5, 0.05]), 0.1, 0.002
    centre = on_line + (radius - depth) * n
    [(delta, px, py, nx, ny, sign)] = touching(*centre, radius, vertices)
    assert sign == 1.0
    assert delta == pytest.approx(depth, abs=1e-15)
    assert (px, py) == pytest.approx(tuple(on_line - depth * n), abs=1e-15)
    assert (nx, ny) == pytest.approx(tuple(n), abs=1e-15)


def test_circle_on_a_convex_corner() -> None:
    # a 5 cm step down at x = 1; the centre 3 cm past the edge, 4 cm above it: 5 cm from the corner
    vertices = np.array([[1.0, 0.0], [1.0, -0.05]])
    [(delta, px, py, nx, ny, sign)] = touching(1.03, 0.04, 0.06, vertices)
    assert sign == 1.0
    assert delta == pytest.approx(0.01, abs=1e-15)
    assert (nx, ny) == pytest.approx((0.6, 0.8), abs=1e-15)
    assert (px, py) == pytest.approx((0.994, -0.008), abs=1e-15)
    assert ground_contact(1.03, 0.04, 0.06, vertices, LEVEL) == pytest.approx((delta, px, py, nx, ny), abs=1e-15)


def test_circle_in_a_concave_corner_touches_the_riser_and_the_tread() -> None:
    # a 5 cm step up at x = 1; a 4 cm foot pushed 2 mm into the riser and 1 mm into the tread
    vertices = np.array([[1.0, 0.0], [1.0, 0.05]])
    riser, tread = touching(1.0 - 0.038, 0.039, 0.04, vertices)
    assert riser == pytest.approx((0.002, 1.002, 0.039, -1.0, 0.0, 1.0), abs=1e-15)
    assert tread == pytest.approx((0.001, 0.962, -0.001, 0.0, 1.0, 1.0), abs=1e-15)  # the corner is 5.4 cm away


def contact_energy(cx: float, cy: float, radius: float, vertices: np.ndarray) -> float:
    """The foot's contact energy over K (Hertz, n = 1.5): the sum of sign delta^2.5 / 2.5 of its features."""
    return sum(sign * delta**2.5 / 2.5 for delta, *_, sign in touching(cx, cy, radius, vertices))


def test_a_shallow_valley_pushes_like_a_plane_not_twice() -> None:
    # a 1 mrad valley at x = 1, the foot over it pressed 0.1 mm in: both faces and the corner (subtracted) touch
    vertices = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.001]])
    radius, depth = 0.15, 1e-4
    features = touching(1.0 - 1e-6, radius - depth, radius, vertices)
    assert sorted(f[5] for f in features) == [-1.0, 1.0, 1.0]
    assert contact_energy(1.0 - 1e-6, radius - depth, radius, vertices) == pytest.approx(depth**2.5 / 2.5, rel=1e-2)


def test_the_contact_energy_is_continuous_across_a_valley() -> None:
    # a level tread, then a 45-degree rise from x = 1: the edges of the region over both faces are x = 1 - C_y
    # (the rise's projection begins) and x = 1 (the tread's ends); there the corner's term cancels a face's
    vertices = np.array([[0.0, 0.0], [1.0, 0.0], [1.1, 0.1]])
    radius, cy = 0.05, 0.03
    for edge in (1.0 - cy, 1.0):
        before, after = (contact_energy(cx, cy, radius, vertices) for cx in (edge - 1e-13, edge + 1e-13))
        assert after == pytest.approx(before, rel=1e-9)
    assert len(touching(1.0 - cy / 2, cy, radius, vertices)) == 3  # between the edges: both faces and the corner


def test_deepest_feature_is_the_distance_to_the_polyline() -> None:
    rng = np.random.default_rng(3)
    vertices = np.column_stack([np.cumsum(rng.uniform(0.02, 0.1, 30)), rng.normal(0.0, 0.02, 30)])
    radius = 0.1
    for _ in range(300):
        cx = rng.uniform(vertices[0, 0], vertices[-1, 0])
        cy = ground_height(cx, vertices, LEVEL) + rng.uniform(0.0, radius)
        delta = ground_contact(cx, cy, radius, vertices, LEVEL)[0]
        assert delta == pytest.approx(radius - distance_to_polyline(cx, cy, vertices), abs=1e-12)


def distance_to_polyline(cx: float, cy: float, vertices: np.ndarray) -> float:
    """Brute force: the least distance from (cx, cy) to the closed segments (the level rays included)."""
    far = 1e3
    points = np.vstack([[vertices[0, 0] - far, vertices[0, 1]], vertices, [vertices[-1, 0] + far, vertices[-1, 1]]])
    best = math.inf
    for a, b in itertools.pairwise(points):
        t = np.clip(np.dot([cx, cy] - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
        best = min(best, float(np.hypot(*([cx, cy] - (a + t * (b - a))))))
    return best


def test_point_foot_inside_the_ground_touches_the_nearest_surface_only() -> None:
    vertices = np.array([[1.0, 0.0], [1.0, -0.05]])  # step down: the point is 1 mm under the upper tread
    assert touching(0.99, -0.001, 0.0, vertices) == [pytest.approx((0.001, 0.99, -0.001, 0.0, 1.0, 1.0), abs=1e-15)]


def test_flat_ground_and_a_flat_polyline_give_the_same_bits() -> None:
    rng = np.random.default_rng(1)
    polyline = np.array([[-1.0, 0.0], [0.3, 0.0], [2.0, 0.0]])
    for cx, cy in zip(rng.uniform(-2, 3, 200), rng.uniform(-0.01, 0.2, 200), strict=True):
        flat = ground_contact(cx, cy, 0.15, FLAT_VERTICES, FLAT_ENDS)
        assert flat == ground_contact(cx, cy, 0.15, polyline, LEVEL)
        assert flat[:3] == (0.15 - cy, cx, cy - 0.15)


def test_ground_height_of_each_profile_kind() -> None:
    steps = profile_arrays(StepsProfile(steps=[{"at": 1.0, "height": -0.05}, {"at": 2.0, "height": 0.02}]), 0.02)
    assert [ground_height(x, *steps) for x in (0.5, 1.0, 1.5, 2.0, 3.0)] == pytest.approx(
        [0, -0.05, -0.05, -0.03, -0.03]
    )
    change = profile_arrays(
        config_from_dict({}, ["ground.profile={kind: slope_change, at: 1, slope: 0.05}"]).ground.profile, 0.02
    )
    assert ground_height(0.5, *change) == 0.0
    assert ground_height(2.0, *change) == pytest.approx(-math.tan(0.03))
    polyline = profile_arrays(
        config_from_dict({}, ["ground.profile={kind: polyline, x: [0, 1, 2], height: [0, 0.1, 0]}"]).ground.profile, 0.0
    )
    assert [ground_height(x, *polyline) for x in (-1.0, 0.5, 1.5, 5.0)] == pytest.approx([0.0, 0.05, 0.05, 0.0])
    rough = config_from_dict({}, ["ground.profile={kind: random, spacing: 0.1, roughness: 0.01, seed: 7, length: 2}"])
    vertices, _ = profile_arrays(rough.ground.profile, 0.02)
    assert vertices.shape == (21, 2) and vertices[0, 1] == 0.0 and vertices[0, 0] == 0.3
    assert np.array_equal(vertices, profile_arrays(rough.ground.profile, 0.02)[0])  # the seed fixes it
    assert 0.003 < np.std(vertices[1:, 1]) < 0.03


def test_outline_for_drawing_keeps_the_risers() -> None:
    vertices, ends = profile_arrays(StepsProfile(steps=[{"at": 1.0, "height": -0.05}]), 0.02)
    outline = profile_outline(vertices, ends, 0.0, 2.0)
    assert outline.tolist() == [[0.0, 0.0], [1.0, 0.0], [1.0, -0.05], [2.0, -0.05]]


@pytest.mark.parametrize(
    ("profile", "field"),
    [
        ("{kind: steps, steps: [{at: 1, height: 0}]}", "ground.profile.steps.0.height"),
        ("{kind: steps, steps: [{at: 1, height: 0.1}, {at: 0.5, height: 0.1}]}", "ground.profile.steps"),
        ("{kind: polyline, x: [0, 1, 2], height: [0, 1]}", "ground.profile.height"),
        ("{kind: polyline, x: [0, 2, 1], height: [0, 1, 0]}", "ground.profile.x"),
        ("{kind: polyline, x: [0, .inf], height: [0, 0]}", "ground.profile.x.1"),
        ("{kind: random, spacing: -0.1}", "ground.profile.spacing"),
        ("{kind: random, roughness: -0.1}", "ground.profile.roughness"),
        ("{kind: slope_change, at: 1, slope: 2}", "ground.profile.slope"),
        ("{kind: stairs}", "ground.profile"),
        ("{kind: steps, steps: [{at: true, height: 0.1}]}", "ground.profile.steps.0.at"),
        ("{kind: random, seed: -1}", "ground.profile.seed"),
        ("{kind: steps, steps: [{at: -1, height: 0.1}]}", "ground.profile"),
    ],
)
def test_bad_profiles_are_one_line_errors_naming_the_field(profile: str, field: str) -> None:
    with pytest.raises(ConfigError) as error:
        config_from_dict({}, [f"ground.profile={profile}"])
    assert error.value.field == field
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("other", ["friction.model=lugre"])
def test_profiles_are_refused_where_they_are_not_modelled(other: str) -> None:
    with pytest.raises(ConfigError, match=r"^ground\.profile: "):
        config_from_dict({}, [STEP_DOWN, other])


def test_the_flat_profile_is_the_default_and_hashes_like_it() -> None:
    flat = config_from_dict({}, ["ground.profile={kind: flat}"])
    assert flat.hash() == config_from_dict({}).hash()
    assert flat.hash() != config_from_dict({}, ["ground.profile={kind: polyline, x: [0, 1], height: [0, 0]}"]).hash()


def test_walker_on_a_flat_polyline_walks_exactly_as_on_the_flat_ground() -> None:
    flat = simulate(default_walker(t_end=1.0)).summary
    polyline = simulate(
        default_walker("ground.profile={kind: polyline, x: [-5, 0.26, 50], height: [0, 0, 0]}", t_end=1.0)
    ).summary
    assert flat["n_steps"] >= 2
    assert polyline["step_times"] == flat["step_times"]  # exactly: the same arithmetic through the general path
    assert polyline["energy_dissipated"] == flat["energy_dissipated"]


def test_flat_runs_hold_the_flat_ground_type_and_profile_runs_their_arrays() -> None:
    # the kernels specialise on the ground's type: a flat run compiles the plane's arithmetic alone
    assert default_walker().ground.profile == FlatProfile()
    flat = build_model(default_walker()).system
    assert type(flat.ground) is FlatGround
    stepped = build_model(default_walker(STEP_DOWN)).system
    assert type(stepped.ground) is ProfileGround
    np.testing.assert_array_equal(stepped.ground.vertices, [[0.45, 0.0], [0.45, -0.005]])
    assert type(tree_system(stepped).ground) is ProfileGround


def test_minimal_coordinates_walk_down_a_step_as_the_planar_formulation() -> None:
    # the same walker and profile in both formulations: one contact source (contact.response), the same gait
    tight = ("integrator.rtol=1e-10", "integrator.atol=1e-12")
    planar = simulate(default_walker(STEP_DOWN, *tight, t_end=1.0)).summary
    minimal = simulate(default_walker(STEP_DOWN, *tight, "formulation.kind=minimal", t_end=1.0)).summary
    assert planar["status"] == minimal["status"] == "walking" and planar["n_steps"] >= 2
    np.testing.assert_allclose(minimal["step_times"], planar["step_times"], rtol=0, atol=1e-6)


def test_energy_balance_closes_on_a_step_down() -> None:
    config = default_walker(STEP_DOWN, "integrator.rtol=1e-6", "integrator.atol=1e-8", t_end=1.0)
    result = simulate(config)
    assert result.summary["status"] == "walking" and result.summary["n_steps"] >= 2
    strikes_x = [
        foot_contact(y, result.model.system, foot)[2]
        for y, foot in zip(result.run.strike_y, result.run.strike_foot, strict=True)
    ]
    assert strikes_x[0] < 0.45 < strikes_x[1]  # the second heel strike lands below the step
    m_g_l = result.model.total_mass * config.gravity * config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-6 * m_g_l
    assert result.summary["energy_dissipated"]["normal"] > 1e-3 * m_g_l  # the check is not trivially satisfied


def test_animation_draws_the_profile(tmp_path: Path) -> None:
    simulate(default_walker(STEP_DOWN, t_end=0.3)).write(tmp_path / "run")
    fig = Figure()
    FigureCanvasAgg(fig)
    drawing = WalkerDrawing(load_run(tmp_path / "run"), fig)
    surface = drawing.walker.world.T @ np.vstack(drawing.ax.lines[0].get_data())  # back to the slope frame
    riser = surface[:, np.isclose(surface[0], 0.45)]
    np.testing.assert_allclose(riser.T, [[0.45, 0.0], [0.45, -0.005]], atol=1e-12)


def test_compliant_limit_cycle_needs_the_flat_ground() -> None:
    with pytest.raises(ConfigError, match=r"^ground\.profile: "):
        compliant_limit_cycle(default_walker(STEP_DOWN))


def test_a_foot_leaving_the_ground_at_an_event_located_exactly_at_zero_penetration_is_armed() -> None:
    # the event functions' sides are > 0 and <= 0: an event root found at delta = 0.0 exactly is "not in the ground"
    assert guard_arms(True, False, 0.0, 0.01)
    assert not guard_arms(True, False, 1e-12, 0.01)


@pytest.mark.slow
def test_walks_on_random_ground_and_the_energy_balance_closes() -> None:
    config = default_walker("ground.profile={kind: random, roughness: 0.0005, seed: 1}", t_end=5.0)
    result = simulate(config)
    assert result.status == "walking" and result.summary["n_steps"] >= 10
    m_g_l = result.model.total_mass * config.gravity * config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-7 * m_g_l
