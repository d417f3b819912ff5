"""Whether the compass's plastic heel strike (leading foot stuck, trailing foot released) is the limit of stiff contact.

The rigid impact map (:meth:`LegChain.impact`) kills the leading foot's velocity with whatever impulse that takes
and releases the trailing foot unconditionally. A compliant strike with Coulomb-bounded friction tends to it as
the contact stiffens only if

* the released trailing foot leaves the ground (its normal velocity after the impact > 0);
* the leading foot can stick: the impact's tangential-to-normal impulse ratio is within mu_s;
* while the leading foot slides at touchdown its friction, -mu_k sgn(v_t) per unit of normal impulse, does not
  push the trailing foot into the ground. The feet couple through the walker's inverse inertia W = J_T M^-1 J_L^T
  (M of the free walker: hip position and both leg angles); a slipping leading foot changes the trailing foot's
  normal velocity at the rate W_nn - mu_k sgn(v_t) W_nt per unit of leading normal impulse. When that is negative
  the trailing foot is compressed during the strike (a double-support impact the rigid map does not model):
  measured on the default walker with d = 5 mm, landing at v_t = -0.25 m/s, its load rises from 33 to 51 N
  and the compliant gait's touchdown difference levels off near 6e-4 rad instead of converging.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.rigid.models import CompassChain, LegChain


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


def _free_mass_matrix(walker: LegChain, q: np.ndarray) -> np.ndarray:
    """Mass matrix of the walker lifted off the ground: coordinates (hip x, hip y, leg angles)."""
    n = 2 + walker.n_q
    mass = np.zeros((n, n))
    for body in walker.bodies:
        theta = q[body.leg]
        jac = np.zeros((2, n))
        jac[:, :2] = np.eye(2)
        jac[:, 2 + body.leg] = body.distance * np.array([math.cos(theta), math.sin(theta)]) - body.offset * np.array(
            [math.sin(theta), -math.cos(theta)]
        )
        mass += body.mass * jac.T @ jac
        mass[2 + body.leg, 2 + body.leg] += body.inertia
    return mass


def _foot_jacobian(walker: LegChain, q: np.ndarray, leg: int) -> np.ndarray:
    """Velocity of the material point of a leg's foot arc at its bottom (the contact point), free coordinates."""
    arm, d, theta = walker.leg_length - walker.foot_radius, walker.foot_offset, q[leg]
    jac = np.zeros((2, 2 + walker.n_q))
    jac[:, :2] = np.eye(2)
    jac[:, 2 + leg] = arm * np.array([math.cos(theta), math.sin(theta)]) - d * np.array(
        [math.sin(theta), -math.cos(theta)]
    )
    jac[0, 2 + leg] += walker.foot_radius  # the arc turning about its centre R above the point
    return jac


def strike_check(walker: CompassChain, x_minus: np.ndarray, mu_kinetic: float) -> StrikeCheck:
    """The release quantities of the compass's strike from its pre-impact state (stance leg 0, leading leg 1)."""
    q, qd = x_minus[:2], x_minus[2:]
    hip_velocity = walker.body_kinematics(q, qd)[-1][1] @ qd  # the last body is the hip mass, at the hip
    u = np.concatenate([hip_velocity, qd])
    mass = _free_mass_matrix(walker, q)
    trailing, leading = _foot_jacobian(walker, q, 0), _foot_jacobian(walker, q, 1)
    coupling = trailing @ np.linalg.solve(mass, leading.T)  # W_TL: trailing velocity per leading impulse
    leading_velocity = leading @ u
    impulse = -np.linalg.solve(leading @ np.linalg.solve(mass, leading.T), leading_velocity)  # leading foot stuck
    slip = float(leading_velocity[0])
    return StrikeCheck(
        trailing_release_speed=float((trailing @ u + coupling @ impulse)[1]),
        leading_slip_speed=slip,
        trailing_push_rate=float(coupling[1, 1] - mu_kinetic * np.sign(slip) * coupling[1, 0]),
        friction_ratio=float(abs(impulse[0]) / impulse[1]),
    )
