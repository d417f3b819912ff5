"""Garcia et al. 1998's published equations of the simplest walker (MODEL.md 8) and its step map's Jacobian from
their variational equations: the independent route that the validation checks the rigid tree's massless-leg limit
(:mod:`biped_sim.rigid.tree_kernels`) and its finite-difference multipliers against.

Garcia's variables are theta (the stance angle) and phi = theta - theta_sw; the state here is the rigid walker's,
(theta, theta_sw, thetadot, thetadot_sw), with g = l = 1 and slope gamma.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import StepFailedError
from biped_sim.rigid.tree import RigidWalker


def garcia_rhs(slope: float, x: np.ndarray) -> np.ndarray:
    """thetadd = sin(theta - gamma), phidd = thetadd + sin(phi) (thetadot^2 - cos(theta - gamma))."""
    theta, theta_sw, theta_d, theta_sw_d = x
    phi = theta - theta_sw
    theta_dd = math.sin(theta - slope)
    phi_dd = theta_dd + math.sin(phi) * (theta_d**2 - math.cos(theta - slope))
    return np.array([theta_d, theta_sw_d, theta_dd, theta_dd - phi_dd])


def garcia_jacobian(slope: float, x: np.ndarray) -> np.ndarray:
    """d(garcia_rhs)/dx."""
    theta, theta_sw, theta_d, _ = x
    phi = theta - theta_sw
    s, c = math.sin(theta - slope), math.cos(theta - slope)
    d_phi = -math.cos(phi) * (theta_d**2 - c)  # theta_sw_dd = -sin(phi) (theta_d^2 - cos(theta - gamma))
    jac = np.zeros((4, 4))
    jac[0, 2] = jac[1, 3] = 1.0
    jac[2, 0] = c
    jac[3, 0] = d_phi - math.sin(phi) * s
    jac[3, 1] = -d_phi
    jac[3, 2] = -2.0 * math.sin(phi) * theta_d
    return jac


def garcia_impact_jacobian(x_minus: np.ndarray) -> np.ndarray:
    """d(impact)/dx- of theta+ = -theta-, thetadot+ = cos(2 theta) thetadot-, phi+ = -2 theta-, phidot+ =
    cos(2 theta) (1 - cos(2 theta)) thetadot- (so theta_sw+ = theta-, thetadot_sw+ = cos^2(2 theta) thetadot-)."""
    theta, _, theta_d, _ = x_minus
    c2, s2 = math.cos(2.0 * theta), math.sin(2.0 * theta)
    jac = np.zeros((4, 4))
    jac[0, 0] = -1.0
    jac[1, 0] = 1.0
    jac[2, 0] = -2.0 * s2 * theta_d
    jac[2, 2] = c2
    jac[3, 0] = -4.0 * c2 * s2 * theta_d
    jac[3, 2] = c2**2
    return jac


def simplest_variational_jacobian(walker: RigidWalker, z: np.ndarray) -> np.ndarray:
    """Step-map Jacobian of the simplest walker in section coordinates (theta, thetadot) from Garcia's variational
    equations (not finite differences): Phi' = Df(x) Phi along the flow for the step's duration, the saltation
    through the strike guard g = theta_st + theta_sw (the event time moves with the state), then the impact's."""
    from scipy.integrate import solve_ivp  # here: scipy.integrate adds 0.3 s to start-up

    x0 = walker.from_section(z)
    step = rigid_step(walker, x0)
    if step.status != "strike":
        raise StepFailedError(f"the simplest walker {step.status}")
    slope = walker.slope

    def augmented(_t: float, y: np.ndarray) -> np.ndarray:
        x, phi = y[:4], y[4:].reshape(4, 4)
        return np.concatenate([garcia_rhs(slope, x), (garcia_jacobian(slope, x) @ phi).ravel()])

    y0 = np.concatenate([x0, np.eye(4).ravel()])
    sol = solve_ivp(augmented, (0.0, step.period), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    x_minus, phi = sol.y[:4, -1], sol.y[4:, -1].reshape(4, 4)
    f = garcia_rhs(slope, x_minus)
    grad = np.array([1.0, 1.0, 0.0, 0.0])
    saltation = np.eye(4) - np.outer(f, grad) / (grad @ f)
    full = garcia_impact_jacobian(x_minus) @ saltation @ phi
    theta, theta_d = z  # d(from_section)/dz: theta_sw = -theta, thetadot_sw = cos(2 theta) thetadot
    lift = np.array(
        [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [-2.0 * math.sin(2.0 * theta) * theta_d, math.cos(2.0 * theta)]]
    )
    return full[[0, 2]] @ lift
