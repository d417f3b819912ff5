"""MuJoCo's soft contact matched to this project's contact law (plain numbers: MuJoCo is not imported here).

MuJoCo's contact is a constraint on the acceleration, a + d (b v + k r) = (1 - d) a0 with the impedance d, written
with a direct ``solref = -k -b``: in the normal direction a linear spring-damper in acceleration units, whose force
is clipped at zero (a contact pushes, never pulls). Two numbers are matched:

* frequency: our law linearised at the static penetration under the whole weight, omega^2 = n K delta_s^(n-1) / M;
* damping ratio: the one whose *clipped* oscillator loses what our law loses in a strike. The clipped oscillator
  lets go when its force k r + b v reaches zero, before it is back at the surface, so it returns more speed than
  the free oscillator's exp(-zeta pi / sqrt(1 - zeta^2)): at zeta = 0.456 (that formula's zeta for e = 0.2) it
  returns 0.32 of the approach speed. Our law's effective restitution is its drop test's
  (:func:`~biped_sim.studies.drop_test.drop_test`: Flores at nominal e = 0.2 returns 0.156), reached by the
  clipped oscillator at zeta = 0.90. Matching the free oscillator's formula instead made MuJoCo's heel strikes
  lose half as much energy as ours; on the laterally unstable Kuo-type compass (multiplier -5) that put its
  second and third steps 1 % off ours (docs/guide/formulations.md gives the measurement).
"""

from __future__ import annotations

import functools
import math

from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from biped_sim.config import Config
from biped_sim.studies.drop_test import drop_test

IMPEDANCE = 0.95  # solimp d (constant): the fraction of the reference acceleration the contact enforces
ZETA_RANGE = (1e-3, 20.0)  # damping ratios searched: restitution from 0.997 to 0.0005


def clipped_restitution(zeta: float) -> float:
    """Separation over approach speed of a linear spring-damper (damping ratio ``zeta``) whose force is clipped at
    zero: it lets go when k r + b v = 0 (dimensionless: omega = 1, approach speed 1)."""

    def force(_t: float, y: list[float]) -> float:
        return y[0] + 2.0 * zeta * y[1]

    force.terminal, force.direction = True, -1  # type: ignore[attr-defined]
    run = solve_ivp(
        lambda _t, y: [y[1], -2.0 * zeta * y[1] - y[0]], (0.0, 100.0), [0.0, 1.0], events=force, rtol=1e-12, atol=1e-14
    )
    return float(-run.y_events[0][0][1])


def matched_damping_ratio(config: Config) -> float:
    """The damping ratio of MuJoCo's clipped contact that returns our law's effective restitution, its drop test's
    (at the drop test's own stiffness: every law's is free of the stiffness and mass, as Hunt-Crossley's family and
    Kelvin-Voigt with its damping from e scale with them); 0 for an elastic law, the largest searched for a
    plastic one (e = 0: Flores's is undefined)."""
    return _damping_ratio(config.contact.model, config.contact.restitution)


@functools.lru_cache(maxsize=64)
def _damping_ratio(model: str, restitution: float) -> float:
    """:func:`matched_damping_ratio` of a law and its nominal restitution (a drop test and a root search: kept)."""
    if restitution == 0.0:
        return ZETA_RANGE[1]
    target = float(drop_test(model, restitution)["effective_restitution"])
    if target >= clipped_restitution(ZETA_RANGE[0]):
        return 0.0
    return float(brentq(lambda z: clipped_restitution(z) - target, *ZETA_RANGE, xtol=1e-10))


def matched_solref(config: Config, mass: float, stiffness: float, penetration: float) -> tuple[float, float]:
    """(k, b) of MuJoCo's direct solref: our law's frequency linearised at the static ``penetration`` under
    ``mass``, and the damping ratio whose clipped contact loses what ours loses (:func:`matched_damping_ratio`)."""
    n = 1.0 if config.contact.model == "kelvin_voigt" else config.contact.exponent
    omega = math.sqrt(n * stiffness * penetration ** (n - 1.0) / mass)
    zeta = matched_damping_ratio(config)
    return omega**2 / IMPEDANCE, 2.0 * zeta * omega / IMPEDANCE
