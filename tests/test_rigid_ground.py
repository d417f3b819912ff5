"""The rigid heel strike on a ground profile: the energy of a step down, the landing height, risers, the impact."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import load_config, simulate
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.ground import Footing, ProfileStrike, RigidGround
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.simulate.rigid import RigidRunResult

from .conftest import CONFIGS, invoke, one_line_error

SIMPLEST = CONFIGS / "simplest_walker.yaml"
ROUND_FOOT = CONFIGS / "round_foot_walker.yaml"


def _on_cycle(path, *overrides: str) -> list[str]:  # type: ignore[no-untyped-def]
    """Overrides that start the rigid walker of ``path`` on its limit cycle (found once per walker)."""
    config = load_config(path, ["dynamics=rigid", *overrides])
    legs = rigid_limit_cycle(config).fixed_point
    return ["dynamics=rigid", "simulation.initial={" + ", ".join(f"{k}: {v!r}" for k, v in legs.items()) + "}"]


@pytest.fixture(scope="module")
def simplest_start() -> list[str]:
    return _on_cycle(SIMPLEST)


@pytest.fixture(scope="module")
def round_foot_start() -> list[str]:
    return _on_cycle(ROUND_FOOT)


def _step_down_run(path, start: list[str], height: float, at: float, steps: int = 3) -> RigidRunResult:  # type: ignore[no-untyped-def]
    profile = f"ground.profile={{kind: steps, steps: [{{at: {at!r}, height: {-height!r}}}]}}"
    result = simulate(load_config(path, [*start, profile, f"simulation.max_steps={steps}", "simulation.t_end=100"]))
    assert isinstance(result, RigidRunResult)
    return result


@pytest.mark.parametrize(("path", "height", "at"), [(SIMPLEST, 1e-3, 0.6), (ROUND_FOOT, 2e-3, 0.45)])
def test_a_step_down_adds_m_g_h_to_the_energy_budget(path, height: float, at: float, request) -> None:  # type: ignore[no-untyped-def]
    start = request.getfixturevalue("simplest_start" if path == SIMPLEST else "round_foot_start")
    result = _step_down_run(path, start, height, at)
    assert result.status == "walking"
    walker = result.walker
    # the budget closes across the step down: E(t) - E(0) + impact losses = 0 to the integration error
    assert np.max(np.abs(result.energy.residual)) < 1e-10 * walker.reference_mass * walker.gravity
    # the potential of the same state on the lower level is lower by exactly m_total g h (h along the slope
    # normal: its vertical part is h cos(gamma))
    weight = walker.reference_mass * walker.gravity
    after = result.strike_time[1] < result.time  # samples of the step taken on the lower level
    first = np.argmax(after)
    flat = walker.energy(result.state[first])[1]
    down = result.energy.potential[first]
    hip_x = result.hip[first, 0]
    theta = result.state[first, 0]
    contact_x = hip_x + (walker.leg_length - walker.foot_radius) * math.sin(theta)
    slope_part = -weight * math.sin(walker.slope) * (contact_x + walker.foot_radius * theta)
    assert flat + slope_part - down == pytest.approx(weight * height * math.cos(walker.slope), rel=1e-9)


def test_the_swing_foot_lands_on_the_profile(round_foot_start: list[str]) -> None:
    result = _step_down_run(ROUND_FOOT, round_foot_start, 2e-3, 0.45, steps=2)
    walker = result.walker
    l, R = walker.leg_length, walker.foot_radius
    # the hip after the second strike: its stance foot's arc centre R above the lower level
    theta = result.strike_post[1, 0]
    index = np.searchsorted(result.time, result.strike_time[1])
    assert result.time[index] == result.strike_time[1]
    assert result.hip[index, 1] == pytest.approx(-2e-3 + R + (l - R) * math.cos(theta), abs=1e-12)
    # on the plane the strike is the walker's own symmetric guard; on the lower level the swing foot's arc
    # comes down h below the stance foot's: the stance leg leans further than the landing leg
    assert abs(result.strike_pre[0, 0] + result.strike_pre[0, 1]) < 1e-12
    stance, swing = result.strike_pre[1, :2]
    assert (l - R) * (math.cos(stance) - math.cos(swing)) == pytest.approx(-2e-3, abs=1e-13)
    assert -stance > swing


def test_a_riser_in_the_swing_foots_way_trips_the_walker() -> None:
    config = load_config(SIMPLEST)
    walker = rigid_walker(config)
    x0 = np.array([0.2003109, -0.2003109, -0.1998325, -0.1998325 * math.cos(0.4006218)])
    flat = rigid_step(walker, x0)
    landing = flat.length  # where the swing foot lands on the plane
    riser = RigidGround(np.array([[landing - 0.15, 0.0], [landing - 0.15, 0.05]]), np.zeros(2))
    tripped = rigid_step(walker, x0, profile=ProfileStrike(walker, riser, Footing(0.0, 0.0)))
    assert tripped.status == "tripped"
    foot_x, foot_y = ProfileStrike(walker, riser, Footing(0.0, 0.0)).swing_foot(tripped.x_minus)
    assert foot_x == pytest.approx(landing - 0.15, abs=1e-9) and 0.0 < foot_y < 0.05
    # the same step up beyond the landing point is never reached: an ordinary strike on the plane
    beyond = RigidGround(np.array([[landing + 0.05, 0.0], [landing + 0.05, 0.05]]), np.zeros(2))
    step = rigid_step(walker, x0, profile=ProfileStrike(walker, beyond, Footing(0.0, 0.0)))
    assert step.status == "strike"
    np.testing.assert_allclose(step.x_plus, flat.x_plus, atol=1e-12)


def test_the_simplest_walkers_strike_is_garcias_map_when_the_legs_are_symmetric() -> None:
    walker = rigid_walker(load_config(SIMPLEST))
    theta, theta_d = -0.21, -0.23
    c2 = math.cos(2.0 * theta)  # MODEL.md 8: theta+ = -theta, thetadot+ = c2 thetadot, thetadot_sw+ = c2^2 thetadot
    garcia = np.array([-theta, theta, c2 * theta_d, c2 * c2 * theta_d])
    np.testing.assert_allclose(walker.impact(np.array([theta, -theta, theta_d, -0.05])), garcia, rtol=0, atol=1e-15)
    # asymmetric legs (a step down): the hip mass keeps its angular momentum about the new contact point,
    # |r x v| with r the new stance leg (unit length) and v = thetadot * (cos theta, sin theta)
    theta, theta_sw, theta_d = -0.22, 0.25, -0.2
    after = walker.impact(np.array([theta, theta_sw, theta_d, 0.0]))
    leg_new = np.array([-math.sin(theta_sw), math.cos(theta_sw)])
    v_before = -theta_d * np.array([math.cos(theta), math.sin(theta)])
    v_after = -after[2] * np.array([math.cos(after[0]), math.sin(after[0])])
    cross = leg_new[0] * v_before[1] - leg_new[1] * v_before[0]
    assert leg_new[0] * v_after[1] - leg_new[1] * v_after[0] == pytest.approx(cross, rel=1e-14)
    # the new swing leg's infinitesimal foot, at rest before, gets only an impulse along its massless leg
    assert after[3] == pytest.approx(math.cos(theta_sw - theta) * after[2], rel=1e-14)


def test_a_flat_polyline_walks_as_the_plane(round_foot_start: list[str]) -> None:
    # the profile's guard (the swing foot out of its mid-stance scuff, then its clearance) finds the plane's strikes
    overrides = [*round_foot_start, "simulation.max_steps=4", "simulation.t_end=100"]
    plane = simulate(load_config(ROUND_FOOT, overrides))
    polyline = simulate(
        load_config(ROUND_FOOT, [*overrides, "ground.profile={kind: polyline, x: [-1, 0.5, 9], height: [0, 0, 0]}"])
    )
    assert plane.status == polyline.status == "walking"
    np.testing.assert_allclose(polyline.strike_time, plane.strike_time, rtol=0, atol=1e-11)
    np.testing.assert_allclose(polyline.strike_post, plane.strike_post, rtol=0, atol=1e-9)


@pytest.mark.parametrize("height", [0.004, 0.005])  # 0.8 and 1 % of the leg
def test_the_mid_stance_scuff_after_a_step_down_is_not_a_strike(round_foot_start: list[str], height: float) -> None:
    # after the step down the swing leg lags: it passes the stance leg after the stance leg has passed the
    # normal, its foot dipping below the stance level (and leaving it exactly at the plane's strike guard)
    result = _step_down_run(ROUND_FOOT, round_foot_start, height, 0.444, steps=5)
    assert result.status == "walking"
    assert np.min(np.diff(result.strike_time)) > 0.35  # the gait's period is 0.43 s; no step cut at mid-stance


def test_the_limit_cycle_command_refuses_a_profile() -> None:
    profile = "ground.profile={kind: steps, steps: [{at: 0.6, height: -0.001}]}"
    result = invoke("limit-cycle", str(SIMPLEST), "--set", profile)
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith("error: ground.profile: ")
