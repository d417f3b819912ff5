"""Energy balance and constraint drift: the strongest internal checks of the implementation."""

from __future__ import annotations

import numpy as np
import pytest

from biped_sim import config_from_dict, simulate


def test_energy_balance_over_10s_dopri5_tight() -> None:
    config = config_from_dict({}, ["simulation.t_end=10", "integrator.rtol=1e-9", "integrator.atol=1e-11"])
    result = simulate(config)
    assert result.status == "walking"
    m_g_l = result.model.total_mass * config.gravity * config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-5 * m_g_l
    # the walker really dissipates: the check is not trivially satisfied
    assert result.summary["energy_dissipated"]["normal"] > 0.1 * m_g_l
    assert result.summary["energy_dissipated"]["friction"] > 0.0


@pytest.mark.slow  # the stiff friction laws: ~20 s in all; 0.5 s of each law is in test_walking's fast tier
@pytest.mark.parametrize(
    "overrides",
    [
        ["contact.model=kelvin_voigt", "friction.model=coulomb"],
        ["contact.model=hunt_crossley", "friction.model=threlfall"],
        ["contact.model=lankarani_nikravesh", "friction.model=bengisu_akay"],
        ["contact.model=flores", "friction.model=brown_mcphee"],
        ["contact.model=flores", "friction.model=lugre"],
    ],
)
def test_energy_balance_other_laws(overrides: list[str]) -> None:
    config = config_from_dict({}, [*overrides, "simulation.t_end=3", "integrator.rtol=1e-9", "integrator.atol=1e-11"])
    result = simulate(config)
    m_g_l = result.model.total_mass * config.gravity * config.walker.leg_length
    assert np.max(np.abs(result.energy.residual)) < 1e-5 * m_g_l


def test_hertz_without_friction_conserves_mechanical_energy() -> None:
    config = config_from_dict(
        {}, ["contact.model=hertz", "friction.model=none", "simulation.t_end=1", "integrator.rtol=1e-10"]
    )
    result = simulate(config)
    assert result.summary["energy_dissipated"]["normal"] == 0.0
    assert result.summary["energy_dissipated"]["friction"] == 0.0
    total = result.energy.kinetic + result.energy.potential + result.energy.elastic
    assert np.ptp(total) < 1e-7 * result.model.total_mass * 9.81 * 0.5


def test_baumgarte_bounds_constraint_drift_standard_method_does_not() -> None:
    baumgarte = simulate(config_from_dict({}, ["simulation.t_end=10", "integrator.rtol=1e-6", "integrator.atol=1e-8"]))
    standard = simulate(
        config_from_dict(
            {},
            [
                "simulation.t_end=10",
                "integrator.rtol=1e-6",
                "integrator.atol=1e-8",
                "formulation.baumgarte.alpha=0",
                "formulation.baumgarte.beta=0",
            ],
        )
    )
    b, s = baumgarte.summary["constraint_violation_max"], standard.summary["constraint_violation_max"]
    assert b["position"] < 1e-8
    assert s["position"] > 10 * b["position"]
    # without stabilisation the drift grows with time
    drift = standard.violation[:, 0]
    half = len(drift) // 2
    assert drift[half:].max() > drift[:half].max()
