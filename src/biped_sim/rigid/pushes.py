"""A push on a rigid walker: an impulse p = [px, py] on the hip (slope frame: x downhill, y along the normal).

The reduced coordinates hold the stance foot's rolling constraint and the hip joint exactly, so the impulsive
equations are those of the reduced model: M(q) dqd = J_hip(q)^T p (the constraint impulses do no virtual work
on the reduced velocities). The angles do not move; the rates jump. The contact keeps the model's assumption:
the stance foot stays on the ground, a bilateral constraint, as between strikes (the rigid flow does not
check the sign of the normal force either). The ground's normal impulse, the walker's momentum change
minus p, is returned so that a caller can see when a push would really have lifted the foot (negative):
such a push is applied all the same and noted, the rigid model cannot say what happens next.

Models:

* compass and rimless wheel (:class:`~biped_sim.rigid.models.LegChain`): J_hip = d(hip)/dq, the stance angle's
  column only (the hip rides on the stance leg); the wheel's energies and impulses are per kg of hub mass.
* Garcia's simplest walker (g = l = hip mass = 1; an impulse in units of M sqrt(g l)): the hip mass alone
  gives dthetadot = J^T p with J = -(cos theta, sin theta) (the hip at (-sin theta, cos theta) from the
  stance foot). The massless swing leg carries only an axial impulse to its infinitesimal foot mass, whose
  velocity across the leg therefore stays: dthetadot_sw = -dv_hip . (cos theta_sw, sin theta_sw)
  = dthetadot cos(theta - theta_sw) (the same foot-mass balance that gives Garcia's swing equation).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.rigid.models import LegChain, RigidWalker, SimplestWalker
from biped_sim.rigid.tree import TreeWalker


def hip_push(walker: RigidWalker, x: np.ndarray, impulse: np.ndarray) -> tuple[np.ndarray, float]:
    """(state just after the impulse on the hip, the ground's normal impulse on the stance foot)."""
    px, py = float(impulse[0]), float(impulse[1])
    if isinstance(walker, SimplestWalker):
        theta, theta_sw, theta_d, theta_sw_d = x
        d_theta = -(math.cos(theta) * px + math.sin(theta) * py)
        ground_normal = -math.sin(theta) * d_theta - py  # the hip mass's momentum change minus p, normal part
        after = np.array([theta, theta_sw, theta_d + d_theta, theta_sw_d + d_theta * math.cos(theta - theta_sw)])
        return after, ground_normal
    if isinstance(walker, TreeWalker):
        return walker.hip_push(x, impulse)
    if not isinstance(walker, LegChain):
        raise TypeError(f"no push model for the rigid {walker.name} walker")
    n = walker.n_q
    q, qd = x[:n], x[n:]
    jac = np.zeros((2, n))
    jac[:, 0] = walker._hip(q[0])[1]  # the hip's Jacobian: it moves with the stance angle only
    d_qd = np.linalg.solve(walker.mass_matrix(q), jac.T @ np.array([px, py]))
    momentum_change = np.zeros(2)
    for body, (_, body_jac, _) in zip(walker.bodies, walker.body_kinematics(q, qd), strict=True):
        momentum_change += body.mass * body_jac @ d_qd
    return np.concatenate([q, qd + d_qd]), float(momentum_change[1] - py)
