"""A deliberately slow, plain-Python reference right-hand side of the planar formulation.

It exists for two reasons: tests assert that the compiled right-hand side agrees with it to
round-off on random states, and the benchmark uses it as the "what most Python code does"
baseline under ``scipy.integrate.solve_ivp``. It is written differently on purpose: it builds
the full augmented (KKT) matrix with numpy and solves it with ``numpy.linalg.solve``, instead of
the compiled Schur-complement Cholesky solve. The force laws are the same functions, run as
plain Python (``.py_func``), so each equation still has one source.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from biped_sim.contact import friction as friction_laws
from biped_sim.contact import normal as normal_laws
from biped_sim.contact.response import ARMED, FRICTION_MODEL, IMPACT_FLOOR, IMPACT_SPEED, NORMAL_MODEL, TOUCHING
from biped_sim.multibody.planar import PlanarSystem


def _rotation(phi: float) -> np.ndarray:
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


def _normal_law(model: int) -> Callable[..., float]:
    for law in normal_laws.NORMAL_LAWS.values():
        if law.index == model:
            return law.function.py_func
    raise KeyError(model)


def _friction_law(model: int) -> Callable[..., float]:
    for law in friction_laws.FRICTION_LAWS.values():
        if law.index == model:
            return law.function.py_func
    raise KeyError(model)


def reference_rhs(t: float, y: np.ndarray, system: PlanarSystem, modes: np.ndarray) -> np.ndarray:
    """ydot for the planar system (same contract as the compiled ``rhs``), computed plainly."""
    nb = len(system.body_mass)
    n = 3 * nb
    nf = len(system.foot_body)
    q, qd = y[:n].reshape(nb, 3), y[n : 2 * n].reshape(nb, 3)
    ydot = np.zeros_like(y)
    ydot[:n] = y[n : 2 * n]
    mass = np.zeros((n, n))
    force = np.zeros(n)
    for b in range(nb):
        mass[3 * b, 3 * b] = mass[3 * b + 1, 3 * b + 1] = system.body_mass[b]
        mass[3 * b + 2, 3 * b + 2] = system.body_inertia[b]
        force[3 * b : 3 * b + 2] = system.body_mass[b] * system.gravity
    normal_law = _normal_law(int(system.switches[NORMAL_MODEL]))
    friction_model = int(system.switches[FRICTION_MODEL])
    powers = np.zeros(2)
    for i in range(nf):
        b = system.foot_body[i]
        r, phi = q[b, :2], q[b, 2]
        v, omega = qd[b, :2], qd[b, 2]
        centre = r + _rotation(phi) @ system.foot_center[i]
        contact = centre - np.array([0.0, system.foot_radius[i]])
        arm = contact - r
        v_contact = v + omega * np.array([-arm[1], arm[0]])
        delta, delta_dot, slip = -contact[1], -v_contact[1], v_contact[0]
        if modes[i, ARMED] <= 0.5 or delta <= 0.0:
            continue
        impact = modes[i, IMPACT_SPEED] if modes[i, TOUCHING] > 0.5 else delta_dot
        impact = max(impact, system.limits[IMPACT_FLOOR])
        f_n = max(normal_law(delta, delta_dot, impact, system.normal_params), 0.0)
        elastic = system.normal_params[normal_laws.K] * delta ** system.normal_params[normal_laws.N]
        powers[0] += (f_n - elastic) * delta_dot
        fp = system.friction_params
        if friction_model == friction_laws.LUGRE:
            z = y[2 * n + i]
            z_dot = friction_laws.lugre_bristle_rate.py_func(slip, z, fp)
            f_t = friction_laws.lugre_friction.py_func(slip, z, z_dot, f_n, fp)
            ydot[2 * n + i] = z_dot
            powers[1] += -f_t * slip
        else:
            f_t = _friction_law(friction_model)(slip, f_n, fp)
            powers[1] += -f_t * slip
        force[3 * b : 3 * b + 2] += [f_t, f_n]
        force[3 * b + 2] += arm[0] * f_n - arm[1] * f_t
    ydot[2 * n + nf : 2 * n + nf + 2] = powers

    nj = len(system.joint_bodies)
    m = 2 * nj
    jacobian = np.zeros((m, n))
    gamma = np.zeros(m)
    alpha, beta = system.baumgarte
    for j in range(nj):
        rows = slice(2 * j, 2 * j + 2)
        residual = np.zeros(2)
        residual_rate = np.zeros(2)
        for side, sign in ((0, 1.0), (1, -1.0)):
            b = system.joint_bodies[j, side]
            s_local = system.joint_points[j, 2 * side : 2 * side + 2]
            if b < 0:
                residual += sign * s_local
                continue
            a_s = _rotation(q[b, 2]) @ s_local
            b_s = np.array([-a_s[1], a_s[0]])  # d(A s)/dphi
            jacobian[rows, 3 * b : 3 * b + 2] = sign * np.eye(2)
            jacobian[rows, 3 * b + 2] = sign * b_s
            residual += sign * (q[b, :2] + a_s)
            residual_rate += sign * (qd[b, :2] + qd[b, 2] * b_s)
            gamma[rows] += sign * qd[b, 2] ** 2 * a_s
        gamma[rows] += -2.0 * alpha * residual_rate - beta**2 * residual
    kkt = np.zeros((n + m, n + m))
    kkt[:n, :n] = mass
    kkt[:n, n:] = jacobian.T
    kkt[n:, :n] = jacobian
    solution = np.linalg.solve(kkt, np.concatenate([force, gamma]))
    ydot[n : 2 * n] = solution[:n]
    return ydot
