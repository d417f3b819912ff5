"""The mean first-passage time of a rigid walker in space on random slopes (:mod:`biped_sim.studies.uncertainty.
space_slopes`): each step's state turned into its slope's frame, the walks, the command."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import load_config
from biped_sim.simulate.space_rigid import space_start
from biped_sim.studies.uncertainty.mfpt import mfpt_curve
from biped_sim.studies.uncertainty.space_slopes import space_slope_walks, tilted
from biped_sim.walkers.space_geometry import attitude, rot_y
from tests.conftest import invoke, one_line_error
from tests.test_space_run import STARTED, TINKERTOY


@pytest.mark.parametrize("change", [0.05, -0.1])
def test_a_change_of_slope_turns_the_state_and_leaves_the_walker_in_the_world(change: float) -> None:
    """The gait's post-strike state in the frame of a slope ``change`` steeper: the stance leg's attitude and angular
    velocity in the world (the slope's frame turned by the slope about its lateral axis) as they were, the hinge's
    too, and gravity in the world straight down from either frame (the walks' model on the steeper slope)."""
    start = space_start(load_config(TINKERTOY, [STARTED]))
    slope, x = start.model.slope, start.state
    turned = tilted(x, change)
    world = rot_y(slope) @ attitude(*x[:3])
    np.testing.assert_allclose(rot_y(slope + change) @ attitude(*turned[:3]), world, atol=1e-14)
    np.testing.assert_allclose(rot_y(slope + change) @ turned[4:7], rot_y(slope) @ x[4:7], atol=1e-14)
    assert turned[3] == x[3] and turned[7] == x[7] and abs(turned[2] - x[2]) == pytest.approx(abs(change), rel=0.1)
    np.testing.assert_array_equal(tilted(x, 0.0), x)
    steeper = replace(start.model, slope=slope + change)
    down = np.array([0.0, 0.0, -start.model.gravity])
    np.testing.assert_allclose(rot_y(slope + change) @ steeper.gravity_vector, down, atol=1e-15)
    np.testing.assert_allclose(rot_y(slope) @ start.model.gravity_vector, down, atol=1e-15)


def test_the_toy_walks_the_cap_on_its_slope_and_falls_sooner_the_rougher_the_slopes() -> None:
    """Roughness 0: every walk reaches the cap, the MFPT unbounded; slopes of sd 0.01 and 0.02 rad topple every walk
    within 30 steps, the rougher sooner; the same seeds give the same walks."""
    config = load_config(TINKERTOY, [STARTED])
    curve = mfpt_curve(config, "slope", [0.0, 0.01, 0.02], seeds=6, cap=30)
    smooth, rough, rougher = curve.estimates
    assert smooth.falls == 0 and smooth.censored == 6 and math.isinf(smooth.mfpt)
    assert rough.falls == rougher.falls == 6 and 1.0 < rougher.mfpt < rough.mfpt < 30.0
    assert curve.chain is None and "kink" in curve.notes[0]
    strikes, fell = space_slope_walks(config, 0.01, range(6), 30)
    assert fell.all() and strikes.sum() + 6 == pytest.approx(rough.mfpt * 6)


def test_mfpt_of_the_toy_picks_random_slopes_and_writes_its_curve(tmp_path: Path) -> None:
    """``biped-sim mfpt`` on a rigid walker in space walks random slopes by default (as the rimless wheel)."""
    out = tmp_path / "mfpt"
    args = ("mfpt", str(TINKERTOY), "--set", STARTED, "--roughness", "0.02", "--seeds", "2", "--cap", "20")
    result = invoke(*args, "--out", str(out))
    assert result.exit_code == 0, result.stderr
    doc = json.loads((out / "mfpt.json").read_text())
    assert doc["ground"] == "slope" and doc["levels"][0]["falls"] == 2 and "chain_mfpt" not in doc["levels"][0]


def test_a_compliant_walker_in_space_walks_no_random_slopes() -> None:
    path = TINKERTOY.with_name("tinkertoy_compliant.yaml")
    compliant = load_config(path)
    result = invoke("mfpt", str(path), "--ground", "slope")
    assert compliant.dynamics == "compliant" and result.exit_code == 2
    message = "error: --ground: random slopes per step are walked by the rigid rimless wheel and rigid walkers in space"
    assert one_line_error(result.stderr).startswith(message)
