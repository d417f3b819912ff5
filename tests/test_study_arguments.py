"""The logic the commands used to hold, as API: compare targets, the guess parser, converge's, bifurcation's and
robustness's argument checks; each names the argument (ArgumentError) or the config key, never an option."""

from __future__ import annotations

from pathlib import Path

import pytest

from biped_sim import config_from_dict, load_config
from biped_sim.config import LEG_KEYS
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.report.targets import compare_targets
from biped_sim.studies.bifurcation import check_bifurcation
from biped_sim.studies.convergence import check_converge
from biped_sim.studies.limit_cycle import parse_guess
from biped_sim.studies.robustness import robustness_configs
from biped_sim.testing import TINY_SWEEP_RUNS

from .conftest import CONFIGS, DEFAULT_CONFIG

SIMPLEST = load_config(CONFIGS / "simplest_walker.yaml")


def test_a_compare_target_is_a_config_a_run_or_a_sweep(short_run_dir: Path, tiny_sweep_dir: Path) -> None:
    [(label, periods)], missing = compare_targets(DEFAULT_CONFIG, ["simulation.t_end=1"], skip=1)
    assert label == "round_foot_walker (simulation.t_end=1)" and len(periods) >= 1 and missing is None
    [(label, periods)], _ = compare_targets(short_run_dir)
    assert label == short_run_dir.name and len(periods) == 4
    series, _ = compare_targets(tiny_sweep_dir)
    assert len(series) == TINY_SWEEP_RUNS


@pytest.mark.parametrize(
    ("target", "overrides", "skip", "error", "match"),
    [
        ("missing.yaml", [], 0, ConfigError, r"missing\.yaml: no such config file, run directory or sweep"),
        ("run", ["ground.slope=0.01"], 0, ArgumentError, r"^overrides: only applies when comparing a config file"),
        ("config", [], -1, ArgumentError, r"^skip: must be >= 0"),
    ],
)
def test_a_bad_compare_target_names_what_is_wrong(  # type: ignore[no-untyped-def]
    short_run_dir: Path, target: str, overrides: list[str], skip: int, error, match: str
) -> None:
    path = {"run": short_run_dir, "config": DEFAULT_CONFIG}.get(target, Path(target))
    with pytest.raises(error, match=match):
        compare_targets(path, overrides, skip)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("[0.2, -0.2, -0.2, -0.04]", dict(stance_angle=0.2, stance_rate=-0.2, swing_angle=-0.2, swing_rate=-0.04)),
        ("{stance_angle: 0.2, stance_rate: -0.2, swing_angle: -0.2, swing_rate: 0}", None),
    ],
)  # fmt: skip
def test_a_guess_is_four_numbers_or_the_four_keys(text: str, expected: dict[str, float] | None) -> None:
    guess = parse_guess(text, LEG_KEYS)
    assert guess is not None and set(guess) == {"stance_angle", "stance_rate", "swing_angle", "swing_rate"}
    assert expected is None or guess == expected
    assert parse_guess(None, LEG_KEYS) is None


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[0.2, -0.2]", "expected the 4 keys stance_angle, stance_rate, swing_angle, swing_rate"),
        ("[.nan, -0.2, -0.2, -0.04]", "stance_angle must be a finite number"),
        ("[true, -0.2, -0.2, -0.04]", "values must be numbers"),
        ("[0.2, -0.2, -0.2", "malformed YAML"),
    ],
)
def test_a_bad_guess_is_an_argument_error(text: str, match: str) -> None:
    with pytest.raises(ArgumentError, match=rf"^guess: .*{match}"):
        parse_guess(text, LEG_KEYS)


@pytest.mark.parametrize(
    ("levels", "mu_kinetic", "mu_static", "match"),
    [(1, 1.0, 1.2, "^levels: "), (5, 1.0, 0.5, "^mu_static: must be >= "), (5, -1.0, 1.2, "^mu_kinetic: ")],
)
def test_converge_refuses_bad_arguments(levels: int, mu_kinetic: float, mu_static: float, match: str) -> None:
    with pytest.raises(ArgumentError, match=match):
        check_converge(config_from_dict({}), levels, mu_kinetic, mu_static)
    with pytest.raises(ConfigError, match=r"^walker\.kind: "):
        check_converge(SIMPLEST, 5, 1.0, 1.2)


@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        ((0.005, 0.019, 57, "walker.leg_mass"), ArgumentError, "^param: only ground.slope"),
        ((float("nan"), 0.019, 57), ArgumentError, "^start: slope nan: "),
        ((0.005, 2.0, 57), ArgumentError, "^stop: slope 2.0: "),
        ((0.005, 0.019, 1), ArgumentError, "^n: at least 2"),
    ],
)
def test_bifurcation_refuses_bad_arguments(args: tuple, error: type, match: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(error, match=match):
        check_bifurcation(SIMPLEST, *args)
    with pytest.raises(ConfigError, match=r"^dynamics: "):
        check_bifurcation(config_from_dict({}), 0.005, 0.019, 57)


def test_robustness_runs_the_dynamics_a_walker_has() -> None:
    assert [c.dynamics for c in robustness_configs(config_from_dict({}))] == ["rigid", "compliant"]
    assert [c.dynamics for c in robustness_configs(SIMPLEST)] == ["rigid"]  # both: those it has
    with pytest.raises(ArgumentError, match=r"^dynamics: the simplest walker has no compliant model"):
        robustness_configs(SIMPLEST, "compliant")
    with pytest.raises(ArgumentError, match=r"^dynamics: unknown dynamics 'soft'"):
        robustness_configs(SIMPLEST, "soft")
