"""Tangential friction laws (MODEL.md 5), compiled with numba.

Every stateless law has the signature ``law(v, f_n, p) -> F_T``: ``v`` is the slip velocity of
the contact point along the ground tangent [m/s], ``f_n >= 0`` the normal force [N], ``p`` the
parameter vector of :func:`friction_parameters`, and the returned force (along the same tangent)
opposes the slip. LuGre carries a bristle deflection ``z`` per contact in the ODE state and has
its own pair of functions.

To add a law: one ``@kernel`` function and one line in ``FRICTION_LAWS`` (a law with state goes last):
:func:`friction_force` dispatches over the registry (:mod:`~biped_sim.contact.registry`). In space a contact
patch also resists spinning about its normal: :func:`spin_friction_torque`, any stateless law applied to the
spin velocity of an effective radius (off unless ``spin_radius`` > 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import literal_unroll

from biped_sim.contact.registry import registered_functions
from biped_sim.kernel import kernel

MU_K, MU_S, V0, V1, VS, XI, VISC, SIGMA0, SIGMA1, SIGMA2, SPIN_RADIUS = range(11)


@kernel
def _sign(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@kernel
def no_friction(v: float, f_n: float, p: np.ndarray) -> float:
    """Frictionless contact: F_T = 0."""
    return 0.0


@kernel
def coulomb_friction(v: float, f_n: float, p: np.ndarray) -> float:
    """Coulomb, regularised for an ODE: F_T = -mu_k F_N v / sqrt(v^2 + v0^2).

    The square-root regularisation replaces sgn(v) within |v| ~ v0 (stick is a slow creep);
    it is smooth, so adaptive integrators need no switching logic.
    """
    return -p[MU_K] * f_n * v / math.sqrt(v * v + p[V0] * p[V0])


@kernel
def threlfall_friction(v: float, f_n: float, p: np.ndarray) -> float:
    """Threlfall (1978): F_T = -mu_k F_N (1 - exp(-3|v|/v0)) sgn(v)."""
    return -p[MU_K] * f_n * (1.0 - math.exp(-3.0 * abs(v) / p[V0])) * _sign(v)


@kernel
def ambrosio_friction(v: float, f_n: float, p: np.ndarray) -> float:
    """Ambrosio (2003): F_T = -mu_k c_d F_N sgn(v), c_d = 0 below v0, linear to 1 at v1, 1 above.

    J. Ambrosio, "Impact of rigid and flexible multibody systems", Virtual Nonlinear Multibody
    Systems, Kluwer (2003) 57-81.
    """
    speed = abs(v)
    if speed <= p[V0]:
        return 0.0
    c_d = 1.0 if speed >= p[V1] else (speed - p[V0]) / (p[V1] - p[V0])
    return -p[MU_K] * c_d * f_n * _sign(v)


@kernel
def bengisu_akay_friction(v: float, f_n: float, p: np.ndarray) -> float:
    """Bengisu and Akay (1994) Stribeck law.

    mu = -(mu_s / v_s^2)(|v| - v_s)^2 + mu_s for |v| < v_s;
    mu = mu_k + (mu_s - mu_k) exp(-xi (|v| - v_s)) for |v| >= v_s; F_T = -mu F_N sgn(v).
    M. T. Bengisu, A. Akay, J. Sound Vib. 171 (1994) 557-570.
    """
    speed = abs(v)
    if speed < p[VS]:
        mu = -(p[MU_S] / (p[VS] * p[VS])) * (speed - p[VS]) ** 2 + p[MU_S]
    else:
        mu = p[MU_K] + (p[MU_S] - p[MU_K]) * math.exp(-p[XI] * (speed - p[VS]))
    return -mu * f_n * _sign(v)


@kernel
def brown_mcphee_friction(v: float, f_n: float, p: np.ndarray) -> float:
    """Brown and McPhee (2016): F_T = -(F_N [mu_k tanh(4 v_r) + (mu_s - mu_k) v_r / (0.25 v_r^2 + 0.75)^2] + mu_v v).

    v_r = v / v_t0 (v_t0 = ``v0``). P. Brown, J. McPhee, J. Comput. Nonlinear Dyn. 11 (2016) 054502.
    """
    v_r = v / p[V0]
    mu = p[MU_K] * math.tanh(4.0 * v_r) + (p[MU_S] - p[MU_K]) * v_r / (0.25 * v_r * v_r + 0.75) ** 2
    return -(f_n * mu + p[VISC] * v)


@kernel
def lugre_bristle_rate(v: float, z: float, p: np.ndarray) -> float:
    """LuGre bristle dynamics per unit normal load: zdot = v - sigma0 |v| z / g(v).

    g(v) = mu_k + (mu_s - mu_k) exp(-(v/v_s)^2). C. Canudas de Wit, H. Olsson, K. J. Astrom,
    P. Lischinsky, IEEE TAC 40 (1995) 419-425, in the load-proportional form used for contact
    (sigma0 [1/m], sigma1 [s/m] per newton of normal force): MODEL.md's form divides by
    g = F_N (...) and lets sigma1 zdot act with no normal load, which at touchdown (F_N -> 0,
    zdot = v) throws a finite friction force without any normal force. Steady sliding gives the
    same Stribeck curve F_T = -F_N g(v) sgn(v) - sigma2 v in both forms.
    """
    g = p[MU_K] + (p[MU_S] - p[MU_K]) * math.exp(-((v / p[VS]) ** 2))
    return v - p[SIGMA0] * abs(v) * z / g


@kernel
def lugre_friction(v: float, z: float, z_dot: float, f_n: float, p: np.ndarray) -> float:
    """LuGre friction force F_T = -(F_N (sigma0 z + sigma1 zdot) + sigma2 v)."""
    return -(f_n * (p[SIGMA0] * z + p[SIGMA1] * z_dot) + p[SIGMA2] * v)


@dataclass(frozen=True)
class FrictionLaw:
    """A registered friction law: dispatch number, compiled function, and whether it carries state."""

    index: int
    function: Callable[..., float]
    stateful: bool = False


FRICTION_LAWS: dict[str, FrictionLaw] = {
    "none": FrictionLaw(0, no_friction),
    "coulomb": FrictionLaw(1, coulomb_friction),
    "threlfall": FrictionLaw(2, threlfall_friction),
    "ambrosio": FrictionLaw(3, ambrosio_friction),
    "bengisu_akay": FrictionLaw(4, bengisu_akay_friction),
    "brown_mcphee": FrictionLaw(5, brown_mcphee_friction),
    "lugre": FrictionLaw(6, lugre_friction, stateful=True),
}
LUGRE = FRICTION_LAWS["lugre"].index  # the one law with state: the kernels call it with its bristles
# the compiled dispatch below reads the registry: law number i is the i-th stateless function
FRICTION_FUNCTIONS = registered_functions(FRICTION_LAWS, stateless_only=True)


@kernel
def friction_force(model: int, v: float, f_n: float, p: np.ndarray) -> float:
    """Dispatch to the stateless law numbered ``model`` (its index in FRICTION_LAWS); 0 for any other number."""
    f = 0.0
    index = 0
    for law in literal_unroll(FRICTION_FUNCTIONS):  # unrolled at compile time: one direct call per law
        if index == model:
            f = law(v, f_n, p)
        index += 1  # noqa: SIM113 (numba cannot enumerate a literal_unroll)
    return f


@kernel
def spin_friction_torque(model: int, w_n: float, f_n: float, p: np.ndarray) -> float:
    """Spin (drilling) friction torque about the contact normal: M_n = r_s F_T(r_s w_n, F_N).

    ``w_n`` is the foot's angular velocity about the normal [rad/s] (the ground's is 0) and r_s = ``p[SPIN_RADIUS]``
    the patch's effective spin radius [m]; F_T is the stateless law numbered ``model`` (:func:`friction_force`)
    taken at the speed r_s w_n of a point r_s from the patch's centre, so it opposes the spin with the law's own
    dry limit and regularisation; 0 when r_s = 0. Dry (Coulomb) friction spread over a Hertzian patch of radius
    a, whose pressure is p0 sqrt(1 - r^2/a^2), gives |M_n| = mu F_N 3 pi a / 16 in full sliding, i.e.
    r_s = 3 pi a / 16 (K. L. Johnson, Contact Mechanics, Cambridge 1985, ch. 7; V. L. Popov, Contact Mechanics
    and Friction, Springer 2010, sec. 8.2.4). The torque is independent of the slip of the patch's centre: the
    Contensou coupling, which lowers both the force and the torque when slip and spin combine (R. I. Leine,
    C. Glocker, Eur. J. Mech. A/Solids 22 (2003) 193-216), is left out, so a foot that both slips and spins
    dissipates a little more than a dry patch would.
    """
    r_s = p[SPIN_RADIUS]
    return r_s * friction_force(model, r_s * w_n, f_n, p)


def friction_parameters(
    mu_kinetic: float,
    mu_static: float,
    v0: float,
    v1: float,
    v_stribeck: float,
    stribeck_decay: float,
    viscous: float,
    sigma0: float,
    sigma1: float,
    sigma2: float,
    spin_radius: float = 0.0,
) -> np.ndarray:
    """Parameter vector for the compiled laws (index constants at the top of this module); ``spin_radius`` r_s [m]
    of :func:`spin_friction_torque` (0: no spin friction)."""
    values = [mu_kinetic, mu_static, v0, v1, v_stribeck, stribeck_decay, viscous, sigma0, sigma1, sigma2, spin_radius]
    return np.array(values, dtype=np.float64)
