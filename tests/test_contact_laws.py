"""Normal and friction force laws against their defining properties and the drop test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim.contact import friction as fr
from biped_sim.contact.normal import (
    NORMAL_LAWS,
    flores_chi,
    hertz_stiffness,
    hunt_crossley_chi,
    kelvin_voigt_damping,
    lankarani_nikravesh_chi,
    normal_force,
    normal_parameters,
)
from biped_sim.studies.drop_test import DROP_TEST_RESTITUTIONS, drop_test


def test_hertz_stiffness_formula() -> None:
    # steel sphere on steel plane, R = 0.01 m: E* = E / (2 (1 - nu^2))
    e, nu = 210e9, 0.3
    expected = 4.0 / 3.0 * e / (2 * (1 - nu**2)) * math.sqrt(0.01)
    assert hertz_stiffness(e, nu, e, nu, 0.01) == pytest.approx(expected, rel=1e-14)


def test_hysteresis_factors() -> None:
    assert hunt_crossley_chi(0.5) == pytest.approx(0.75)
    assert lankarani_nikravesh_chi(0.5) == pytest.approx(0.5625)
    assert flores_chi(0.5) == pytest.approx(1.6)
    assert flores_chi(1.0) == hunt_crossley_chi(1.0) == lankarani_nikravesh_chi(1.0) == 0.0


def test_kelvin_voigt_damping_gives_restitution_of_linear_oscillator() -> None:
    k, m, e = 1e6, 2.0, 0.4
    d = kelvin_voigt_damping(k, e, m)
    zeta = d / (2 * math.sqrt(k * m))
    assert math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)) == pytest.approx(e, rel=1e-12)


@pytest.mark.parametrize("model", list(NORMAL_LAWS))
def test_normal_force_is_never_sticky(model: str) -> None:
    p = normal_parameters(model, 1e6, 1.5, 0.3, None, 1.0)
    index = NORMAL_LAWS[model].index
    for delta_dot in np.linspace(-5, 5, 41):
        assert normal_force(index, 1e-4, delta_dot, 0.5, p) >= 0.0


@pytest.mark.parametrize("e", DROP_TEST_RESTITUTIONS)
def test_drop_test_restitution(e: float) -> None:
    assert drop_test("hertz", e)["effective_restitution"] == pytest.approx(1.0, abs=1e-4)
    assert drop_test("flores", e)["effective_restitution"] == pytest.approx(e, abs=0.05)


@pytest.mark.parametrize("model", ["hunt_crossley", "lankarani_nikravesh"])
def test_drop_test_hunt_crossley_family_at_high_restitution(model: str) -> None:
    assert drop_test(model, 0.9)["effective_restitution"] == pytest.approx(0.9, abs=0.02)


def test_dissipative_laws_lose_more_energy_at_lower_restitution() -> None:
    for model in ("kelvin_voigt", "hunt_crossley", "lankarani_nikravesh", "flores"):
        values = [drop_test(model, e)["effective_restitution"] for e in (0.3, 0.6, 0.9)]
        assert values[0] < values[1] < values[2] < 1.0


P = fr.friction_parameters(0.5, 0.7, 1e-3, 1e-2, 2e-3, 100.0, 0.0, 1e4, 20.0, 0.0)


@pytest.mark.parametrize("name", [n for n, law in fr.FRICTION_LAWS.items() if not law.stateful and n != "none"])
def test_friction_opposes_slip_and_is_odd(name: str) -> None:
    law = fr.FRICTION_LAWS[name].function
    for v in (1e-4, 3e-3, 0.05, 1.0):
        forward, backward = law(v, 10.0, P), law(-v, 10.0, P)
        assert forward <= 0.0
        assert backward == pytest.approx(-forward, rel=1e-14)
    assert law(0.0, 10.0, P) == 0.0


@pytest.mark.parametrize("name", ["coulomb", "threlfall", "ambrosio", "bengisu_akay"])
def test_friction_tends_to_kinetic_coulomb_at_large_slip(name: str) -> None:
    assert fr.FRICTION_LAWS[name].function(1.0, 10.0, P) == pytest.approx(-5.0, rel=1e-3)


def test_ambrosio_dead_zone_and_ramp() -> None:
    assert fr.ambrosio_friction(0.5e-3, 10.0, P) == 0.0
    assert fr.ambrosio_friction(5.5e-3, 10.0, P) == pytest.approx(-0.5 * 10.0 * 0.5)


def test_bengisu_akay_peaks_at_static_coefficient() -> None:
    assert fr.bengisu_akay_friction(2e-3, 10.0, P) == pytest.approx(-7.0)


def test_brown_mcphee_peak_exceeds_kinetic() -> None:
    speeds = np.linspace(1e-5, 1e-2, 2000)
    peak = max(-fr.brown_mcphee_friction(v, 10.0, P) for v in speeds)
    assert peak > 5.0
    assert -fr.brown_mcphee_friction(1.0, 10.0, P) == pytest.approx(5.0, rel=1e-3)


def test_lugre_steady_state_is_stribeck_curve() -> None:
    for v in (1e-3, 0.05):
        g = 0.5 + 0.2 * math.exp(-((v / 2e-3) ** 2))
        z_ss = g / P[fr.SIGMA0]
        assert fr.lugre_bristle_rate(v, z_ss, P) == pytest.approx(0.0, abs=1e-12)
        assert fr.lugre_friction(v, z_ss, 0.0, 10.0, P) == pytest.approx(-10.0 * g)


def test_lugre_has_no_force_without_normal_load() -> None:
    assert fr.lugre_friction(0.5, 1e-5, 0.5, 0.0, P) == 0.0
