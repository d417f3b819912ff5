"""Drop test: the standard check of a dissipative contact law (MODEL.md 4).

A disc (mass 1 kg, radius 0.15 m, uniform: J = m R^2 / 2) meets the ground at 1 m/s without
friction; gravity is switched off during the flight and the contact so that the measured
effective restitution, separation speed over approach speed, is that of the law alone
(equivalent to a drop from 5.1 cm when gravity's impulse during the ~1 ms contact is
neglected). The contact stiffness is the Hertz value of the default materials. Integration
is dopri5 at rtol 1e-11 with touchdown and lift-off located as events, so the speeds come
straight from the event log.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import IntegratorConfig, MaterialsConfig
from biped_sim.contact.friction import FRICTION_LAWS, friction_parameters
from biped_sim.contact.normal import NORMAL_LAWS, hertz_stiffness, normal_parameters
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.planar import PlanarSystem

DROP_TEST_RESTITUTIONS = (0.3, 0.5, 0.7, 0.9)
DISC_MASS = 1.0  # kg
DISC_RADIUS = 0.15  # m
APPROACH_SPEED = 1.0  # m/s
IMPACT_FLOOR = 1e-3  # m/s


def drop_system(model: str, restitution: float, stiffness: float | None = None, exponent: float = 1.5) -> PlanarSystem:
    """One free disc with one frictionless round foot at its centre, no joints, no gravity."""
    if stiffness is None:
        m = MaterialsConfig()
        stiffness = hertz_stiffness(
            m.foot.youngs_modulus, m.foot.poisson_ratio, m.ground.youngs_modulus, m.ground.poisson_ratio, DISC_RADIUS
        )
    normal = normal_parameters(model, stiffness, exponent, restitution, None, DISC_MASS)
    return PlanarSystem(
        body_mass=np.array([DISC_MASS]),
        body_inertia=np.array([0.5 * DISC_MASS * DISC_RADIUS**2]),
        joint_bodies=np.zeros((0, 2), dtype=np.int64),
        joint_points=np.zeros((0, 4)),
        foot_body=np.array([0], dtype=np.int64),
        foot_center=np.zeros((1, 2)),
        foot_radius=np.array([DISC_RADIUS]),
        foot_partner=np.array([-1], dtype=np.int64),
        gravity=np.zeros(2),
        baumgarte=np.zeros(2),
        normal_params=normal,
        friction_params=friction_parameters(0, 0, 1e-3, 1e-2, 1e-3, 0, 0, 1e5, 0, 0),
        switches=np.array([NORMAL_LAWS[model].index, FRICTION_LAWS["none"].index, 0], dtype=np.int64),
        limits=np.array([IMPACT_FLOOR, -math.inf, math.inf, 0.0]),  # one impact: no re-contact
    )


def drop_test(model: str, restitution: float, stiffness: float | None = None) -> dict[str, float | str]:
    """Effective restitution of one law at nominal e: separation over approach speed."""
    system = drop_system(model, restitution, stiffness)
    gap = 1.234e-4  # deliberately not a multiple of any step
    y0 = np.zeros(6 + 1 + 2)
    y0[1] = DISC_RADIUS + gap
    y0[4] = -APPROACH_SPEED
    modes0 = np.array([[1.0, 0.0, 0.0, 0.0]])
    integrator = IntegratorConfig(method="dopri5", rtol=1e-11, atol=1e-14, max_step=1e-4)
    run = integrate_model(system, y0, modes0, integrator, t_end=0.05, sample_rate=100.0)
    log = run.contact_log
    onsets = log[log[:, 2] > 0]
    separations = log[log[:, 2] < 0]
    if len(onsets) == 0 or len(separations) == 0:
        raise RuntimeError(f"drop test {model} e={restitution}: no complete impact within 0.05 s")
    v_in, v_out = onsets[0, 3], -separations[0, 3]
    return {
        "model": model,
        "nominal_restitution": restitution,
        "effective_restitution": v_out / v_in,
        "approach_speed": v_in,
        "separation_speed": v_out,
        "contact_duration": float(separations[0, 0] - onsets[0, 0]),
    }


def drop_test_table(
    models: list[str] | tuple[str, ...] = tuple(NORMAL_LAWS),
    restitutions: list[float] | tuple[float, ...] = DROP_TEST_RESTITUTIONS,
) -> list[dict[str, float | str]]:
    """Drop test for every (law, e) pair."""
    return [drop_test(model, e) for model in models for e in restitutions]
