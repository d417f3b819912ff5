"""Friction laws against mechanics: the incline's dry limits and LuGre against Canudas de Wit et al. (1995).

The pieces and the cheap rows are checked here; every row of both studies (every law, body and regime on the
incline, the sphere in space, LuGre's presliding, break-away and lag) is a row of ``biped-sim validate``, which
the slow tier runs and checks once (tests/test_validation.py), not twice."""

from __future__ import annotations

import dataclasses
import math

import pytest

from biped_sim.studies.friction_checks import (
    CHECKED_LAWS,
    MU_KINETIC,
    MU_STATIC,
    SCALES,
    SPHERE,
    creep_speed,
    dead_band,
    dry_coefficients,
    dry_limit_parameters,
    frictionless_row,
    incline_row,
    regularised_band,
    rolling_case,
    shrinks,
)
from biped_sim.studies.lugre_checks import steady_state_check

STICTION = {"bengisu_akay", "brown_mcphee", "lugre"}  # the laws whose dry limit has mu_s > mu_k


@pytest.mark.parametrize("law", CHECKED_LAWS)
def test_each_laws_dry_coefficients_are_read_from_the_law(law: str) -> None:
    mu_s, mu_k = dry_coefficients(law, dry_limit_parameters(1.0))
    assert mu_k == pytest.approx(MU_KINETIC, abs=1e-6)
    # Brown-McPhee's peak sits a little off mu_s (its tanh has not quite reached mu_k at v = v_t0)
    assert mu_s == pytest.approx(
        MU_STATIC if law in STICTION else MU_KINETIC, abs=2e-3 if law == "brown_mcphee" else 1e-6
    )


def test_creep_speeds_are_the_closed_forms_of_each_law() -> None:
    p = dry_limit_parameters(1.0)
    v0, r, mu = 1e-3, 0.27, MU_KINETIC
    closed = {
        "coulomb": v0 * r / math.sqrt(mu * mu - r * r),
        "threlfall": -v0 / 3.0 * math.log(1.0 - r / mu),
        "ambrosio": v0 + r / mu * (10.0 * v0 - v0),
        "bengisu_akay": v0 * (1.0 - math.sqrt(1.0 - r / MU_STATIC)),
        "lugre": 0.0,  # its bristles hold without slip
    }
    for law, speed in closed.items():
        assert creep_speed(law, r, p) == pytest.approx(speed, rel=1e-10, abs=1e-16), law


def test_only_ambrosio_has_a_dead_band_and_it_is_v0() -> None:
    p = dry_limit_parameters(1.0)
    bands = {law: dead_band(law, p) for law in CHECKED_LAWS}
    assert bands.pop("ambrosio") == pytest.approx(1e-3, rel=1e-12)
    assert set(bands.values()) == {0.0}


@pytest.mark.parametrize("law", [law for law in CHECKED_LAWS if law != "lugre"])
def test_the_regularised_band_shrinks_with_the_regularisation(law: str) -> None:
    base, fine = (regularised_band(law, dry_limit_parameters(scale)) for scale in SCALES)
    assert fine == pytest.approx(base * SCALES[1] / SCALES[0], rel=1e-3)


def test_lugre_settles_on_the_papers_steady_state_curve() -> None:
    check = steady_state_check()
    assert check.passed, check


def test_a_case_off_its_tolerance_or_not_shrinking_fails_its_row() -> None:
    case = rolling_case("coulomb", SPHERE, 1.0)
    fine = dataclasses.replace(case, scale=0.1, measured=case.expected + 0.6 * case.error, tolerance=case.tolerance)
    assert not shrinks(case, fine)  # the error must halve (at least) when the regularisation is 10x finer
    assert not incline_row([case, fine]).passed
    off = dataclasses.replace(case, measured=case.expected + 2.0 * case.tolerance + 1e-3)
    assert not off.passed and not incline_row([off]).passed
    assert not dataclasses.replace(case, slip=1.5 * case.creep).passed  # it must creep at the law's creep speed
    assert incline_row([case]).passed and "\n" not in str(incline_row([case]))


def test_without_friction_every_body_slides_at_g_sin_without_spin() -> None:
    row = frictionless_row()
    assert row.passed, row
