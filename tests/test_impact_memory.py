"""contact.impact_memory: a rebound continues its impact; the step periods no longer jump where one appears."""

from __future__ import annotations

import numpy as np
import pytest

from biped_sim import config_from_dict, simulate
from biped_sim.config import derive
from biped_sim.contact.response import remembered_impact_speed
from biped_sim.studies.impact_memory import count_rebounds, memory_scan

remember = remembered_impact_speed.py_func


def test_a_rebound_keeps_the_larger_speed_a_late_touchdown_is_a_new_impact() -> None:
    assert remember(0.15, 1.00, 1.004, 0.004, 0.1) == 0.15  # a rebound 4 ms after its lift-off
    assert remember(0.15, 1.00, 1.004, 0.30, 0.1) == 0.30  # a harder re-impact counts with its own speed
    assert remember(0.15, 1.00, 1.30, 0.004, 0.1) == 0.004  # a touchdown after a swing: a new impact
    assert remember(0.15, 1.00, 1.004, 0.004, 0.0) == 0.004  # recontact time 0: every touchdown (the old rule)


def test_rebound_counts_read_the_contact_log() -> None:
    rows = [[0.0, 0, 1, 0.2], [0.010, 0, -1, -0.05], [0.013, 0, 1, 0.004], [0.4, 0, -1, -0.1], [0.8, 0, 1, 0.2]]
    log = np.array(rows)
    assert count_rebounds(log, 0.1) == 1 and count_rebounds(log, 0.5) == 2


def test_periods_jump_where_a_rebound_appears_under_touchdown_memory_only() -> None:
    """Issue 20's reproduction: leg inertia 0.0049, e from 0.300 to 0.305 adds a rebound (1.3 ms jump before)."""
    config = config_from_dict({}, ["walker.leg_inertia=0.0049", "formulation.kind=minimal", "simulation.t_end=4"])
    scan = memory_scan(config, [0.3, 0.3025, 0.305])
    assert scan.rebounds["touchdown"][0] < scan.rebounds["touchdown"][-1]  # a rebound appears in between
    assert scan.largest_jump("touchdown") > 0.8e-3
    assert scan.largest_jump("impact") < 0.15e-3  # the smooth slope over 0.0025 of e: about 0.05 ms
    assert np.all(np.isfinite(scan.periods["impact"]))
    assert scan.rebounds["impact"].min() >= 3  # the heel strikes do rebound: the rule is exercised


def test_energy_balance_closes_through_rebounds() -> None:
    config = config_from_dict({}, ["contact.restitution=0.5", "simulation.t_end=4", "integrator.rtol=1e-9"])
    result = simulate(config)
    assert result.status == "walking"
    assert count_rebounds(result.run.contact_log, config.contact.recontact_time) >= 3
    m_g_l = result.model.total_mass * config.gravity * config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-5 * m_g_l


@pytest.mark.parametrize("memory", ["impact", "touchdown"])
def test_memory_is_invisible_without_rebounds(memory: str) -> None:
    """At e = 0.2 the heel strikes do not rebound: both memories give the same run bit for bit."""
    base = config_from_dict({}, ["contact.restitution=0.2", "simulation.t_end=2"])
    reference = simulate(derive(base, {"contact.impact_memory": "touchdown"})).summary
    summary = simulate(derive(base, {"contact.impact_memory": memory})).summary
    assert summary["step_times"] == reference["step_times"]
    assert summary["energy_dissipated"] == reference["energy_dissipated"]
