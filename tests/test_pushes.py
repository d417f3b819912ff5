"""Pushes (simulation.pushes): an impulse on the hip, consistent with the joints, booked in the energy audit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import config_from_dict, simulate
from biped_sim.errors import ConfigError
from biped_sim.multibody import euler_parameters
from biped_sim.multibody.dispatch import formulation_of, measures
from biped_sim.multibody.minimal import tree_system
from biped_sim.multibody.tree import tree_state
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.simulate import prepare_model
from biped_sim.testing import default_walker

from .conftest import DEFAULT_CONFIG, invoke, one_line_error, plain_engine

IMPULSE = np.array([0.3, -0.2])  # [N s]: forward and down, about 0.1 m/s on the 4 kg walker
PUSH = "simulation.pushes=[{time: 0.3, impulse: [0.4, 0.1]}]"


def planar_momenta(y: np.ndarray, system: tuple, point: np.ndarray) -> tuple[np.ndarray, float]:
    """Total linear momentum and angular momentum about ``point`` of a planar state."""
    nb = system.body_mass.shape[0]
    linear, angular = np.zeros(2), 0.0
    for b in range(nb):
        m, r, v = system.body_mass[b], y[3 * b : 3 * b + 2], y[3 * nb + 3 * b : 3 * nb + 3 * b + 2]
        linear += m * v
        d = r - point
        angular += m * (d[0] * v[1] - d[1] * v[0]) + system.body_inertia[b] * y[3 * nb + 3 * b + 2]
    return linear, angular


def mid_stance_state(*overrides: str) -> tuple[tuple, np.ndarray]:
    """(system, state at 0.4 s) of the default walker: the legs apart, both joints loaded."""
    result = simulate(default_walker(*overrides, t_end=0.4))
    return result.model.system, result.run.y[-1]


def test_a_planar_push_keeps_the_joints_and_gives_the_walker_exactly_the_impulse() -> None:
    system, y = mid_stance_state()
    with plain_engine():  # the push's equations (a compiled run's pushes: the tests below)
        after = formulation_of(system).hip_impulse(y, system, IMPULSE)
        violation = measures(system).violation
        violations = [violation(state, system) for state in (after, y)]
        hip = np.array(measures(system).hip(y, system))
    n = 3 * system.body_mass.shape[0]
    assert np.array_equal(after[:n], y[:n]) and np.array_equal(after[2 * n :], y[2 * n :])
    assert violations[0][0] == violations[1][0]
    assert abs(violations[0][1] - violations[1][1]) < 1e-14  # Phidot unchanged, to round-off
    linear_before, angular_before = planar_momenta(y, system, hip)
    linear_after, angular_after = planar_momenta(after, system, hip)
    # the joints are internal (the feet touch by penalty forces, finite): the walker is free-floating at the jump
    np.testing.assert_allclose(linear_after - linear_before, IMPULSE, rtol=0, atol=1e-14)
    assert abs(angular_after - angular_before) < 1e-14  # the impulse acts at the hip: no moment about it


def test_a_spatial_push_keeps_the_joints_and_the_normalisation_and_moves_the_hip_as_the_planar_one() -> None:
    planar, y_planar = mid_stance_state()
    spatial, y = mid_stance_state("formulation.kind=spatial")
    nb = spatial.body_mass.shape[0]
    s_a = tuple(spatial.con_vecs[0, :3])

    def hip_velocity(state: np.ndarray) -> np.ndarray:
        return np.array(euler_parameters.point_state(state, nb, spatial.con_bodies[0, 0], s_a)[1])

    with plain_engine():  # the push's equations (a compiled run's pushes: the tests below)
        after = formulation_of(spatial).hip_impulse(y, spatial, IMPULSE)
        violation = measures(spatial).violation
        np.testing.assert_allclose(violation(after, spatial), violation(y, spatial), rtol=0, atol=1e-14)
        spatial_jump = hip_velocity(after) - hip_velocity(y)
        planar_after = formulation_of(planar).hip_impulse(y_planar, planar, IMPULSE)
    rates = lambda state: state[7 * nb : 14 * nb].reshape(nb, 7)[:, :3]  # noqa: E731
    momentum_change = spatial.body_mass @ (rates(after) - rates(y))
    np.testing.assert_allclose(momentum_change, [*IMPULSE, 0.0], rtol=0, atol=1e-14)
    n = 3 * planar.body_mass.shape[0]
    a, (sx, sy) = planar.joint_bodies[0, 0], planar.joint_points[0, :2]

    def planar_hip_velocity(state: np.ndarray) -> np.ndarray:
        c, s = math.cos(state[3 * a + 2]), math.sin(state[3 * a + 2])
        omega = state[n + 3 * a + 2]
        return state[n + 3 * a : n + 3 * a + 2] + omega * np.array([-(s * sx + c * sy), c * sx - s * sy])

    planar_jump = planar_hip_velocity(planar_after) - planar_hip_velocity(y_planar)
    # the two formulations integrate the same walker to 0.4 s (to their tolerances): the jumps agree to that
    np.testing.assert_allclose(spatial_jump, [*planar_jump, 0.0], rtol=0, atol=1e-6)


def test_a_minimal_push_gives_the_walker_exactly_the_impulse_and_moves_the_hip_as_the_planar_one() -> None:
    planar, y_planar = mid_stance_state()
    system = tree_system(planar)
    y = tree_state(y_planar, planar)
    with plain_engine():  # the push's equations (a compiled run's pushes: the tests below)
        after = formulation_of(system).hip_impulse(y, system, IMPULSE)
        planar_after = formulation_of(planar).hip_impulse(y_planar, planar, IMPULSE)
    n = 2 + system.body_mass.shape[0]
    assert np.array_equal(after[:n], y[:n]) and np.array_equal(after[2 * n :], y[2 * n :])
    # the same state in both coordinates: the jumps agree to round-off (hip velocity, leg rates)
    np.testing.assert_allclose(after, tree_state(planar_after, planar), rtol=0, atol=1e-13)


def test_a_compliant_run_books_the_push_work_and_its_energy_balance_closes() -> None:
    pushed = simulate(default_walker(PUSH, t_end=0.6))
    run, energy = pushed.run, pushed.energy
    assert run.pushes.shape == (1, 3) and run.pushes[0, 0] == 0.3
    first = int(run.pushes[0, 1])
    assert run.t[first - 1] <= 0.3 + 1e-12 < run.t[first]
    system = pushed.model.system
    before = run.y[first - 1]  # the state at the push time, just before it
    kinetic = lambda state: measures(system).mechanical_energy(state, system, run.modes[first - 1])[0]  # noqa: E731
    with plain_engine():  # the push's work by the source's equations, against the compiled run's
        expected = kinetic(formulation_of(system).hip_impulse(before, system, np.array([0.4, 0.1]))) - kinetic(before)
    assert run.pushes[0, 2] == pytest.approx(expected, rel=1e-9)
    assert energy.push_work[first - 1] == 0.0 and energy.push_work[first] == run.pushes[0, 2]
    scale = pushed.model.total_mass * pushed.config.gravity * pushed.model.leg_length
    assert abs(run.pushes[0, 2]) / scale > 1e-3  # a push the audit would see ...
    assert pushed.summary["energy_residual_max_relative"] < 1e-6  # ... and the balance closes with it booked
    unbooked = energy.residual + energy.push_work
    assert abs(unbooked[first] - unbooked[first - 1]) == pytest.approx(abs(run.pushes[0, 2]), rel=1e-3)
    assert pushed.summary["pushes"] == [{"time": 0.3, "impulse": [0.4, 0.1], "work": run.pushes[0, 2]}]
    assert pushed.summary["constraint_violation_max"]["velocity"] < 1e-6
    assert "energy/push_work" in {channel.path for channel in pushed.trajectory().channels}


def test_pushes_are_applied_in_time_order_with_every_integrator() -> None:
    for method in ("rk4", "radau"):
        out_of_order = "simulation.pushes=[{time: 0.2, impulse: [0.1, 0.0]}, {time: 0.1, impulse: [-0.1, 0.0]}]"
        result = simulate(default_walker(out_of_order, f"integrator.method={method}", "integrator.dt=1e-4", t_end=0.3))
        assert result.run.pushes[:, 0].tolist() == [0.1, 0.2]
        assert [push["impulse"] for push in result.summary["pushes"]] == [[-0.1, 0.0], [0.1, 0.0]]
        assert result.summary["energy_residual_max_relative"] < 1e-4, method


def test_a_run_without_pushes_has_no_push_records_and_no_push_work() -> None:
    plain = simulate(default_walker(t_end=0.5))
    assert plain.run.pushes.shape == (0, 3) and "pushes" not in plain.summary
    assert not plain.energy.push_work.any()


def test_a_big_push_makes_the_compliant_walker_fall_as_a_result() -> None:
    result = simulate(default_walker("simulation.pushes=[{time: 0.3, impulse: [-6.0, 0.0]}]", t_end=3.0))
    assert result.status == "fell" and result.stop_time is not None and result.stop_time > 0.3
    assert result.summary["energy_residual_max_relative"] < 1e-4


RIGID = ["dynamics=rigid", "simulation.t_end=4"]


def test_a_rigid_push_stops_the_step_and_jumps_the_state_as_computed() -> None:
    walker = rigid_walker(config_from_dict({}, RIGID))
    x0 = np.array([0.25, -0.25, -1.6, -0.5])
    free = rigid_step(walker, x0, sample_rate=100.0)
    pushed = rigid_step(walker, x0, sample_rate=100.0, pushes=[(0.2, IMPULSE)])
    k = int(np.flatnonzero(np.isclose(free.samples_t, 0.2))[0])
    assert pushed.samples_t[k] == free.samples_t[k] and len(pushed.pushes) == 1
    expected, _ = walker.hip_push(free.samples_x[k], IMPULSE)
    np.testing.assert_allclose(pushed.samples_x[k], expected, rtol=0, atol=1e-9)  # the flow to 0.2, then the jump
    np.testing.assert_allclose(pushed.samples_x[k - 1], free.samples_x[k - 1], rtol=0, atol=1e-9)


def test_a_rigid_compass_push_keeps_the_momenta_the_impulse_cannot_change() -> None:
    walker = rigid_walker(config_from_dict({}, RIGID))
    x = np.array([0.1, -0.2, -1.4, 0.3])
    after, ground_normal = walker.hip_push(x, IMPULSE)
    assert np.array_equal(after[:2], x[:2])
    contact = walker.contact_point(x[:2])
    hip = walker.hip(x[:2])
    # about the contact point the ground impulse has no moment: the whole walker gains r_hip x p
    moment = (hip - contact)[0] * IMPULSE[1] - (hip - contact)[1] * IMPULSE[0]
    jump = walker.angular_momentum(after, contact) - walker.angular_momentum(x, contact)
    assert jump == pytest.approx(moment, abs=1e-13)
    # the swing leg (body 1) is pushed only through the hip pin: its momentum about the hip is kept
    swing = {1}
    assert walker.angular_momentum(after, hip, swing) == pytest.approx(
        walker.angular_momentum(x, hip, swing), abs=1e-13
    )
    linear = walker.linear_momentum(after) - walker.linear_momentum(x)
    assert ground_normal == pytest.approx(linear[1] - IMPULSE[1], abs=1e-14)


def test_a_simplest_walker_push_moves_its_hip_across_the_stance_leg_and_keeps_the_swing_foot() -> None:
    walker = rigid_walker(config_from_dict({}, [*RIGID, "walker.kind=simplest", "ground.slope=0.004"]))
    theta, theta_sw = 0.15, -0.1
    x = np.array([theta, theta_sw, -0.2, -0.1])
    after, ground_normal = walker.hip_push(x, IMPULSE)
    across = np.array([-math.cos(theta), -math.sin(theta)])  # d(hip)/dtheta, l = 1
    hip_jump = (after[2] - x[2]) * across
    np.testing.assert_allclose(hip_jump, (IMPULSE @ across) * across, rtol=0, atol=1e-15)  # hip mass 1
    swing_across = np.array([math.cos(theta_sw), math.sin(theta_sw)])
    swing_foot_jump = hip_jump + (after[3] - x[3]) * swing_across
    assert swing_foot_jump @ swing_across == pytest.approx(0.0, abs=1e-15)  # the massless leg pushes it only along
    assert ground_normal == pytest.approx(hip_jump[1] - IMPULSE[1], abs=1e-15)


@pytest.mark.parametrize("kind", ["compass", "simplest", "rimless_wheel"])
def test_a_rigid_run_books_the_push_and_a_big_one_makes_it_fall(kind: str) -> None:
    extra = {
        "simplest": ["ground.slope=0.004", "simulation.initial=rigid_limit_cycle"],
        "rimless_wheel": ["ground.slope=0.1", "walker.leg_length=1.0"],
    }
    base = [*RIGID, f"walker.kind={kind}", *extra.get(kind, [])]
    small = simulate(config_from_dict({}, [*base, "simulation.pushes=[{time: 1.3, impulse: [0.01, 0.0]}]"]))
    assert len(small.summary["pushes"]) == 1 and small.summary["pushes"][0]["work"] != 0.0
    assert small.summary["energy_residual_max"] < 1e-9
    assert "energy/push_work" in {channel.path for channel in small.trajectory().channels}
    big = simulate(config_from_dict({}, [*base, "simulation.pushes=[{time: 1.3, impulse: [-5.0, 0.0]}]"]))
    assert big.status == "fell" and big.stop_time is not None and big.stop_time > 1.3


@pytest.mark.parametrize(
    ("push", "field"),
    [
        ("[{time: 2.5, impulse: [1.0, 0.0]}]", "simulation.pushes"),
        ("[{time: .nan, impulse: [1.0, 0.0]}]", "simulation.pushes.0.time"),
        ("[{time: -1.0, impulse: [1.0, 0.0]}]", "simulation.pushes.0.time"),
        ("[{time: 0.5, impulse: [.inf, 0.0]}]", "simulation.pushes.0.impulse.0"),
        ("[{time: 0.5, impulse: [true, 0.0]}]", "simulation.pushes.0.impulse"),
        ("[{time: 0.5, impulse: [1.0]}]", "simulation.pushes.0.impulse.1"),
        ("[{time: 0.5}]", "simulation.pushes.0.impulse"),
        ("[{time: 0.5, impulse: [1.0, 0.0], where: hip}]", "simulation.pushes.0.where"),
    ],
)
def test_a_bad_push_is_a_one_line_error_naming_the_field(push: str, field: str) -> None:
    with pytest.raises(ConfigError) as info:
        prepare_model(config_from_dict({}, ["simulation.t_end=2.0", f"simulation.pushes={push}"]))
    assert info.value.field == field


def test_a_bad_push_on_the_command_line_is_exit_2_and_writes_nothing(tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "run"
    for push in ("[{time: 99.0, impulse: [1.0, 0.0]}]", "[{time: 0.5, impulse: [.nan, 0.0]}]"):
        result = invoke("run", str(DEFAULT_CONFIG), "--set", f"simulation.pushes={push}", "--out", str(out))
        assert result.exit_code == 2 and "simulation.pushes" in one_line_error(result.stderr)
    assert not out.exists()
