"""The bundled walkers walk; every normal law x friction law runs; heel strikes are debounced."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from biped_sim import config_from_dict, load_config, simulate
from biped_sim.contact.friction import FRICTION_LAWS
from biped_sim.contact.normal import NORMAL_LAWS
from biped_sim.simulate import RunResult

from .conftest import CONFIGS


def test_default_walker_walks_steadily(default_run: RunResult) -> None:
    assert default_run.status == "walking"
    assert default_run.summary["n_steps"] >= 30
    last = default_run.step_periods[-10:]
    assert (last.max() - last.min()) / last.mean() < 0.01
    # alternating feet, forward progress, little slip
    feet = default_run.steps.foot
    assert np.all(feet[1:] != feet[:-1])
    assert np.all(default_run.step_lengths > 0.1)
    assert np.all(np.abs(default_run.summary["slip_per_step"]) < 1e-3)


def test_compass_goswami_walks() -> None:
    result = simulate(load_config(CONFIGS / "compass_goswami.yaml"))
    assert result.status == "walking"
    assert result.summary["n_steps"] >= 10
    last = result.step_periods[-4:]
    assert (last.max() - last.min()) / last.mean() < 0.02


@pytest.mark.parametrize(("normal", "friction"), list(itertools.product(NORMAL_LAWS, FRICTION_LAWS)))
def test_every_law_combination_runs(normal: str, friction: str) -> None:
    overrides = [f"contact.model={normal}", f"friction.model={friction}", "simulation.t_end=2.5"]
    if normal == "hertz":
        overrides.append("contact.restitution=1.0")
    result = simulate(config_from_dict({}, overrides))
    assert result.status in ("walking", "fell")
    if friction != "none":  # without friction the stance foot slides away before the first step
        assert result.summary["n_steps"] >= 1


def test_steeper_slope_falls_and_reports_time() -> None:
    result = simulate(config_from_dict({}, ["ground.slope=0.2", "simulation.t_end=5"]))
    assert result.status == "fell"
    assert 0.0 < result.summary["stop_time"] < 5.0
    assert result.summary["t_end"] == pytest.approx(result.summary["stop_time"])


def test_max_steps_stops_the_run() -> None:
    result = simulate(config_from_dict({}, ["simulation.max_steps=4"]))
    assert result.summary["n_steps"] == 4
    assert result.run.t_final == pytest.approx(result.heel_strike_times[-1])


def test_bounces_belong_to_one_heel_strike() -> None:
    """A bouncy foot (e = 0.9, Hunt-Crossley) touches down several times per strike."""
    result = simulate(
        config_from_dict({}, ["contact.model=hunt_crossley", "contact.restitution=0.9", "simulation.t_end=3"])
    )
    log = result.run.contact_log
    touchdowns = int(np.sum(log[:, 2] > 0))
    assert touchdowns > result.summary["n_steps"]  # bounces happened
    assert np.all(result.steps.foot[1:] != result.steps.foot[:-1])
