"""Whether the compass's plastic heel strike (leading foot stuck, trailing foot released) is the limit of stiff contact.

The rigid impact map (:meth:`RigidWalker.impact`) kills the leading foot's velocity with whatever impulse that takes
and releases the trailing foot unconditionally. A compliant strike with Coulomb-bounded friction tends to it as
the contact stiffens only if

* the released trailing foot leaves the ground (its normal velocity after the impact > 0);
* the leading foot can stick: the impact's tangential-to-normal impulse ratio is within mu_s;
* while the leading foot slides at touchdown its friction, -mu_k sgn(v_t) per unit of normal impulse, does not
  push the trailing foot into the ground. The feet couple through the walker's inverse inertia W = J_T M^-1 J_L^T
  (M of the free walker: hip position and its angles, every stop locked); a slipping leading foot changes the
  trailing foot's normal velocity at the rate W_nn - mu_k sgn(v_t) W_nt per unit of leading normal impulse. When
  that is negative the trailing foot is compressed during the strike (a double-support impact the rigid map does
  not model): measured on the default walker with d = 5 mm, landing at v_t = -0.25 m/s, its load rises from 33 to
  51 N and the compliant gait's touchdown difference levels off near 6e-4 rad instead of converging.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.rigid.tree import RigidWalker
from biped_sim.rigid.tree_layout import RigidTree, point_velocity


@dataclass(frozen=True)
class StrikeCheck:
    """The rigid strike's release quantities (feet: contact points; + x downhill, + normal away from the ground)."""

    trailing_release_speed: float  # trailing foot's normal velocity just after the impact [m/s]
    leading_slip_speed: float  # leading foot's tangential velocity at touchdown [m/s]
    trailing_push_rate: float  # d(trailing normal velocity)/d(leading normal impulse) while it slides [1/kg]
    friction_ratio: float  # |tangential| / normal impulse on the leading foot in the impact

    def violations(self, mu_static: float) -> list[str]:
        """One line per violated condition of the module docstring (empty: the rigid strike is the limit)."""
        out = []
        if self.trailing_release_speed <= 0.0:
            out.append(f"the trailing foot does not leave the ground ({self.trailing_release_speed:+.3e} m/s)")
        if self.friction_ratio > mu_static:
            out.append(f"the leading foot cannot stick (impulse ratio {self.friction_ratio:.3f} > mu_s {mu_static})")
        if self.trailing_push_rate < 0.0:
            out.append(
                f"the leading foot lands slipping ({self.leading_slip_speed:+.3e} m/s) and its friction pushes the"
                f" trailing foot into the ground ({self.trailing_push_rate:+.3e} m/s per N s)"
            )
        return out


def _free_jacobian(p: RigidTree, point: int | None, q: np.ndarray) -> np.ndarray:
    """Velocity Jacobian of a point of the walker lifted off the ground, coordinates (hip x, hip y, angles): the
    w vectors of table 0's ``point`` (None: the stance foot's centre, w = 0) taken from the hip's."""
    n = len(q)
    hip = p.w[0, p.n_points]
    jac = np.zeros((2, 2 + n))
    jac[:, :2] = np.eye(2)
    for k in range(n):
        wx = (p.w[0, point, k, 0] if point is not None else 0.0) - hip[k, 0]
        wy = (p.w[0, point, k, 1] if point is not None else 0.0) - hip[k, 1]
        s, c = math.sin(q[k]), math.cos(q[k])
        jac[:, 2 + k] = (-s * wx - c * wy, c * wx - s * wy)
    return jac


def _free_inverse_inertia(walker: RigidWalker, q: np.ndarray) -> np.ndarray:
    """M^-1 of the lifted walker with every stop locked (the legs rigid through the strike): the constrained
    inverse M^-1 - M^-1 A^T (A M^-1 A^T)^-1 A M^-1, A the locks' rows."""
    p, n = walker.params, walker.n_q
    mass = np.zeros((2 + n, 2 + n))
    for i in range(walker.n_points):
        row = p.rows[0, i]
        jac = _free_jacobian(p, i, q)
        mass += row["mass"] * jac.T @ jac
        mass[2 + row["own"], 2 + row["own"]] += row["inertia"]
    inverse = np.linalg.inv(mass)
    locks = np.zeros((len(p.locks), 2 + n))
    for j, lock in enumerate(p.locks):
        locks[j, 2 + lock["parent"]], locks[j, 2 + lock["child"]] = -1.0, 1.0
    if len(locks):
        projected = inverse @ locks.T
        inverse -= projected @ np.linalg.solve(locks @ projected, projected.T)
    return inverse


def _contact_jacobian(walker: RigidWalker, q: np.ndarray, landing: bool) -> np.ndarray:
    """Velocity of the material point at the bottom of the stance (or landing) foot's arc, free coordinates."""
    p = walker.params
    jac = _free_jacobian(p, walker.n_points + 1 if landing else None, q)
    foot_body = p.rolling[1 if landing else 0]
    radius = p.landing_radius if landing else walker.foot_radius
    jac[0, 2 + foot_body] += radius  # the arc turning about its centre R above the point
    return jac


def strike_check(walker: RigidWalker, x_minus: np.ndarray, mu_kinetic: float) -> StrikeCheck:
    """The release quantities of a two-legged walker's heel strike from its pre-impact state (its stance foot
    trailing, its swing foot leading)."""
    n = walker.n_q
    q, qd = x_minus[:n], x_minus[n:]
    hip_velocity = point_velocity(walker.params, 0, walker.n_points, q, qd)
    u = np.concatenate([hip_velocity, qd])
    inverse = _free_inverse_inertia(walker, q)
    trailing, leading = _contact_jacobian(walker, q, False), _contact_jacobian(walker, q, True)
    coupling = trailing @ inverse @ leading.T  # W_TL: trailing velocity per leading impulse
    leading_velocity = leading @ u
    impulse = -np.linalg.solve(leading @ inverse @ leading.T, leading_velocity)  # leading foot stuck
    slip = float(leading_velocity[0])
    return StrikeCheck(
        trailing_release_speed=float((trailing @ u + coupling @ impulse)[1]),
        leading_slip_speed=slip,
        trailing_push_rate=float(coupling[1, 1] - mu_kinetic * np.sign(slip) * coupling[1, 0]),
        friction_ratio=float(abs(impulse[0]) / impulse[1]),
    )
