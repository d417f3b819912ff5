"""Walker offsets (McGeer's w and d) in every model, and the rigid gait search that needs no hand-tuned guess."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from biped_sim import config_from_dict, load_config, simulate
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle, rigid_limit_cycle_initial
from biped_sim.rigid.tree import RigidWalker

from .conftest import CONFIGS, DEFAULT_CONFIG, invoke, one_line_error

OFFSETS = ["walker.leg_com_offset=0.02", "walker.foot_offset=0.03"]
# the example: its config start falls, yet it has a stable gait
SEARCH_EXAMPLE = [
    "dynamics=rigid",
    "gravity=1",
    "walker.leg_length=1.2",
    "walker.foot_radius=0.2",
    "walker.leg_mass=0.5",
    "walker.leg_com_from_hip=0.5",
    "walker.leg_inertia=0.02",
    "walker.hip_mass=1",
    "ground.slope=0.01",
]


def _axis(theta: float) -> np.ndarray:
    return np.array([math.sin(theta), -math.cos(theta)])


def _across(theta: float) -> np.ndarray:
    return np.array([math.cos(theta), math.sin(theta)])


@pytest.fixture(scope="module")
def offset_walker() -> RigidWalker:
    walker = rigid_walker(load_config(DEFAULT_CONFIG, ["dynamics=rigid", *OFFSETS]))
    assert isinstance(walker, RigidWalker)
    return walker


def test_rigid_flow_conserves_energy_with_offsets(offset_walker: RigidWalker) -> None:
    step = rigid_step(offset_walker, offset_walker.from_section(np.array([0.25, -1.6, -0.5])), sample_rate=1000.0)
    assert step.status == "strike"
    energy = np.array([sum(offset_walker.energy(x)) for x in step.samples_x])
    kinetic = np.array([offset_walker.energy(x)[0] for x in step.samples_x])
    assert np.ptp(kinetic) > 0.1 * kinetic.max()
    assert np.ptp(energy) < 1e-10 * energy.max()


def test_offset_strike_impact_and_step_length(offset_walker: RigidWalker) -> None:
    """The strike is where the swing arc touches the ground; the impact conserves the walker's angular momentum
    about the new contact point and the trailing leg's about the hip; the step is the contact point's advance."""
    walker = offset_walker
    l, R, d = walker.leg_length, walker.foot_radius, walker.config.walker.foot_offset
    x_start = walker.from_section(np.array([0.25, -1.6, -0.5]))
    step = rigid_step(walker, x_start)
    x_minus, x_plus = step.x_minus, walker.impact(step.x_minus)
    hip = walker.hip(x_minus[:2])
    new_centre = hip + (l - R) * _axis(x_minus[1]) + d * _across(x_minus[1])
    assert abs(new_centre[1] - R) < 1e-12  # the swing arc touches the slope
    assert x_minus[1] > x_minus[0] + 0.3  # the real strike, swing foot ahead (not the mid-stance crossing)
    new_contact = new_centre - [0.0, R]
    shift = new_contact - walker.contact_point(x_plus[:2])
    after_hip = walker.hip(x_plus[:2])
    assert after_hip + shift == pytest.approx(hip, abs=1e-14)  # the new stance foot carries the same hip
    before = walker.angular_momentum(x_minus, new_contact)
    assert walker.angular_momentum(x_plus, new_contact - shift) == pytest.approx(before, rel=1e-12)
    trailing = walker.angular_momentum(x_minus, hip, coordinates={0})
    assert walker.angular_momentum(x_plus, hip - shift, coordinates={1}) == pytest.approx(trailing, rel=1e-12)
    old_contact = walker.contact_point(x_minus[:2])
    assert (
        abs(walker.angular_momentum(x_plus, old_contact - shift) - walker.angular_momentum(x_minus, old_contact)) > 1e-3
    )
    start_contact = walker.contact_point(x_start[:2])  # the step started in the same frame as x_minus
    assert step.length == pytest.approx(new_contact[0] - start_contact[0], rel=1e-12)
    # just after the strike the legs are symmetric about -phi: the section map's swing angle
    assert walker.from_section(walker.to_section(x_plus)) == pytest.approx(x_plus, abs=1e-12)


def test_compliant_planar_walker_balances_energy_with_offsets() -> None:
    config = config_from_dict(
        {}, ["walker.leg_com_offset=-0.02", "walker.foot_offset=-0.03", "simulation.t_end=1.5", "integrator.rtol=1e-9"]
    )
    result = simulate(config)
    assert result.status == "walking" and result.summary["n_steps"] >= 2
    m_g_l = result.model.total_mass * config.gravity * config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-6 * m_g_l
    assert result.summary["energy_dissipated"]["normal"] > 1e-3 * m_g_l


def test_compliant_start_rolls_on_the_offset_arc() -> None:
    """The stance foot's arc centre is R (less the static sinkage) above its contact point at x = 0."""
    result = simulate(config_from_dict({}, [*OFFSETS, "simulation.t_end=0.01"]))
    from biped_sim.multibody.planar import foot_kinematics

    delta, delta_dot, slip, x_contact, _, _ = foot_kinematics(result.run.y[0], result.model.system, 0)
    assert delta == pytest.approx(result.model.meta["static_penetration"], rel=1e-9)
    assert abs(x_contact) < 1e-12 and abs(delta_dot) < 1e-12 and abs(slip) < 1e-12


@pytest.mark.slow  # ~10 s: the spatial compass and the four-legged walker with offsets
def test_spatial_walkers_with_offsets_agree_with_planar_and_balance_energy() -> None:
    walking = ["walker.leg_com_offset=-0.02", "walker.foot_offset=-0.03", "simulation.t_end=2", "integrator.rtol=1e-9"]
    planar = simulate(config_from_dict({}, walking))
    spatial = simulate(config_from_dict({}, [*walking, "formulation.kind=spatial"]))
    assert spatial.status == planar.status == "walking"
    assert spatial.step_periods == pytest.approx(planar.step_periods, rel=1e-6)
    four = simulate(load_config(CONFIGS / "four_legged_walker.yaml", [*OFFSETS[:1], "simulation.t_end=1"]))
    for run in (spatial, four):
        m_g_l = run.model.total_mass * 9.81 * run.model.leg_length
        assert np.max(np.abs(run.energy.residual)) < 1e-5 * m_g_l


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ("walker.leg_com_offset=0.49", "walker.leg_com_offset"),  # hypot(c, w) > l: the mass beyond the leg
        ("walker.foot_offset=0.35", "walker.foot_offset"),  # |d| >= l - R
        ("walker.foot_offset=-0.4", "walker.foot_offset"),
    ],
)
@pytest.mark.parametrize("command", ["run", "limit-cycle"])
def test_bad_offsets_are_one_line_exit_2(override: str, field: str, command: str, tmp_path) -> None:  # type: ignore[no-untyped-def]
    out = ["--out", str(tmp_path / "run")] if command == "run" else []
    result = invoke(command, str(DEFAULT_CONFIG), "--set", override, *out)
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith(f"error: {field}:")
    assert not (tmp_path / "run").exists()


def test_gait_search_finds_the_stable_gait_when_the_config_start_falls() -> None:
    result = invoke("limit-cycle", str(DEFAULT_CONFIG), *[a for s in SEARCH_EXAMPLE for a in ("--set", s)], "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["converged"] and doc["stable"]
    assert doc["start"].startswith("scan ") and "settling steps" in doc["start"]
    assert any(note.startswith("found by Newton from scan") for note in doc["notes"])
    # without the scan (settle-steps 0: the cycle nearest the guess) the config start has no gait
    nearest = invoke(
        "limit-cycle", str(DEFAULT_CONFIG), *[a for s in SEARCH_EXAMPLE for a in ("--set", s)], "--settle-steps", "0"
    )
    assert nearest.exit_code == 1 and one_line_error(nearest.stderr) == (
        "error: no rigid limit cycle: the walker falls from the config's initial state"
    )


@pytest.mark.slow  # ~4 s: the generic starts fall too, then the scan runs
def test_rigid_limit_cycle_start_uses_the_same_search() -> None:
    config = load_config(DEFAULT_CONFIG, [*SEARCH_EXAMPLE, "simulation.initial=rigid_limit_cycle"])
    cycle = rigid_limit_cycle(config)
    from_guess = rigid_limit_cycle(load_config(DEFAULT_CONFIG, SEARCH_EXAMPLE))
    assert cycle.stable and from_guess.stable and cycle.start
    assert cycle.section_point == pytest.approx(from_guess.section_point, abs=1e-9)  # the one stable gait
    # a run's start solves on scipy's step (runs keep their bits), the cycle above on the compiled one
    assert rigid_limit_cycle_initial(config) == pytest.approx(cycle.fixed_point, abs=1e-10)
    known = rigid_limit_cycle(load_config(DEFAULT_CONFIG, ["dynamics=rigid"]))  # a gait found from its guess
    assert known.converged and known.start == "the config's initial state, after 30 settling steps"


# lands slipping backwards (about -0.25 m/s) vs forwards; both are stable rigid gaits with an asymmetric strike
SLIPPING_STRIKE = ["walker.foot_offset=0.005"]
RELEASING_STRIKE = ["walker.foot_offset=0.005", "walker.leg_com_offset=0.002"]


@pytest.mark.parametrize(
    ("overrides", "mu_kinetic", "pushed"),
    [
        ([], 1.0, False),
        (RELEASING_STRIKE, 1.0, False),
        (SLIPPING_STRIKE, 1.0, True),
        (["walker.leg_com_offset=-0.002"], 1.0, True),
        (SLIPPING_STRIKE, 0.19, False),  # below W_nn / |W_nt| = 0.0945 / 0.455
    ],
)
def test_rigid_strike_check_flags_the_trailing_foot_pushed_into_the_ground(
    overrides: list[str], mu_kinetic: float, pushed: bool
) -> None:
    """The free walker's plastic impulse reproduces the impact map (the trailing foot's normal velocity after it);
    the trailing foot is pushed in exactly when the leading foot lands slipping backwards and mu_k is large."""
    from biped_sim.studies.convergence import rigid_strike_check

    config = load_config(DEFAULT_CONFIG, overrides)
    cycle = rigid_limit_cycle(config)
    check = rigid_strike_check(config, cycle, mu_kinetic)
    x = cycle.fixed_point  # the impact map's post-impact state: the trailing foot is the swing leg's
    arm, d = config.walker.leg_length - config.walker.foot_radius, config.walker.foot_offset
    swing = (arm * math.sin(x["swing_angle"]) + d * math.cos(x["swing_angle"])) * x["swing_rate"]
    stance = (arm * math.sin(x["stance_angle"]) + d * math.cos(x["stance_angle"])) * x["stance_rate"]
    assert check.trailing_release_speed == pytest.approx(swing - stance, rel=1e-9)
    assert check.trailing_release_speed > 0.2 and check.friction_ratio < 0.2  # released, and the lead can stick
    assert (check.trailing_push_rate < 0.0) == pushed == (check.violations(mu_kinetic + 0.01) != [])
    assert (check.leading_slip_speed < -0.2) == (overrides not in ([], RELEASING_STRIKE))


def test_converge_warns_when_the_rigid_strike_is_not_the_limit() -> None:
    args = ["converge", str(DEFAULT_CONFIG), "--levels", "2", "--set", SLIPPING_STRIKE[0]]
    table = invoke(*args)
    assert table.exit_code == 0, table.output
    assert "warning: the rigid strike is not the stiff-contact limit: the leading foot lands slipping" in table.stdout
    low_friction = invoke(*args, "--mu-kinetic", "0.19", "--mu-static", "0.2", "--json")
    strike = json.loads(low_friction.stdout)["rigid_strike"]
    assert strike["violations"] == [] and strike["trailing_push_rate"] > 0.0


def _assert_converges(rows: list, touchdown_factor: float, period_factor: float) -> None:  # type: ignore[type-arg]
    diffs = [row.touchdown_difference for row in rows]
    periods = [abs(row.period_difference) for row in rows]
    assert all(math.isfinite(d) for d in diffs)
    assert diffs[-1] < diffs[0] / touchdown_factor and periods[-1] < periods[0] / period_factor


@pytest.mark.slow  # ~25-40 s: five compliant runs of 20 steps
def test_compliant_gait_converges_to_the_rigid_one_with_offsets() -> None:
    """As in the validation's convergence check: stiffer, less restitutive, stickier contact -> the rigid gait, here
    with d = 5 mm and w = 2 mm, whose strike is asymmetric (swing angle != -stance angle) and releases the
    trailing foot: 7.7e-3 -> 2.2e-5 rad (sigma1 stiffened with sqrt(sigma0) as before: 2.7e-5 too)."""
    from biped_sim.studies.convergence import converge

    rigid, rows = converge(load_config(DEFAULT_CONFIG, RELEASING_STRIKE))
    assert rigid.stable and abs(rigid.fixed_point["swing_angle"] + rigid.fixed_point["stance_angle"]) > 1e-2
    _assert_converges(rows, 100, 20)


@pytest.mark.slow  # ~25-45 s: five compliant runs of 20 steps
def test_a_slipping_strike_converges_once_friction_cannot_push_the_trailing_foot_in() -> None:
    """d = 5 mm lands slipping backwards; with mu_k = 1 the leading foot's friction pushes the trailing foot into
    the ground and the difference stops near 6e-4 rad (it stayed near 6e-3 with sigma1 ~ sqrt(sigma0)). Below
    the check's bound the same gait converges: 8.5e-3 -> 2.5e-5 rad."""
    from biped_sim.studies.convergence import converge

    _, rows = converge(load_config(DEFAULT_CONFIG, SLIPPING_STRIKE), mu_kinetic=0.19, mu_static=0.2)
    _assert_converges(rows, 100, 100)
