"""Limit cycles: Garcia's fixed point, multipliers two ways, the compass gaits, the compliant start and Newton."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from biped_sim import load_config
from biped_sim.cli import app
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.planar import constraint_violation, foot_kinematics
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.limit_cycle import LimitCycle, rigid_limit_cycle
from biped_sim.simulate import RunResult
from biped_sim.studies.garcia import simplest_variational_jacobian
from biped_sim.studies.limit_cycle import TouchdownSection, compliant_limit_cycle
from biped_sim.walkers import build_model

from .conftest import CONFIGS, DEFAULT_CONFIG

SIMPLEST = CONFIGS / "simplest_walker.yaml"


def test_garcia_fixed_point_to_1e_8_and_stable() -> None:
    cycle = rigid_limit_cycle(load_config(SIMPLEST))
    assert cycle.converged
    assert cycle.fixed_point["stance_angle"] == pytest.approx(0.20031090049483, abs=1e-8)
    assert cycle.fixed_point["stance_rate"] == pytest.approx(-0.19983247291764, abs=1e-8)
    assert cycle.fixed_point["swing_angle"] == -cycle.fixed_point["stance_angle"]
    assert cycle.stable


def test_finite_difference_multipliers_match_the_variational_equations() -> None:
    config = load_config(SIMPLEST)
    cycle = rigid_limit_cycle(config)
    variational = np.linalg.eigvals(simplest_variational_jacobian(rigid_walker(config), cycle.section_point))
    assert np.max(np.abs(np.sort_complex(variational) - np.sort_complex(cycle.multipliers))) < 1e-6
    assert abs(cycle.multipliers[0].imag) > 0.1  # a complex pair at 0.009: the comparison is not trivial


def test_goswami_rigid_gait_is_stable_and_the_default_walker_has_one() -> None:
    goswami = rigid_limit_cycle(load_config(CONFIGS / "compass_goswami.yaml", ["dynamics=rigid"]))
    assert goswami.stable and goswami.step_period == pytest.approx(0.7344, abs=1e-3)
    default = rigid_limit_cycle(load_config(CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid"]))
    assert default.stable and default.step_period == pytest.approx(0.4338, abs=1e-3)


def test_compliant_run_can_start_on_the_rigid_limit_cycle() -> None:
    from biped_sim import simulate

    config = load_config(
        CONFIGS / "round_foot_walker.yaml", ["simulation.initial=rigid_limit_cycle", "simulation.t_end=3"]
    )
    result = simulate(config)
    rigid = rigid_limit_cycle(load_config(CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid"]))
    assert result.status == "walking"
    # e = 0.3, not the plastic strike of the rigid model: the heel strike's rebounds (one impact, its impact
    # velocity remembered through them: contact.impact_memory) lengthen the compliant step by about 1.5 %
    assert abs(result.step_periods[-1] - rigid.step_period) < 0.02 * rigid.step_period


def test_limit_cycle_cli_json_and_bad_guess() -> None:
    runner = CliRunner()
    out = runner.invoke(app, ["limit-cycle", str(CONFIGS / "rimless_wheel.yaml"), "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.output)
    for key in (
        "converged",
        "fixed_point",
        "step_period",
        "step_length",
        "speed",
        "multipliers",
        "max_multiplier_modulus",
        "stable",
    ):
        assert key in doc
    assert doc["multipliers"][0][0] == pytest.approx(0.5, abs=1e-6)
    bad = runner.invoke(app, ["limit-cycle", str(SIMPLEST), "--guess", "[1, 2, 3]"])  # 4 keys or the section's 2
    assert bad.exit_code == 2 and "--guess" in bad.output


# --- compliant: Newton on the step map between heel strikes ------------------------------------------------------

GOSWAMI = CONFIGS / "compass_goswami.yaml"
GOSWAMI_SHORT_STEP = {  # the rigid Goswami compass's unstable short-step cycle (period 0.582 s, multiplier 4.29)
    "stance_angle": 0.2572735297920956,
    "swing_angle": -0.2572735297920956,
    "stance_rate": -1.2113187124166462,
    "swing_rate": -0.7127563008668898,
}


@pytest.fixture(scope="module")
def default_compliant() -> LimitCycle:
    return compliant_limit_cycle(load_config(DEFAULT_CONFIG))


def _section(overrides: list[str] | None = None) -> TouchdownSection:
    config = load_config(DEFAULT_CONFIG, overrides or [])
    return TouchdownSection(config, build_model(config))


@pytest.mark.parametrize("friction", ["ambrosio", "lugre"])
def test_lift_is_exact_on_the_constraints_and_the_section_and_project_inverts_it(friction: str) -> None:
    section = _section([f"friction.model={friction}"])
    z = np.array([0.27, -0.26, -1.58, -1.8, 0.87, -0.17, 0.04, 1e-4][: len(section.names)])
    y, modes = section.lift(z)
    assert np.max(np.abs(np.array(constraint_violation(y, section.system)))) < 1e-15
    delta, delta_dot = foot_kinematics(y, section.system, 0)[:2]
    assert abs(delta) < 1e-15
    assert modes[0, :3].tolist() == [1.0, 1.0, delta_dot]  # the striking foot as the touchdown event leaves it
    assert foot_kinematics(y, section.system, 1)[0] > 0 and modes[1, :3].tolist() == [1.0, 1.0, z[6]]
    assert np.max(np.abs(section.project(y, modes, 0) - z)) < 1e-15  # to round-off
    # the same state with the legs' bodies, feet, bristles and modes swapped, read with foot 1 striking
    swapped = np.concatenate([y[3:6], y[0:3], y[9:12], y[6:9], y[13:14], y[12:13], y[14:]])
    assert np.array_equal(section.project(swapped, modes[::-1], 1), section.project(y, modes, 0))


@pytest.mark.slow  # Newton on the compliant step map at rtol 1e-13 and a 15 s settling run: ~15 s
def test_compliant_newton_converges_on_the_default_walker_gait(
    default_compliant: LimitCycle, default_run: RunResult
) -> None:
    cycle = default_compliant
    assert cycle.converged and cycle.residual <= 1e-10 and cycle.stable
    # 0.43508 s before contact.impact_memory: impact (the heel strike's rebounds now keep its impact velocity)
    assert cycle.step_period == pytest.approx(0.43949, abs=1e-5)
    assert set(cycle.to_json()["fixed_point"]) == {"stance_angle", "swing_angle", "stance_rate", "swing_rate"}
    lines = cycle.lines["touchdown"]  # the arc centre on the leg's axis: the hip-to-foot line is the leg
    assert (lines["stance_line_angle"], lines["swing_line_angle"]) == pytest.approx(
        (cycle.touchdown["stance_angle"], cycle.touchdown["swing_angle"]), abs=1e-12
    )
    # the settling run of the default walker (34 steps at rtol 1e-8) ends on the same touchdown state
    settled = default_run.heel_strike_states[-1]
    # within 2e-5 (measured 7e-6): the largest multiplier is 0.65 (0.57 under impact_memory touchdown, whose
    # reset stance damping settled the gait faster: 1.3e-7 then), a complex pair, so the approach spirals
    assert max(abs(settled[k] - cycle.fixed_point[k]) for k in settled) < 2e-5
    # the fast contact directions are forgotten within a step: 3 zero multipliers of 7
    assert np.sum(np.abs(cycle.multipliers) < 1e-6) == 3


@pytest.mark.slow  # needs the default walker's compliant fixed point (~10 s of Newton)
def test_a_run_started_on_the_compliant_fixed_point_stays_there_and_settles_at_the_newton_rate(
    default_compliant: LimitCycle,
) -> None:
    """10 steps from the fixed point repeat it; a perturbed run's touchdowns give the multipliers by least squares."""
    section = _section()
    z_star = default_compliant.section_point

    def touchdowns(z: np.ndarray, steps: int) -> tuple[np.ndarray, np.ndarray]:
        y, modes = section.lift(z)
        run = integrate_model(section.system, y, modes, section.integrator, 10.0, 1.0, steps, initial_stance_foot=0)
        assert len(run.strike_t) == steps
        z_k = [section.project(run.strike_y[k], run.strike_modes[k], int(run.strike_foot[k])) for k in range(steps)]
        return np.array(z_k), np.diff(np.concatenate([[0.0], run.strike_t]))

    on_cycle, periods = touchdowns(z_star, 10)
    assert np.ptp(periods) < 1e-8  # measured 1.6e-12
    assert np.max(np.abs(on_cycle - z_star)) < 1e-9  # measured 8.6e-11
    perturbed, _ = touchdowns(z_star + 1e-4 * np.eye(len(z_star))[2], 14)
    deviations = perturbed[3:] - z_star  # from step 4 on, the contact modes and the 0.11 pair have died out
    # the deviations span the few slow directions still excited; what lies under 1e-6 of the largest is the
    # integration's rounding, whose least-squares fit gave spurious multipliers (-0.70 on numpy 2.4.6): left out
    identified = np.linalg.lstsq(deviations[:-1], deviations[1:], rcond=1e-6)[0].T
    dominant = max(np.linalg.eigvals(identified), key=lambda m: (abs(m), m.imag))
    newton = max(default_compliant.multipliers, key=lambda m: (abs(m), m.imag))
    assert abs(dominant - newton) < 1e-4  # measured 2e-5


def test_rigid_cli_finds_the_unstable_goswami_cycle_without_settling() -> None:
    guess = "[0.18, -0.9, -0.18, -0.45]"
    args = ["limit-cycle", str(GOSWAMI), "--set", "dynamics=rigid", "--guess", guess, "--settle-steps", "0", "--json"]
    out = CliRunner().invoke(app, args)
    assert out.exit_code == 0, out.output
    doc = json.loads(out.output)
    assert doc["converged"] and not doc["stable"]
    assert doc["step_period"] == pytest.approx(0.58203, abs=1e-5)
    assert doc["max_multiplier_modulus"] == pytest.approx(4.288, abs=1e-3)


@pytest.mark.slow  # Newton on the compliant step map at rtol 1e-13: ~10 s
def test_compliant_newton_finds_the_unstable_goswami_short_step_gait() -> None:
    cycle = compliant_limit_cycle(load_config(GOSWAMI), GOSWAMI_SHORT_STEP, settle_steps=0)
    assert cycle.converged and not cycle.stable
    assert cycle.step_period == pytest.approx(0.5819, abs=1e-3)  # rigid: 0.58203 s
    assert cycle.max_multiplier_modulus == pytest.approx(4.28, abs=0.05)  # rigid: 4.288


def test_bifurcation_detects_period_doubling_and_writes_csv_and_figures(tmp_path: Path) -> None:
    """Simplest walker across Garcia's flip (0.0151): period 1 below it, period 2 in the brute force above it."""
    out = tmp_path / "bif"
    args = ["bifurcation", str(CONFIGS / "simplest_walker.yaml"), "--from", "0.012", "--to", "0.016", "--n", "3"]
    result = CliRunner().invoke(app, [*args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    continuation = pd.read_csv(out / "bifurcation.csv")
    assert list(continuation["stable"]) == [True, True, False]  # the flip lies between 0.014 and 0.016
    brute = pd.read_csv(out / "brute_force.csv")
    distinct = brute.groupby("slope")["step_period"].apply(lambda p: len(np.unique(np.round(p, 6))))
    assert list(distinct) == [1, 1, 2]
    assert all((out / f"bifurcation.{ext}").stat().st_size > 0 for ext in ("png", "svg"))
