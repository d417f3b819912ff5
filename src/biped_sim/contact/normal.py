"""Normal contact force laws (MODEL.md 4), compiled with numba.

Every law has the same signature ``law(delta, delta_dot, impact_speed, p) -> F_N`` with
``delta`` the penetration [m], ``delta_dot`` the approach velocity [m/s], ``impact_speed`` the
approach velocity remembered at contact onset (deltadot^-) and ``p`` the parameter vector built
by :func:`normal_parameters`: ``p[K, N, CHI, D]`` = stiffness, exponent, hysteresis factor,
linear damping. Laws return the unclipped force; :func:`normal_force` clips it at zero (no
"sticky" pull) so that clipping is applied once, for every law.

To add a law: write one ``@kernel`` function below and add one line to ``NORMAL_LAWS``:
:func:`normal_force` dispatches over the registry (:mod:`~biped_sim.contact.registry`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import literal_unroll

from biped_sim.contact.registry import registered_functions
from biped_sim.kernel import kernel

K, N, CHI, D = 0, 1, 2, 3
N_NORMAL_PARAMS = 4


@kernel
def hertz_force(delta: float, delta_dot: float, impact_speed: float, p: np.ndarray) -> float:
    """Hertz (1882): F_N = K delta^n. Elastic: no energy is lost in an impact."""
    return p[K] * delta ** p[N]


@kernel
def kelvin_voigt_force(delta: float, delta_dot: float, impact_speed: float, p: np.ndarray) -> float:
    """Kelvin-Voigt: F_N = K delta + D deltadot (linear spring and dashpot in parallel).

    D follows from e and the effective mass m_eff of the impact: for a linear oscillator
    e = exp(-zeta pi / sqrt(1 - zeta^2)), so zeta = -ln e / sqrt(pi^2 + ln^2 e) and
    D = 2 zeta sqrt(K m_eff) (computed in :func:`normal_parameters`). The force jumps to
    D deltadot^- at touchdown, the law's known flaw (Hunt and Crossley 1975).
    """
    return p[K] * delta + p[D] * delta_dot


@kernel
def hunt_crossley_force(delta: float, delta_dot: float, impact_speed: float, p: np.ndarray) -> float:
    """Hunt and Crossley (1975): F_N = K delta^n (1 + chi deltadot / deltadot^-), chi = 3(1 - e)/2.

    K. H. Hunt, F. R. E. Crossley, J. Appl. Mech. 42 (1975) 440-445.
    """
    return p[K] * delta ** p[N] * (1.0 + p[CHI] * delta_dot / impact_speed)


# Lankarani-Nikravesh and Flores share the Hunt-Crossley form; only chi differs
# (set in normal_parameters), so one compiled body serves the three laws.
lankarani_nikravesh_force = hunt_crossley_force
flores_force = hunt_crossley_force


@kernel
def elastic_force(delta: float, p: np.ndarray) -> float:
    """Conservative part K delta^n of every law (n = 1 for Kelvin-Voigt): its work is stored, not lost."""
    return p[K] * delta ** p[N]


@kernel
def elastic_energy(delta: float, p: np.ndarray) -> float:
    """Energy stored in the contact spring: K delta^(n+1) / (n+1)."""
    return p[K] * delta ** (p[N] + 1.0) / (p[N] + 1.0)


def hunt_crossley_chi(e: float) -> float:
    """Hunt-Crossley hysteresis factor chi = 3(1 - e)/2."""
    return 1.5 * (1.0 - e)


def lankarani_nikravesh_chi(e: float) -> float:
    """Lankarani and Nikravesh (1990), J. Mech. Des. 112:369-376: chi = 3(1 - e^2)/4."""
    return 0.75 * (1.0 - e * e)


def flores_chi(e: float) -> float:
    """Flores, Machado, Silva, Martins (2011), Multibody Syst. Dyn. 25:357-375: chi = 8(1 - e)/(5 e)."""
    return 8.0 * (1.0 - e) / (5.0 * e)


@dataclass(frozen=True)
class NormalLaw:
    """A registered normal law: its dispatch number, compiled function, hysteresis factor, and its force family.

    ``family`` names the force form: laws of one family are one force law whose free parameter (chi) each
    maps from the restitution in its own way, so with the restitution fitted they are reparametrisations of
    each other, which no data can tell apart (the fit's contest reports them as one, with the implied chi).
    """

    index: int
    function: Callable[..., float]
    chi: Callable[[float], float] | None
    family: str


NORMAL_LAWS: dict[str, NormalLaw] = {
    "hertz": NormalLaw(0, hertz_force, None, "hertz"),
    "kelvin_voigt": NormalLaw(1, kelvin_voigt_force, None, "kelvin_voigt"),
    "hunt_crossley": NormalLaw(2, hunt_crossley_force, hunt_crossley_chi, "hunt_crossley"),
    "lankarani_nikravesh": NormalLaw(3, lankarani_nikravesh_force, lankarani_nikravesh_chi, "hunt_crossley"),
    "flores": NormalLaw(4, flores_force, flores_chi, "hunt_crossley"),
}
# the compiled dispatch below reads the registry: law number i is the i-th function
NORMAL_FUNCTIONS = registered_functions(NORMAL_LAWS)


@kernel
def normal_force(model: int, delta: float, delta_dot: float, impact_speed: float, p: np.ndarray) -> float:
    """Dispatch to the law numbered ``model`` (its index in NORMAL_LAWS) and clip at zero."""
    f = 0.0
    index = 0
    for law in literal_unroll(NORMAL_FUNCTIONS):  # unrolled at compile time: one direct call per law
        if index == model:
            f = law(delta, delta_dot, impact_speed, p)
        index += 1  # noqa: SIM113 (numba cannot enumerate a literal_unroll)
    return f if f > 0.0 else 0.0


def hertz_stiffness(e_foot: float, nu_foot: float, e_ground: float, nu_ground: float, radius: float) -> float:
    """Hertz sphere-on-plane stiffness K = (4/3) E* sqrt(R), 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2."""
    e_star = 1.0 / ((1.0 - nu_foot**2) / e_foot + (1.0 - nu_ground**2) / e_ground)
    return 4.0 / 3.0 * e_star * math.sqrt(radius)


def kelvin_voigt_damping(stiffness: float, restitution: float, effective_mass: float) -> float:
    """Damping that gives restitution e for a linear oscillator of mass m_eff (undamped contact)."""
    if restitution >= 1.0:
        return 0.0
    log_e = math.log(restitution)
    zeta = -log_e / math.sqrt(math.pi**2 + log_e**2)
    return 2.0 * zeta * math.sqrt(stiffness * effective_mass)


def normal_parameters(
    model: str,
    stiffness: float,
    exponent: float,
    restitution: float,
    damping: float | None,
    effective_mass: float,
) -> np.ndarray:
    """Parameter vector [K, n, chi, D] for the compiled laws."""
    law = NORMAL_LAWS[model]
    p = np.zeros(N_NORMAL_PARAMS)
    p[K] = stiffness
    p[N] = 1.0 if model == "kelvin_voigt" else exponent
    p[CHI] = law.chi(restitution) if law.chi is not None else 0.0
    if model == "kelvin_voigt":
        p[D] = damping if damping is not None else kelvin_voigt_damping(stiffness, restitution, effective_mass)
    return p
