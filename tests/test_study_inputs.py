"""The studies' bad input (issue 32): walker descriptions, references, ``fit``, ``uncertainty`` and ``mfpt`` options
refused in one line naming the field or option, before any simulation and before anything is written."""

from __future__ import annotations

import copy
import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from biped_sim.config import config_from_dict
from biped_sim.config.loading import MAX_FILE_BYTES
from biped_sim.errors import ConfigError
from biped_sim.io.references import MAX_STEPS, load_reference
from biped_sim.studies.fit import fit_problems
from biped_sim.studies.fit.diagnose import unreached_text
from biped_sim.studies.fit.problem import Outcome
from biped_sim.studies.uncertainty.mfpt import mfpt_estimate

from .conftest import CONFIGS, DEFAULT_CONFIG, invoke, one_line_error

KNEED = yaml.safe_load((CONFIGS / "kneed_walker.yaml").read_text())
REFERENCE = CONFIGS / "references" / "synthetic_round_foot_periods.yaml"
PARAM = ("--param", "walker.leg_inertia=0.0043:0.006")


def _kneed(edit: Any) -> dict[str, Any]:
    data = copy.deepcopy(KNEED)
    edit(data["walker"]["description"], data)
    return data


def _massless_shank(d: dict[str, Any], _: dict[str, Any]) -> None:
    d["bodies"][2]["mass"] = 0.0


def _massless_all(d: dict[str, Any], _: dict[str, Any]) -> None:
    for body in d["bodies"]:
        body["mass"] = 0.0
    d["point_masses"] = []


def _hertz_point_feet(_: dict[str, Any], data: dict[str, Any]) -> None:
    material = {"youngs_modulus": 1.0e9, "poisson_ratio": 0.3}
    data["contact"] = {"materials": {"foot": material, "ground": material}}


def _compliant_point_feet(_: dict[str, Any], data: dict[str, Any]) -> None:
    data["dynamics"] = "compliant"


def _same_point_mass_names(d: dict[str, Any], _: dict[str, Any]) -> None:
    d["point_masses"].append(dict(d["point_masses"][0]))


def _too_many_point_masses(d: dict[str, Any], _: dict[str, Any]) -> None:
    d["point_masses"] = [{"name": f"p{i}", "body": "thigh_1", "mass": 0.001} for i in range(1001)]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_massless_shank, "walker.description.bodies.shank_1.mass: a body needs mass"),
        (_massless_all, "walker.description.bodies.thigh_1.mass: a body needs mass"),
        (_hertz_point_feet, "contact.stiffness: required for point feet"),
        (_compliant_point_feet, "contact.stiffness: required for point feet"),
        (_same_point_mass_names, "walker.description.point_masses: names must be unique"),
        (_too_many_point_masses, "walker.description.point_masses: List should have at most 1000 items"),
    ],
)
def test_a_described_walker_that_cannot_be_built_is_refused_by_the_schema(edit: Any, message: str) -> None:
    with pytest.raises(ConfigError) as refused:
        config_from_dict(_kneed(edit))
    assert str(refused.value).startswith(message)


def test_the_kneed_walkers_point_feet_stay_valid_when_rigid_without_materials() -> None:
    assert config_from_dict(copy.deepcopy(KNEED)).walker.description is not None


def test_a_huge_config_file_is_refused_before_it_is_parsed(tmp_path: Path) -> None:
    path = tmp_path / "huge.yaml"
    path.write_text("# padding\n" * (MAX_FILE_BYTES // 10 + 1))
    result = invoke("run", str(path), "--out", str(tmp_path / "out"))
    assert result.exit_code == 2 and "larger than a config file may be" in one_line_error(result.stderr)
    assert not (tmp_path / "out").exists()


def _reference(tmp_path: Path, **measurement: Any) -> Path:
    data = yaml.safe_load(REFERENCE.read_text())
    data.pop("quantity", None), data.pop("values", None), data.pop("std", None), data.pop("steps", None)
    data["measurements"] = [{"quantity": "step_period", "unit": "s", "mean": [0.4, 0.4], "std": [0.01, 0.01],
                             **measurement}]  # fmt: skip
    path = tmp_path / "reference.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(
    ("measurement", "field", "reason"),
    [
        ({"n_trials": 0}, "measurements.0.n_trials", "one number >= 1"),
        ({"steps": [1, 1_000_000]}, "measurements.0.steps", "step 1,000,000 is past the last step"),
        ({"mean": [0.4] * (MAX_STEPS + 1), "std": None}, "measurements.0.mean", "at most 10000 items"),
    ],
)
def test_a_reference_read_wrongly_or_never_matchable_is_refused(
    tmp_path: Path, measurement: dict[str, Any], field: str, reason: str
) -> None:
    with pytest.raises(ConfigError) as refused:
        load_reference(_reference(tmp_path, **measurement))
    assert refused.value.field.endswith(field) and reason in refused.value.reason


def _fit(tmp_path: Path, *args: str) -> tuple[int, str]:
    out = tmp_path / "fit"
    result = invoke("fit", str(DEFAULT_CONFIG), "--reference", str(REFERENCE), *args, "--out", str(out))
    leftovers = [p.name for p in tmp_path.iterdir() if "fit" in p.name]
    assert leftovers == [], leftovers  # nothing written: no output, no checkpoint folder
    return result.exit_code, one_line_error(result.stderr)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        ((*PARAM, "--posterior", "10", "--walkers", "3"), "error: --walkers: must be even and at least 2"),
        ((*PARAM, "--posterior", "10", "--walkers", "0"), "error: --walkers: must be even and at least 2"),
        ((*PARAM, "--posterior", "10"), "error: --posterior: at least 160"),
        ((*PARAM, "--walkers", "8"), "error: --walkers: only used with --posterior"),
        ((*PARAM, "--executor", "mpi"), "error: --executor: unknown executor 'mpi'"),
        ((*PARAM, "--quantity", "hip_height"), "error: --quantity: unknown quantity 'hip_height'; known: step_period"),
        ((*PARAM, "--skip-steps", "100000000"), "error: --skip-steps: reference step 7 is model step 100,000,007"),
    ],
)
def test_every_fit_option_is_checked_before_the_first_simulation(
    tmp_path: Path, args: tuple[str, ...], expected: str
) -> None:
    code, line = _fit(tmp_path, *args)
    assert code == 2 and line.startswith(expected), line


def test_a_fit_names_the_reference_steps_its_walker_never_reached() -> None:
    fell = Outcome((0.0, 0.4, 0.8), (0.0, 0.2, 0.4), (0.1, 0.1), (-0.1, -0.1), "fell", 0.9)
    assert unreached_text([], fell) is None
    text = unreached_text([3, 4, 3], fell)
    assert text == "the fitted walker never reaches reference step 3, 4 (its run ended fell after 2 model steps)"


def test_fit_problems_refuse_a_step_past_what_a_fit_simulates(tmp_path: Path) -> None:
    from biped_sim import load_config

    reference = load_reference(_reference(tmp_path, steps=[1, MAX_STEPS]))
    with pytest.raises(ConfigError, match="is model step 10,001"):
        fit_problems(load_config(DEFAULT_CONFIG), reference, [PARAM[1]], skip=1)


def test_uncertainty_refuses_zero_samples_and_unknown_spec_keys(tmp_path: Path) -> None:
    zero = invoke("uncertainty", str(DEFAULT_CONFIG), "--param", "ground.slope=uniform:0.018:0.022", "-n", "0",
                  "--out", str(tmp_path / "u"))  # fmt: skip
    assert zero.exit_code == 2 and one_line_error(zero.stderr).startswith("error: --samples: need at least 2")
    spec = tmp_path / "spec.yaml"
    spec.write_text(yaml.safe_dump({"uncertainty": {"parameters": {"ground.slope": "uniform:0.018:0.022"},
                                                    "sample": 8}}))  # fmt: skip
    typo = invoke("uncertainty", str(DEFAULT_CONFIG), "--spec", str(spec), "--out", str(tmp_path / "u"))
    assert typo.exit_code == 2 and one_line_error(typo.stderr) == (
        f"error: {spec}: uncertainty.sample: unknown key; expected parameters, samples, seed, method"
    )
    assert not (tmp_path / "u").exists()


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (("--seeds", "1000000000"), "error: --seeds: 1,000,000,000 walks"),
        (("--cap", "1000000000"), "error: --cap: must be from 1 to 100,000 steps on the slope ground"),
        (("--cap", "20000", "--ground", "height"), "error: --cap: must be from 1 to 10,000 steps on the height ground"),
    ],
)
def test_mfpt_bounds_its_walks_and_names_its_options(tmp_path: Path, args: tuple[str, ...], expected: str) -> None:
    result = invoke("mfpt", str(CONFIGS / "rimless_wheel.yaml"), "--roughness", "0.05", *args,
                    "--out", str(tmp_path / "m"))  # fmt: skip
    assert result.exit_code == 2 and one_line_error(result.stderr).startswith(expected)
    assert not (tmp_path / "m").exists()


def test_the_mfpt_interval_never_goes_below_one_step() -> None:
    estimate = mfpt_estimate(np.array([0, 7]), np.array([True, True]))
    assert estimate.mfpt == 4.5 and 1.0 <= estimate.ci[0] < 4.5 < estimate.ci[1]
    at_once = mfpt_estimate(np.array([0, 0, 0]), np.array([True, True, True]))
    assert at_once.mfpt == 1.0 and at_once.ci[0] == pytest.approx(1.0) and at_once.ci[1] > 1.0


def test_the_mfpt_interval_covers_a_geometric_first_passage_at_its_level() -> None:
    """2000 seeded sets of 20 walks with a 5 % chance of falling per step (MFPT 20), censored at 50 steps."""
    rng, p, cap = np.random.default_rng(1), 0.05, 50
    covered = 0
    for _ in range(2000):
        first_passage = rng.geometric(p, 20)  # the step of the fall, >= 1
        estimate = mfpt_estimate(np.minimum(first_passage - 1, cap), first_passage - 1 < cap)
        covered += estimate.ci[0] <= 1.0 / p <= estimate.ci[1]
    assert 0.93 <= covered / 2000 <= 0.97


@pytest.mark.parametrize("executor", [None, ThreadPoolExecutor(1)], ids=["serial", "executor"])
def test_a_batch_interrupted_keeps_its_finished_evaluations_for_the_checkpoint(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, executor: ThreadPoolExecutor | None
) -> None:
    """SIGTERM or Ctrl-C in the middle of a batch: the checkpoint written on the way out holds what finished."""
    from biped_sim import load_config
    from biped_sim.studies.fit import evaluate

    calls: list[int] = []

    def first_then_interrupted(data: dict[str, Any]) -> Outcome:
        calls.append(1)
        if len(calls) > 1:
            raise KeyboardInterrupt
        return Outcome((0.0, 0.4), (0.0, 0.2), (0.1,), (-0.1,), "walking", 0.4)

    monkeypatch.setattr(evaluate, "simulate_outcome", first_then_interrupted)
    [(_, problem)] = fit_problems(load_config(DEFAULT_CONFIG), load_reference(REFERENCE), [PARAM[1]])
    checkpoint = tmp_path / "fit.checkpoint.json"
    evaluator = evaluate.Evaluator(problem, executor, checkpoint)
    with pytest.raises(KeyboardInterrupt):
        evaluator.outcomes([[0.2], [0.4], [0.6]])
    evaluator.save()
    assert evaluator.evaluations == 1 and list(evaluator.cache) == [evaluate.point_key([0.2])]
    assert len(evaluate.Evaluator(problem, None, checkpoint).cache) == 1


def test_a_fit_that_never_reached_its_steps_prints_no_nan_error(capsys: pytest.CaptureFixture[str]) -> None:
    from biped_sim.cli.fit_commands import _print

    doc = {"parameters": {"walker.leg_inertia": 0.005}, "rms_error_s": math.nan, "rms_weighted_residual": 40.0,
           "evaluations": 50, "simulations": 50, "evaluations_replayed": 0, "wall_time_s": 1.0,
           "verdict": "not converged: the fitted walker never reaches reference step 7 (its run ended fell after 3 "
           "model steps)", "identifiability": {"warnings": []}, "misfit": None}  # fmt: skip
    _print(None, doc)
    line = capsys.readouterr().out.splitlines()[0]
    assert "nan" not in line and "never reaches reference step 7" in line
