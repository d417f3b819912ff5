"""The bundled walkers walk; every normal law and friction law walks; heel strikes are debounced."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from biped_sim import config_from_dict, load_config, simulate
from biped_sim.contact.friction import FRICTION_LAWS
from biped_sim.contact.normal import NORMAL_LAWS
from biped_sim.simulate import RunResult
from biped_sim.testing import default_walker

from .conftest import CONFIGS

TIGHT = ["integrator.rtol=1e-9", "integrator.atol=1e-11"]

# Every normal law and every friction law once (the stiff friction laws cost ~1.5 s per simulated
# second under dopri5: the full 5 x 7 grid is the slow tier's).
ONE_WALK_PER_LAW = [
    ("kelvin_voigt", "coulomb"),
    ("hunt_crossley", "threlfall"),
    ("lankarani_nikravesh", "bengisu_akay"),
    ("flores", "brown_mcphee"),
    ("hertz", "lugre"),
    ("flores", "ambrosio"),
    ("hunt_crossley", "none"),
]


def law_overrides(normal: str, friction: str) -> list[str]:
    """The default walker with these laws (Hertz is elastic: restitution 1)."""
    overrides = [f"contact.model={normal}", f"friction.model={friction}"]
    if normal == "hertz":
        overrides.append("contact.restitution=1.0")
    return overrides


def test_one_walk_per_law_covers_every_law() -> None:
    assert {n for n, _ in ONE_WALK_PER_LAW} == set(NORMAL_LAWS)
    assert {f for _, f in ONE_WALK_PER_LAW} == set(FRICTION_LAWS)


@pytest.mark.parametrize(("normal", "friction"), ONE_WALK_PER_LAW)
def test_each_law_takes_the_first_step_with_its_energy_balanced(normal: str, friction: str) -> None:
    """0.5 s at tight tolerances: the first heel strike comes at 0.39 s (without friction the stance foot
    slides away first), and the energy books balance through it (over 3 s: test_conservation, slow tier)."""
    result = simulate(default_walker(*law_overrides(normal, friction), *TIGHT, t_end=0.5))
    if friction == "none":
        assert result.status == "fell" and result.summary["n_steps"] == 0
    else:
        assert result.status == "walking" and result.summary["n_steps"] == 1
    m_g_l = result.model.total_mass * result.config.gravity * result.config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-5 * m_g_l
    assert sum(result.summary["energy_dissipated"].values()) > 0.0  # there is something to balance


def test_short_walk_alternates_feet_moves_forward_and_barely_slips(short_run: RunResult) -> None:
    assert short_run.status == "walking" and short_run.summary["n_steps"] == 4
    feet = short_run.steps.foot
    assert np.all(feet[1:] != feet[:-1])
    assert np.all(short_run.step_lengths > 0.1)
    assert np.all(np.abs(short_run.summary["slip_per_step"]) < 1e-3)


@pytest.mark.slow
def test_default_walker_walks_steadily(default_run: RunResult) -> None:
    """15 s: the gait settles, the last ten periods agree to 1 %."""
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


@pytest.mark.slow
@pytest.mark.parametrize(("normal", "friction"), list(itertools.product(NORMAL_LAWS, FRICTION_LAWS)))
def test_every_law_combination_runs(normal: str, friction: str) -> None:
    result = simulate(config_from_dict({}, [*law_overrides(normal, friction), "simulation.t_end=2.5"]))
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
