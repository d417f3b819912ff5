"""MuJoCo's soft contact matched to ours (:mod:`biped_sim.bench.mujoco_contact`): the clipped oscillator's restitution
against its closed form, the matched damping ratio, and (MuJoCo installed) a MuJoCo drop losing what our law loses."""

from __future__ import annotations

import math

import pytest

from biped_sim.bench.mujoco_contact import IMPEDANCE, clipped_restitution, matched_damping_ratio, matched_solref
from biped_sim.config import config_from_dict
from biped_sim.studies.drop_test import drop_test


def closed_form(zeta: float) -> float:
    """The under-damped clipped oscillator (omega = 1): it lets go where its acceleration vanishes,
    tan(w t) = 2 zeta w / (zeta^2 - w^2), w = sqrt(1 - zeta^2), with speed exp(-zeta t)(cos w t - zeta/w sin w t)."""
    w = math.sqrt(1.0 - zeta**2)
    t = math.atan2(2.0 * zeta * w, zeta**2 - w**2) / w
    return -math.exp(-zeta * t) * (math.cos(w * t) - zeta / w * math.sin(w * t))


@pytest.mark.parametrize("zeta", [0.1, 0.456, 0.9])
def test_the_clipped_oscillator_returns_its_closed_forms_speed(zeta: float) -> None:
    assert clipped_restitution(zeta) == pytest.approx(closed_form(zeta), rel=1e-9)
    assert clipped_restitution(zeta) > math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))  # it lets go early


def contact(model: str, restitution: float) -> object:
    return config_from_dict({"contact": {"model": model, "stiffness": 1e7, "restitution": restitution}})


def test_the_matched_damping_ratio_loses_what_flores_loses_and_an_elastic_law_none() -> None:
    zeta = matched_damping_ratio(contact("flores", 0.2))
    assert clipped_restitution(zeta) == pytest.approx(drop_test("flores", 0.2, 1e7)["effective_restitution"], 1e-8)
    assert 0.85 < zeta < 0.95  # the free oscillator's formula would give 0.456
    assert matched_damping_ratio(contact("hertz", 0.2)) == 0.0


def test_a_mujoco_drop_with_the_matched_solref_returns_our_laws_restitution() -> None:
    """A ball dropped at 0.5 m/s on MuJoCo's plane (RK4, 1e-5 s) with the matched solref (10 kg, static penetration
    1e-4 m): its rebound speed is our Flores law's within 3 % (the impedance's reference acceleration the rest)."""
    mujoco = pytest.importorskip("mujoco")
    config = contact("flores", 0.2)
    k, b = matched_solref(config, 10.0, 1e7, 1e-4)
    xml = f"""<mujoco><option timestep="1e-5" integrator="RK4" gravity="0 0 0"/><worldbody>
      <geom type="plane" size="1 1 0.1"/><body pos="0 0 0.1"><joint type="slide" axis="0 0 1"/>
      <geom type="sphere" size="0.1" mass="10" solref="{-k} {-b}" solimp="{IMPEDANCE} {IMPEDANCE} 0.001"/>
      </body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qvel[0] = -0.5
    mujoco.mj_step(model, data, nstep=5000)
    ours = drop_test("flores", 0.2, 1e7)["effective_restitution"]
    assert data.qvel[0] / 0.5 == pytest.approx(ours, rel=0.03)


def test_our_kelvin_voigt_law_is_the_clipped_oscillator_so_its_damping_ratio_is_the_free_formulas() -> None:
    """Kelvin-Voigt with D from e's free-oscillator zeta, clipped at zero force, is MuJoCo's contact exactly."""
    e = 0.2
    free = -math.log(e) / math.sqrt(math.pi**2 + math.log(e) ** 2)
    assert matched_damping_ratio(contact("kelvin_voigt", e)) == pytest.approx(free, rel=1e-6)
