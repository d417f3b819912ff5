"""Walkers built from their description (walkers.described), joint stops as compliant contacts (contact.stop),
and the minimal formulation over a tree of bodies (multibody.minimal's tree solve)."""

from __future__ import annotations

import itertools
import math

import numba
import numpy as np
import pytest

from biped_sim.config import Config, IntegratorConfig, config_from_dict, derive, load_config
from biped_sim.contact.normal import NORMAL_LAWS, normal_parameters
from biped_sim.contact.stop import (
    FREE,
    HELD,
    LATCHED,
    RELEASING,
    NoStops,
    Stops,
    make_stops,
    stop_torques,
    stops_energy,
)
from biped_sim.errors import ConfigError
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.dispatch import formulation_of, make_workspace, measures, system_rhs
from biped_sim.multibody.minimal import HIP, tree_system
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.tree import STAR, TREE, tree_state
from biped_sim.simulate import CompliantRunResult, simulate
from biped_sim.simulate.warmup import _with_joints
from biped_sim.studies.convergence import converge
from biped_sim.testing import default_walker, pendulum
from biped_sim.walkers import build_model

from .conftest import ROOT, plain_engine

KNEED = ROOT / "configs" / "kneed_walker_compliant.yaml"


def _kneed(*overrides: str, foot_centre: tuple[float, float] | None = None, latch: bool = True) -> Config:
    """The bundled compliant kneed walker, with ``--set`` overrides and, if given, both feet's arc centre and
    whether its knee stops latch."""
    config = load_config(KNEED, list(overrides))
    data = config.model_dump(mode="json")
    for foot in data["walker"]["description"]["feet"]:
        foot["centre"] = list(foot_centre) if foot_centre is not None else foot["centre"]
    for joint in data["walker"]["description"]["joints"]:
        for stop in joint["stops"]:
            stop["latch"] = latch
    return config_from_dict(data)


# ---------------------------------------------------------------- a joint stop: the drop test


def test_a_walker_without_joint_stops_has_a_stops_record_of_its_own_type() -> None:
    """No stops is a type (NoStops), on which numba specialises: such a walker compiles none of the stops' code and
    its stop kernels are no-ops; a walker with stops has a Stops record, in both formulations."""
    plain, kneed = build_model(default_walker()).system, build_model(_kneed()).system
    assert type(plain.stops) is NoStops and plain.stops.law.shape == (0,)
    assert type(kneed.stops) is Stops and numba.typeof(kneed.stops) != numba.typeof(plain.stops)
    assert type(tree_system(plain).stops) is NoStops and type(tree_system(kneed).stops) is Stops
    y, modes, force = np.ones(12), np.ones((2, 4)), np.ones(6)
    assert stop_torques(y, plain.stops, modes, 2, force) == 0.0 and stops_energy(y, plain.stops, modes, 2) == 0.0
    assert force.tolist() == [1.0] * 6


def stop_pendulum(law: str, restitution: float, stiffness: float = 1.0e3) -> PlanarSystem:
    """The uniform 1 m rod (1 kg) hinged to the ground at its top end of :func:`biped_sim.testing.pendulum`,
    with a lower stop at 0 rad against the ground (it may not swing past the slope normal): no feet."""
    params = normal_parameters(law, stiffness, 1.5, restitution, None, 1.0 / 3.0)
    stops = make_stops(
        np.array([[2, -1, 5, -1]]), np.array([[-1.0, 0.0, 1e-3]]), np.array([NORMAL_LAWS[law].index]), params
    )
    return pendulum()[0]._replace(stops=stops)


def _drop(law: str, restitution: float) -> tuple[float, float, float]:
    """(effective restitution, largest |E + W_stop - E(0)| over the run, W_stop) of the rod released at 0.4 rad."""
    system = stop_pendulum(law, restitution)
    phi0 = 0.4
    y0 = np.array([0.5 * math.sin(phi0), -0.5 * math.cos(phi0), phi0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert formulation_of(system).layout_of(system).size == y0.size
    integrator = IntegratorConfig(method="dopri5", rtol=1e-11, atol=1e-13, max_step=1e-3)
    run = integrate_model(system, y0, np.zeros((1, 4)), integrator, t_end=0.6, sample_rate=2000.0)
    log = run.contact_log
    onsets, releases = log[log[:, 2] > 0], log[log[:, 2] < 0]
    assert len(onsets) >= 1 and len(releases) >= 1 and np.all(log[:, 1] == 0)  # contact 0: the stop (no feet)
    energy = measures(system).mechanical_energy
    total = np.array([sum(energy(run.y[k], system, run.modes[k])) + run.y[k, -1] for k in range(len(run.t))])
    return -releases[0, 3] / onsets[0, 3], float(np.max(np.abs(total - total[0]))), float(run.y[-1, -1])


@pytest.mark.parametrize(("law", "restitution", "tolerance"), [("flores", 0.5, 0.05), ("hunt_crossley", 0.9, 0.02)])
def test_a_pendulum_falling_onto_a_stop_rebounds_with_its_restitution_and_closes_its_energy(
    law: str, restitution: float, tolerance: float
) -> None:
    effective, residual, dissipated = _drop(law, restitution)
    assert effective == pytest.approx(restitution, abs=tolerance)
    # the rod falls from 0.4 rad: m g (l/2)(1 - cos 0.4) = 0.388 J; the impact loses (1 - e^2) of it
    drop_energy = 9.81 * 0.5 * (1.0 - math.cos(0.4))
    assert dissipated == pytest.approx((1.0 - effective**2) * drop_energy, rel=0.02)
    assert residual < 1e-8 * drop_energy


# ---------------------------------------------------------------- the tree formulation


def _random_tree_states(planar: PlanarSystem, count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Planar states that satisfy the joints (angles, rates and the root's motion drawn at random) with a
    random contact mode table; built through the minimal coordinates, so both describe one state."""
    rng = np.random.default_rng(seed)
    minimal = tree_system(planar)
    layout = formulation_of(planar).layout_of(planar)
    nb, nf, ns = planar.body_mass.shape[0], planar.foot_body.shape[0], planar.stops.law.shape[0]
    states = []
    for _ in range(count):
        phi, omega = rng.uniform(-0.3, 0.3, nb), rng.normal(0.0, 2.0, nb)
        hip, hip_velocity = np.array([0.0, rng.uniform(0.95, 1.01)]), rng.normal(0.0, 1.0, 2)
        y = np.zeros(layout.size)
        for b in range(nb):  # the centre of mass of b from the root's origin down the tree (tree_system's origins)
            origin, velocity, j = hip.copy(), hip_velocity.copy(), b
            chain = []
            while minimal.body_parent[j] >= 0:
                chain.append(j)
                j = minimal.body_parent[j]
            for k in reversed(chain):
                p = minimal.body_parent[k]
                arm = _rotate(phi[p], minimal.body_joint[k])
                origin, velocity = origin + arm, velocity + omega[p] * np.array([-arm[1], arm[0]])
            arm = _rotate(phi[b], minimal.body_com[b])
            y[layout.position(b)] = [*(origin + arm), phi[b]]
            y[layout.velocity(b)] = [*(velocity + omega[b] * np.array([-arm[1], arm[0]])), omega[b]]
        y[layout.first_bristle : layout.first_bristle + nf] = rng.normal(0.0, 1e-6, nf)
        modes = np.column_stack([np.ones(nf + ns), rng.integers(0, 2, nf + ns), rng.uniform(0.01, 1.0, nf + ns)])
        states.append((y, np.column_stack([modes, np.zeros(nf + ns)])))
    return states


def _rotate(phi: float, v: np.ndarray) -> np.ndarray:
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def formulations_agree(planar: PlanarSystem, count: int, seed: int) -> list[np.ndarray]:
    """On ``count`` random states, the tree formulation's angular accelerations, work rates, feet and energies agree
    with the absolute coordinates'; returns the absolute coordinates' right-hand sides. The equations as plain
    Python (conftest.plain_engine): the compiled runs of both formulations agree in the walks' tests."""
    minimal = tree_system(planar)
    nb = planar.body_mass.shape[0]
    n = HIP + nb
    rates = []
    with plain_engine():
        for y_planar, modes in _random_tree_states(planar, count=count, seed=seed):
            y = tree_state(y_planar, planar)
            fast, full = np.zeros_like(y), np.zeros_like(y_planar)
            system_rhs(0.0, y, minimal, modes, make_workspace(minimal), fast)
            system_rhs(0.0, y_planar, planar, modes, make_workspace(planar), full)
            alpha = full[3 * nb + 2 : 6 * nb : 3]
            scale = np.max(np.abs(alpha))
            np.testing.assert_allclose(fast[n + HIP : 2 * n], alpha, rtol=1e-9, atol=1e-9 * scale)
            np.testing.assert_allclose(fast[2 * n :], full[6 * nb :], rtol=1e-9, atol=1e-12)
            e_planar, e_minimal = (
                sum(measures(s).mechanical_energy(v, s, modes)) for s, v in ((planar, y_planar), (minimal, y))
            )
            assert e_minimal == pytest.approx(e_planar, rel=1e-12, abs=1e-12)
            rates.append(full)
    return rates


def test_the_tree_formulation_agrees_with_absolute_coordinates_on_the_kneed_walker() -> None:
    """On random states, the kneed walker's angular accelerations, stop work rates and feet agree in both."""
    planar = build_model(_kneed()).system
    assert not tree_system(planar).star and planar.stops.law.shape[0] == 2
    pressed = sum(int(full[-1] != 0.0) for full in formulations_agree(planar, count=30, seed=3))
    assert pressed > 3  # the stops took part


def test_the_tree_solve_equals_the_star_solve_on_the_compass_to_rounding() -> None:
    """The compass, a star, run by the arrow solve and, with a hip stop it never reaches (the warm-up's: a tree in a
    group the warm-up compiles), by the tree's mass matrix and Cholesky: the same gait to rounding (not bit for bit:
    the two solves order their arithmetic differently), the stop's dissipated work zero throughout."""
    star = default_walker("formulation.kind=minimal", t_end=1.0)
    models = [build_model(config) for config in (star, _with_joints(star, stop=True, element=False))]
    assert [model.system.topology for model in models] == [STAR, TREE]
    integrator = IntegratorConfig(method="dopri5", rtol=1e-10, atol=1e-12)
    runs = [integrate_model(model.system, model.y0, model.modes0, integrator, 1.0, 200.0) for model in models]
    assert len(runs[0].strike_t) >= 2 and np.array_equal(runs[0].strike_foot, runs[1].strike_foot)
    np.testing.assert_allclose(runs[1].strike_t, runs[0].strike_t, rtol=0, atol=1e-9)
    ny = runs[0].y.shape[1]
    np.testing.assert_allclose(runs[1].y[:, :ny], runs[0].y, rtol=0, atol=1e-7)
    assert not np.array_equal(runs[1].y[:, :ny], runs[0].y)  # the tree's solve did run
    assert runs[1].y.shape[1] == ny + 1 and not np.any(runs[1].y[:, ny:])  # the stop's work: never struck


# ---------------------------------------------------------------- the builder


@pytest.mark.parametrize("offsets", [(), ("walker.foot_offset=0.01", "walker.leg_com_offset=0.004")])
def test_the_compass_preset_builds_the_compass_of_model_md(offsets: tuple[str, ...]) -> None:
    """The compass preset, built from its description, is MODEL.md's compass: each leg with half the hip mass at
    the hip, its centre of mass d = m c / (m + M_H/2) along and d_w = m w / (m + M_H/2) across the leg, its inertia
    by parallel axes, the foot arc centre l - R along and d across the leg, rolling on its stance foot."""
    config = default_walker(*offsets)
    w = config.walker
    m, c, across, half_hip = w.leg_mass, w.leg_com_from_hip, w.leg_com_offset, 0.5 * w.hip_mass
    mass = m + half_hip
    d, d_w = m * c / mass, m * across / mass
    inertia = w.leg_inertia + m * ((c - d) ** 2 + (across - d_w) ** 2) + half_hip * (d**2 + d_w**2)
    system = build_model(config).system
    np.testing.assert_allclose(system.body_mass, [mass, mass], rtol=1e-15)
    np.testing.assert_allclose(system.body_inertia, [inertia, inertia], rtol=1e-15)
    np.testing.assert_allclose(system.joint_points, [[-d_w, d, -d_w, d]], rtol=1e-15, atol=1e-17)
    centre = [w.foot_offset - d_w, -(w.leg_length - w.foot_radius - d)]
    np.testing.assert_allclose(system.foot_center, [centre, centre], rtol=1e-15)
    assert np.array_equal(system.foot_partner, [1, 0]) and np.array_equal(system.foot_radius, [w.foot_radius] * 2)


def test_without_latches_the_stance_knee_of_chens_walker_flexes_and_it_falls() -> None:
    """Why the bundled config's knees latch: with plain one-sided stops (and its feet under the shanks' axes) the
    stance knee leaves its stop within milliseconds of the start (contact 2: knee_1's stop) and the walker falls."""
    result = simulate(_kneed("simulation.t_end=1", latch=False))
    assert result.status == "fell"
    log = result.run.contact_log
    stance_knee = log[log[:, 1] == 2]
    assert stance_knee[0, 2] == 1.0 and stance_knee[1, 2] == -1.0 and stance_knee[1, 0] < 0.01


def _latch_states(result: CompliantRunResult, stop: int) -> np.ndarray:
    """The latch state (FREE, HELD, RELEASING) of joint stop ``stop`` at each sample of a run."""
    return result.run.modes[:, result.model.system.foot_body.shape[0] + stop, LATCHED]


def test_a_knee_latch_engages_at_the_knee_strike_and_lets_go_after_the_toe_off_and_the_strike() -> None:
    """One step of the latching kneed walker: the stance knee starts latched, the swing knee free; the swing knee's
    strike (its stop's onset, fast) latches it; at the heel strike the trailing foot's toe-off begins the stance
    knee's release (RELEASING) and the end of the leading foot's compression completes it, both knees held
    through the strike; each knee's latch is in the contact log as its stop's onset and release."""
    result = simulate(_kneed("simulation.max_steps=2", "simulation.t_end=1.5", "output.sample_rate=20000"))
    run, nf = result.run, result.model.system.foot_body.shape[0]
    stance, swing = _latch_states(result, 0), _latch_states(result, 1)
    assert stance[0] == HELD and swing[0] == FREE
    log = run.contact_log
    knee_strike = log[(log[:, 1] == nf + 1) & (log[:, 2] > 0) & (log[:, 3] > 1.0)][0]  # not the start's graze
    assert 0.2 < knee_strike[0] < run.strike_t[0] and knee_strike[3] > 5.0  # rad/s
    assert np.all(swing[run.t < knee_strike[0]] == FREE)
    latched = run.t[np.argmax(swing == HELD)]
    assert latched == pytest.approx(knee_strike[0], abs=1e-4)  # the next sample
    toe_off = log[(log[:, 1] == 0) & (log[:, 2] < 0)][0, 0]
    release = log[(log[:, 1] == nf) & (log[:, 2] < 0)][0, 0]
    assert run.strike_t[0] < toe_off < release < run.strike_t[0] + 0.01  # the soft bundled contact: ~5 ms
    between = (run.t > toe_off) & (run.t < release)
    swinging = (run.t > release) & (run.t < release + 0.2)  # the released knee's next swing, before its strike
    assert np.all(stance[between] == RELEASING) and np.all(stance[swinging] == FREE)
    assert np.all(swing[(run.t > latched) & (run.t < run.strike_t[1])] == HELD)


def test_a_swing_foot_starting_below_the_ground_is_refused_without_the_scuffing_guard() -> None:
    """The stance leg leaning, the swing leg straight down: its foot starts under the ground, which the scuffing
    guard would ignore (mid-stance scuffing) and a run without it could not start from."""
    swing_down = ["simulation.initial.swing_thigh_angle=0", "simulation.initial.swing_shank_angle=0"]
    assert build_model(_kneed(*swing_down)).y0.size  # the guard ignores the scuffing swing foot
    with pytest.raises(ConfigError, match=r"^simulation\.initial: the swing foot starts below the ground"):
        build_model(_kneed(*swing_down, "contact.scuffing_guard=false"))


def test_a_latch_needs_a_joint_within_a_leg_one_line_naming_the_field() -> None:
    data = _kneed().model_dump(mode="json")
    data["walker"]["description"]["joints"][0]["stops"] = [{"side": "upper", "angle": 0.5, "latch": True}]
    with pytest.raises(ConfigError, match=r"^walker\.description\.joints\.hip\.stops\.0\.latch: a latch") as error:
        config_from_dict(data)
    assert "\n" not in str(error.value)


def test_a_latched_knee_is_held_from_both_sides_of_its_limit() -> None:
    """Chen's stance knee, which a one-sided stop lets flex (the walker falls: above), is held by its latch from
    both sides: while HELD its relative angle is found inside the limit (flexed, the latch pulling it back) and
    past it (pushed back), always within 0.02 rad, and the walker walks."""
    result = simulate(_kneed("simulation.max_steps=1", "simulation.t_end=1"))
    assert result.run.strike_t.shape[0] == 1
    pitch, system = measures(result.model.system).pitch, result.model.system
    held = _latch_states(result, 0) == HELD
    knee = np.array([pitch(y, system, 2)[0] - pitch(y, system, 0)[0] for y in result.run.y[held]])
    assert np.min(knee) < -1e-4 and np.max(knee) > 1e-6 and np.max(np.abs(knee)) < 0.02


@pytest.mark.parametrize("latch", [True, False])
def test_the_compliant_kneed_walker_closes_its_energy_balance_with_the_knee_stops(latch: bool) -> None:
    """With its knee stops latching (the bundled config) and with plain stops (and McGeer's 5 cm foot offset,
    which keeps that walker's stance knee on its stop): the stops' work W_stop closes the balance; the latches'
    releases lose the energy their springs hold then, also in W_stop."""
    result = simulate(_kneed("simulation.t_end=1.5", foot_centre=None if latch else (0.05, -0.48), latch=latch))
    assert result.status == "walking" and result.summary["n_steps"] >= 2
    audit = result.energy
    stops = audit.dissipated_stops - audit.dissipated_stops[0]
    scale = float(np.max(np.abs(audit.kinetic)))
    assert stops[-1] > 0.03 * scale  # the knee strikes and the stance knee's stop (or latch) lose energy
    assert np.max(np.abs(audit.residual)) < 1e-7 * scale
    assert np.max(np.abs(audit.residual - stops)) > 1e5 * np.max(np.abs(audit.residual))  # without W_stop: open
    assert result.summary["energy_dissipated"]["stops"] == pytest.approx(float(stops[-1]))
    channels = {channel.path: channel.data for channel in result.trajectory().channels}
    assert np.array_equal(channels["energy/dissipated_stops"], audit.dissipated_stops)  # W_stop in trajectory.h5


@pytest.mark.slow
def test_planar_and_minimal_coordinates_walk_the_same_kneed_gait() -> None:
    tight = ("integrator.rtol=1e-10", "integrator.atol=1e-12")
    planar, minimal = (simulate(_kneed(f"formulation.kind={kind}", *tight)) for kind in ("planar", "minimal"))
    assert planar.status == minimal.status == "walking" and planar.summary["n_steps"] >= 6
    assert planar.summary["step_feet"] == minimal.summary["step_feet"]
    np.testing.assert_allclose(minimal.summary["step_times"], planar.summary["step_times"], rtol=0, atol=1e-7)
    np.testing.assert_allclose(minimal.summary["step_lengths"], planar.summary["step_lengths"], rtol=0, atol=1e-7)


@pytest.mark.slow
def test_a_push_and_a_step_down_on_the_compliant_kneed_walker_in_both_formulations() -> None:
    works = []
    for kind in ("planar", "minimal"):
        config = _kneed(f"formulation.kind={kind}", "simulation.t_end=2.0")
        pushed = simulate(derive(config, {"simulation.pushes": [{"time": 1.0, "impulse": [0.05, 0.0]}]}))
        assert pushed.status == "walking"
        works.append(pushed.summary["pushes"][0]["work"])
        step_down = {"kind": "steps", "steps": [{"at": 0.3, "height": -0.005}]}
        stepped = simulate(derive(config, {"ground.profile": step_down}))
        assert stepped.status == "walking" and stepped.summary["n_steps"] >= 2
    assert works[0] > 0 and works[1] == pytest.approx(works[0], rel=1e-8)  # the same push, the same work


@pytest.mark.slow
def test_converge_the_latching_kneed_gait_approaches_the_rigid_limit_cycle() -> None:
    """``converge`` on the latching kneed walker (feet x10, knee stops x100 per level: stops_level): the compliant
    gait's period approaches the rigid walker's (the same round feet) level after level, within 1e-4 s at the
    fourth, and its touchdown state within 2e-3 rad, rad/s there (the fifth level, 1e10 N/m^1.5, costs a minute
    and its touchdown difference is ~1e-2 again: each strike leaves ~0.5 % of the trailing leg's rate jump off the
    rigid map, less with less friction, as the leading foot lands sliding: rigid/strike_check.py's mechanism)."""
    _, rows = converge(_kneed(), levels=4, steps=8)
    assert all(row.status == "walking" for row in rows)
    periods = [abs(row.period_difference) for row in rows]
    assert all(later < earlier for earlier, later in itertools.pairwise(periods))
    assert periods[0] > 1e-3 and periods[-1] < 1e-4
    assert rows[-1].touchdown_difference < 2e-3 < rows[0].touchdown_difference
