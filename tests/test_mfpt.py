"""Mean first-passage time on random ground: the censored estimate, the rimless wheel's chain against its walks."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from biped_sim import load_config
from biped_sim.report.uncertainty import mfpt_figure
from biped_sim.studies.uncertainty.mfpt import MfptCurve, mfpt_curve, mfpt_estimate
from biped_sim.studies.uncertainty.rimless_chain import Wheel

from .conftest import CONFIGS, invoke, one_line_error

WHEEL = CONFIGS / "rimless_wheel.yaml"


def test_uncensored_walks_give_their_mean_first_passage_the_falling_step_counted() -> None:
    estimate = mfpt_estimate(np.array([10, 20, 30]), np.array([True, True, True]))
    assert estimate.mfpt == 21 and estimate.ci[0] < 21 < estimate.ci[1] and estimate.censored == 0


def test_censored_walks_give_steps_over_falls_and_no_fall_only_a_lower_bound() -> None:
    censored = mfpt_estimate(np.array([10, 100, 100]), np.array([True, False, False]))
    assert censored.mfpt == pytest.approx(211) and censored.censored == 2
    assert censored.ci[0] < 211 < censored.ci[1]
    none = mfpt_estimate(np.array([100, 100]), np.array([False, False]))
    assert math.isinf(none.mfpt) and math.isinf(none.ci[1]) and 0 < none.ci[0] < 200


def test_a_level_without_falls_is_drawn_as_its_lower_bound_without_warnings() -> None:
    fell = mfpt_estimate(np.array([10, 100]), np.array([True, False]))
    none = mfpt_estimate(np.array([100, 100]), np.array([False, False]))
    curve = MfptCurve("slope", [0.02, 0.01], [fell, none], chain=None, seeds=2, cap=100)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        figure = mfpt_figure([curve])
    (ax,) = figure.axes
    bound = next(line for line in ax.get_lines() if line.get_label() == "no fall: MFPT above")
    assert list(bound.get_xdata()) == [0.01] and list(bound.get_ydata()) == [none.ci[0]]


def test_the_apex_map_has_the_wheel_s_fixed_point() -> None:
    wheel = Wheel.of(load_config(WHEEL))
    x = wheel.nominal_apex_rate()
    assert wheel.apex_map(np.array([x]), np.array([wheel.slope]))[0] == pytest.approx(x, rel=1e-12)
    assert np.isnan(wheel.apex_map(np.array([0.0]), np.array([wheel.slope - 0.2]))[0])  # uphill from rest: falls


def test_rimless_walks_agree_with_the_markov_chain_on_rough_slopes() -> None:
    curve = mfpt_curve(load_config(WHEEL), "slope", [0.04], seeds=300, cap=2000)
    (estimate,) = curve.estimates
    assert curve.chain is not None and estimate.ci[0] <= curve.chain[0] <= estimate.ci[1]


def test_the_mfpt_cli_writes_json_and_a_figure(tmp_path: Path) -> None:
    out = tmp_path / "m"
    result = invoke("mfpt", str(WHEEL), "--roughness", "0.05", "--seeds", "20", "--cap", "500", "--out", str(out),
                    "--json")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["levels"][0]["falls"] == 20 and doc["levels"][0]["chain_mfpt"] > 1
    assert {p.name for p in out.iterdir()} == {"mfpt.json", "mfpt.png", "mfpt.svg"}


@pytest.mark.slow
def test_the_default_walker_walks_random_heights_until_a_fall_or_the_cap() -> None:
    curve = mfpt_curve(load_config(CONFIGS / "round_foot_walker.yaml"), "height", [0.002, 0.02], seeds=3, cap=5)
    rough, very = curve.estimates
    assert rough.falls + rough.censored == 3 and very.falls == 3  # 2 % of the leg length: every walk falls
    assert very.mfpt < 5 and curve.chain is None


@pytest.mark.parametrize(
    ("config", "args", "field"),
    [
        (WHEEL, ("--roughness", "0.01,x"), "--roughness"),
        (WHEEL, ("--roughness", "-0.01"), "--roughness"),
        (CONFIGS / "round_foot_walker.yaml", ("--ground", "slope"), "--ground"),
        (WHEEL, ("--seeds", "1"), "--seeds"),
    ],
)
def test_bad_mfpt_input_is_one_line(tmp_path: Path, config: Path, args: tuple[str, ...], field: str) -> None:
    result = invoke("mfpt", str(config), *args, "--out", str(tmp_path / "m"))
    assert result.exit_code == 2 and field in one_line_error(result.stderr)
    assert not (tmp_path / "m").exists()
