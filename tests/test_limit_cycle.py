"""Limit cycles: Garcia's fixed point, multipliers two ways, the compass gaits, the compliant start."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from biped_sim import load_config
from biped_sim.analysis.limit_cycle import rigid_limit_cycle, simplest_variational_jacobian
from biped_sim.cli import app
from biped_sim.rigid.models import SimplestWalker
from tests.conftest import CONFIGS

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
    variational = np.linalg.eigvals(simplest_variational_jacobian(SimplestWalker(config), cycle.section_point))
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
    assert abs(result.step_periods[-1] - rigid.step_period) < 0.01 * rigid.step_period


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
    bad = runner.invoke(app, ["limit-cycle", str(SIMPLEST), "--guess", "[1, 2]"])
    assert bad.exit_code == 2 and "--guess" in bad.output
