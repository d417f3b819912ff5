"""Rigid (impulsive-impact) walkers in reduced coordinates: flow, heel-strike guard and impact map.

State convention (README): ``x = (theta_st, theta_sw, thetadot_st, thetadot_sw)`` for the bipeds,
``x = (theta, thetadot)`` for the rimless wheel; leg angles from the slope normal, positive with the
foot downhill of the hip. Between strikes the stance foot rolls without slip and the swing leg swings
freely; the swing foot's mid-stance scuffing is ignored.

The compass and the rimless wheel come from one multibody description (:class:`LegChain`): point
bodies and leg inertias placed on legs that hang from a hip carried by a stance foot arc rolling on the
slope. The rolling contact is a bilateral holonomic constraint (arc centre at height R, x_C + R theta
constant), so the reduced coordinates are the leg angles and every body's position is an explicit
function of them. From that description:

* the flow is Kane's (projected Newton-Euler) equations, ``M(q) qdd = sum_b J_b^T m_b (g - Jdot_b qd)``,
  ``M = sum_b m_b J_b^T J_b + I_b e_b e_b^T``;
* the heel strike is a perfectly plastic impact: the new stance foot becomes the rolling constraint and
  the old one is released, so the generalized momentum of the new coordinates is continuous,
  ``(J'^T M J') qd+ = J'^T M v-`` with ``v- = J qd-`` the bodies' velocities just before. Its physical
  content is the conservation of the whole walker's angular momentum about the new contact point and of
  the trailing leg's about the hip (both checked in the tests).

Garcia's simplest walker (massless legs, a hip mass, infinitesimal foot masses, g = l = 1) is the limit
the chain cannot reach with a regular mass matrix; it uses the equations and heel-strike map of MODEL.md
8 exactly as published.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from biped_sim.config import STATE_KEYS, Config

Guard = Callable[[np.ndarray], float]


@dataclass(frozen=True)
class ChainBody:
    """A body of the chain: mass, inertia about its centre of mass, which leg carries it and where.

    ``leg`` indexes the coordinate vector (0 = stance); ``distance`` is measured from the hip along that
    leg, towards its foot, ``offset`` across it (+ downhill when vertical): at hip + distance axis + offset perp.
    """

    mass: float
    inertia: float
    leg: int
    distance: float
    offset: float = 0.0


def _axis(theta: float) -> np.ndarray:
    """Unit vector from the hip to the foot of a leg at angle theta."""
    return np.array([math.sin(theta), -math.cos(theta)])


def _axis_d(theta: float) -> np.ndarray:
    """Derivative of :func:`_axis` with respect to theta."""
    return np.array([math.cos(theta), math.sin(theta)])


class RigidWalker:
    """Common interface of a rigid walker (the step integrator and the limit-cycle tools use only this).

    Subclasses provide the flow, the strike guard phases, the impact map, the energy and the Poincaré
    section coordinates (the independent post-impact variables).
    """

    name: str = ""
    n_q: int = 2
    state_names: tuple[str, ...] = STATE_KEYS
    section_names: tuple[str, ...] = ()
    gravity: float = 1.0
    leg_length: float = 1.0
    foot_radius: float = 0.0
    foot_offset: float = 0.0
    slope: float = 0.0
    fall_leg_angle: float = 1.4
    reference_mass: float = 1.0

    def rhs(self, x: np.ndarray) -> np.ndarray:
        """Time derivative of the state."""
        raise NotImplementedError

    def guard_phases(self) -> list[tuple[str, Guard]]:
        """Sequence of (name, g(x)) whose downward zero crossings end each phase; the last is the strike."""
        raise NotImplementedError

    def impact(self, x_minus: np.ndarray) -> np.ndarray:
        """Post-impact state (new stance leg first) from the pre-impact state."""
        raise NotImplementedError

    def energy(self, x: np.ndarray) -> tuple[float, float]:
        """Kinetic and potential energy (potential zero with the hip on the ground line)."""
        raise NotImplementedError

    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        """Independent coordinates of a post-impact state."""
        raise NotImplementedError

    def from_section(self, z: np.ndarray) -> np.ndarray:
        """Post-impact state from its section coordinates."""
        raise NotImplementedError

    def begin_step(self) -> None:
        """A step begins (a walker with joint stops unlocks its swing stops)."""

    def skip_phase(self, index: int, x: np.ndarray) -> bool:
        """Whether guard phase ``index`` has nothing to wait for at x (none of the bundled walkers')."""
        return False

    def after_phase(self, index: int, x: np.ndarray) -> np.ndarray:
        """The state after guard phase ``index`` ended (a stop strike's impact; otherwise x)."""
        return x

    def next_stance_angle(self, x_minus: np.ndarray) -> float:
        """Angle of the leg about to touch down, just before the strike."""
        return float(x_minus[1])

    @property
    def landing_index(self) -> int:
        """The coordinate of the leg (its hip body) that touches down at the strike: the last one."""
        return self.n_q - 1

    @property
    def strike_angle_offset(self) -> float:
        """phi = atan2(d, l - R): the hip is above the stance arc centre at theta_st = -phi, and the legs strike
        symmetrically about that direction, theta_sw + phi = -(theta_st + phi)."""
        return math.atan2(self.foot_offset, self.leg_length - self.foot_radius)

    def step_length(self, x_start: np.ndarray, x_minus: np.ndarray) -> float:
        """Advance of the contact point over a step: rolling R dtheta plus the spread of the arc centres (at
        hip + (l - R) axis(theta) + d perp(theta), above the contact points) at the strike."""
        theta_new, theta_old = self.next_stance_angle(x_minus), float(x_minus[0])
        rolled = self.foot_radius * (x_start[0] - x_minus[0])
        spread = (self.leg_length - self.foot_radius) * (math.sin(theta_new) - math.sin(theta_old))
        spread += self.foot_offset * (math.cos(theta_new) - math.cos(theta_old))
        return float(rolled + spread)

    def hip_height(self, x: np.ndarray) -> float:
        """Hip height above the slope line: R + (l - R) cos theta_st - d sin theta_st."""
        l, R, d = self.leg_length, self.foot_radius, self.foot_offset
        return R + (l - R) * math.cos(x[0]) - d * math.sin(x[0])

    def legs_state(self, x: np.ndarray) -> dict[str, float]:
        """The README's four InitialState keys for a state."""
        return {name: float(x[i]) for i, name in enumerate(self.state_names)}

    def state_from_legs(self, legs: dict[str, float]) -> np.ndarray:
        """Inverse of :meth:`legs_state`."""
        return np.array([legs[name] for name in self.state_names], dtype=float)

    def fallen(self, x: np.ndarray) -> bool:
        """A leg past the fall angle (the stance leg only, for the wheel)."""
        return bool(np.any(np.abs(x[: self.n_q]) >= self.fall_leg_angle))


class LegChain(RigidWalker):
    """Legs hinged at one hip, the stance foot an arc of radius R rolling on the slope (compass, wheel); the arc
    centre at l - R along the leg and d = ``foot_offset`` across it, C = (-R theta_st, R): hip = C - (l - R)
    axis(theta_st) - d perp(theta_st)."""

    def __init__(
        self,
        bodies: list[ChainBody],
        n_q: int,
        leg_length: float,
        foot_radius: float,
        gravity: float,
        slope: float,
        foot_offset: float = 0.0,
    ) -> None:
        self.bodies = bodies
        self.n_q = n_q
        self.leg_length = leg_length
        self.foot_radius = foot_radius
        self.foot_offset = foot_offset
        self.gravity = gravity
        self.slope = slope
        self.gravity_vector = gravity * np.array([math.sin(slope), -math.cos(slope)])
        self.reference_mass = sum(b.mass for b in bodies)

    # --- kinematics of the description -------------------------------------------------------------------
    def _hip(self, theta_st: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Hip position (contact-point origin at x = 0 for theta_st = 0), its theta_st derivative and second."""
        l, R, d = self.leg_length, self.foot_radius, self.foot_offset
        axis, perp = _axis(theta_st), _axis_d(theta_st)
        position = np.array([-R * theta_st, R]) - (l - R) * axis - d * perp
        first = np.array([-R, 0.0]) - (l - R) * perp + d * axis
        second = (l - R) * axis + d * perp
        return position, first, second

    def body_kinematics(self, q: np.ndarray, qd: np.ndarray) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per body: position (2,), Jacobian (2, n_q), bias acceleration Jdot qd (2,)."""
        hip, hip_d, hip_dd = self._hip(q[0])
        out = []
        for body in self.bodies:
            axis, perp = _axis(q[body.leg]), _axis_d(q[body.leg])
            r, r_d = body.distance * axis + body.offset * perp, body.distance * perp - body.offset * axis  # r'' = -r
            jac = np.zeros((2, self.n_q))
            jac[:, 0] = hip_d
            jac[:, body.leg] += r_d
            bias = hip_dd * qd[0] ** 2 - r * qd[body.leg] ** 2
            out.append((hip + r, jac, bias))
        return out

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """Generalized mass matrix M(q) = sum m J^T J + I e e^T."""
        mass = np.zeros((self.n_q, self.n_q))
        for body, (_, jac, _) in zip(self.bodies, self.body_kinematics(q, np.zeros(self.n_q)), strict=True):
            mass += body.mass * jac.T @ jac
            mass[body.leg, body.leg] += body.inertia
        return mass

    def body_velocities(self, q: np.ndarray, qd: np.ndarray) -> list[tuple[np.ndarray, float]]:
        """Per body: linear velocity and angular velocity."""
        return [
            (jac @ qd, float(qd[body.leg]))
            for body, (_, jac, _) in zip(self.bodies, self.body_kinematics(q, qd), strict=True)
        ]

    # --- dynamics ------------------------------------------------------------------------------------------
    def rhs(self, x: np.ndarray) -> np.ndarray:
        n = self.n_q
        q, qd = x[:n], x[n:]
        mass = np.zeros((n, n))
        force = np.zeros(n)
        for body, (_, jac, bias) in zip(self.bodies, self.body_kinematics(q, qd), strict=True):
            mass += body.mass * jac.T @ jac
            mass[body.leg, body.leg] += body.inertia
            force += body.mass * jac.T @ (self.gravity_vector - bias)
        return np.concatenate([qd, np.linalg.solve(mass, force)])

    def energy(self, x: np.ndarray) -> tuple[float, float]:
        n = self.n_q
        q, qd = x[:n], x[n:]
        kinetic = 0.5 * qd @ self.mass_matrix(q) @ qd
        potential = -sum(
            body.mass * self.gravity_vector @ position
            for body, (position, _, _) in zip(self.bodies, self.body_kinematics(q, qd), strict=True)
        )
        return float(kinetic), float(potential)

    def relabel(self, q_minus: np.ndarray) -> tuple[np.ndarray, list[ChainBody]]:
        """Coordinates and body description after the strike (the new stance leg is coordinate 0)."""
        raise NotImplementedError

    def impact(self, x_minus: np.ndarray) -> np.ndarray:
        n = self.n_q
        q, qd = x_minus[:n], x_minus[n:]
        velocities = self.body_velocities(q, qd)
        q_new, bodies_new = self.relabel(q)
        after = LegChain(bodies_new, n, self.leg_length, self.foot_radius, self.gravity, self.slope, self.foot_offset)
        kin = after.body_kinematics(q_new, np.zeros(n))
        lhs = np.zeros((n, n))
        rhs = np.zeros(n)
        for body, (_, jac, _), (v, omega) in zip(bodies_new, kin, velocities, strict=True):
            lhs += body.mass * jac.T @ jac
            lhs[body.leg, body.leg] += body.inertia
            rhs += body.mass * jac.T @ v
            rhs[body.leg] += body.inertia * omega
        return np.concatenate([q_new, np.linalg.solve(lhs, rhs)])

    def angular_momentum(self, x: np.ndarray, point: np.ndarray, bodies: list[int] | None = None) -> float:
        """Angular momentum (z) of the chosen bodies (default all) about a fixed point of the slope frame."""
        n = self.n_q
        q, qd = x[:n], x[n:]
        kin = self.body_kinematics(q, qd)
        total = 0.0
        for index, (body, (position, jac, _)) in enumerate(zip(self.bodies, kin, strict=True)):
            if bodies is not None and index not in bodies:
                continue
            r = position - point
            v = jac @ qd
            total += body.mass * (r[0] * v[1] - r[1] * v[0]) + body.inertia * qd[body.leg]
        return total

    def contact_point(self, q: np.ndarray) -> np.ndarray:
        """Stance contact point in the frame of :meth:`body_kinematics`."""
        return np.array([-self.foot_radius * q[0], 0.0])


class CompassChain(LegChain):
    """Compass walker: two legs (mass m at c along and w across the leg, inertia I), a hip mass M_H, feet offset d.

    The swing foot's clearance, (l - R)(cos theta_st - cos theta_sw) + d (sin theta_sw - sin theta_st) =
    2 hypot(l - R, d) sin((theta_st + theta_sw + 2 phi) / 2) sin((theta_sw - theta_st) / 2), vanishes at the
    mid-stance crossing (scuffing, ignored) and at the strike: the guard is theta_st + theta_sw + 2 phi."""

    name = "compass"
    section_names = ("stance_angle", "stance_rate", "swing_rate")

    def __init__(self, config: Config) -> None:
        w = config.walker
        bodies = [
            ChainBody(w.leg_mass, w.leg_inertia, 0, w.leg_com_from_hip, w.leg_com_offset),
            ChainBody(w.leg_mass, w.leg_inertia, 1, w.leg_com_from_hip, w.leg_com_offset),
            ChainBody(w.hip_mass, 0.0, 0, 0.0),
        ]
        super().__init__(bodies, 2, w.leg_length, w.foot_radius, config.gravity, config.ground.slope, w.foot_offset)
        self.fall_leg_angle = config.simulation.fall_leg_angle

    def guard_phases(self) -> list[tuple[str, Guard]]:
        # the strike is sought once the hip has passed over the stance arc centre: earlier crossings are scuffing
        phi = self.strike_angle_offset
        if phi == 0.0:  # the d = 0 guards exactly as they always were (golden results are bit-for-bit)
            return [("stance_past_normal", lambda x: x[0]), ("heel_strike", lambda x: x[0] + x[1])]
        return [("stance_past_normal", lambda x: x[0] + phi), ("heel_strike", lambda x: x[0] + x[1] + 2.0 * phi)]

    def relabel(self, q_minus: np.ndarray) -> tuple[np.ndarray, list[ChainBody]]:
        swapped = [ChainBody(b.mass, b.inertia, 1 - b.leg, b.distance, b.offset) for b in self.bodies[:2]]
        return np.array([q_minus[1], q_minus[0]]), [*swapped, self.bodies[2]]

    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        return np.array([x_plus[0], x_plus[2], x_plus[3]])

    def from_section(self, z: np.ndarray) -> np.ndarray:
        # just after a strike the legs are symmetric about -phi: theta_sw = -theta_st - 2 phi
        return np.array([z[0], -z[0] - 2.0 * self.strike_angle_offset, z[1], z[2]])


class RimlessWheel(LegChain):
    """Rimless wheel: N massless spokes of length l, a point mass at the hub (MODEL.md 8)."""

    name = "rimless_wheel"
    state_names = ("stance_angle", "stance_rate")
    section_names = ("stance_rate",)

    def __init__(self, config: Config) -> None:
        w = config.walker
        super().__init__([ChainBody(1.0, 0.0, 0, 0.0)], 1, w.leg_length, 0.0, config.gravity, config.ground.slope)
        self.spokes = w.spokes
        self.half_angle = math.pi / w.spokes
        self.fall_leg_angle = config.simulation.fall_leg_angle

    def guard_phases(self) -> list[tuple[str, Guard]]:
        return [("heel_strike", lambda x: x[0] + self.half_angle)]

    def relabel(self, q_minus: np.ndarray) -> tuple[np.ndarray, list[ChainBody]]:
        return np.array([q_minus[0] + 2.0 * self.half_angle]), self.bodies

    def next_stance_angle(self, x_minus: np.ndarray) -> float:
        return float(x_minus[0] + 2.0 * self.half_angle)

    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        return np.array([x_plus[1]])

    def from_section(self, z: np.ndarray) -> np.ndarray:
        return np.array([self.half_angle, z[0]])

    def legs_state(self, x: np.ndarray) -> dict[str, float]:
        """Stance spoke, and as 'swing' the spoke just behind it (the one that last left the ground)."""
        return {
            "stance_angle": float(x[0]),
            "stance_rate": float(x[1]),
            "swing_angle": float(x[0] - 2.0 * self.half_angle),
            "swing_rate": float(x[1]),
        }

    def state_from_legs(self, legs: dict[str, float]) -> np.ndarray:
        return np.array([legs["stance_angle"], legs["stance_rate"]])


class SimplestWalker(RigidWalker):
    """Garcia et al. 1998: point hip mass, massless legs, point feet; g = l = 1 (MODEL.md 8).

    Garcia's variables are theta (stance angle, the README's) and phi = theta_st - theta_sw (swing leg
    from the stance leg), so theta_sw = theta - phi.
    """

    name = "simplest"
    section_names = ("stance_angle", "stance_rate")

    def __init__(self, config: Config) -> None:
        self.slope = config.ground.slope
        self.gravity = 1.0
        self.leg_length = 1.0
        self.foot_radius = 0.0
        self.fall_leg_angle = config.simulation.fall_leg_angle

    def rhs(self, x: np.ndarray) -> np.ndarray:
        theta, theta_sw, theta_d, theta_sw_d = x
        phi = theta - theta_sw
        theta_dd = math.sin(theta - self.slope)
        phi_dd = theta_dd + math.sin(phi) * (theta_d**2 - math.cos(theta - self.slope))
        return np.array([theta_d, theta_sw_d, theta_dd, theta_dd - phi_dd])

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """d(rhs)/dx, for the variational equations (an independent route to the multipliers)."""
        theta, theta_sw, theta_d, _ = x
        phi = theta - theta_sw
        s, c = math.sin(theta - self.slope), math.cos(theta - self.slope)
        # theta_sw_dd = -sin(phi) (theta_d^2 - cos(theta - gamma))
        bracket = theta_d**2 - c
        d_phi = -math.cos(phi) * bracket
        jac = np.zeros((4, 4))
        jac[0, 2] = 1.0
        jac[1, 3] = 1.0
        jac[2, 0] = c
        jac[3, 0] = d_phi - math.sin(phi) * s
        jac[3, 1] = -d_phi
        jac[3, 2] = -2.0 * math.sin(phi) * theta_d
        return jac

    def guard_phases(self) -> list[tuple[str, Guard]]:
        return [("stance_past_normal", lambda x: x[0]), ("heel_strike", lambda x: x[0] + x[1])]

    def impact(self, x_minus: np.ndarray) -> np.ndarray:
        theta, _, theta_d, _ = x_minus
        c2 = math.cos(2.0 * theta)
        # MODEL.md 8: theta+ = -theta-, thetadot+ = cos(2 theta) thetadot-, phi+ = -2 theta-,
        # phidot+ = cos(2 theta)(1 - cos(2 theta)) thetadot-; theta_sw = theta - phi
        theta_p = -theta
        theta_d_p = c2 * theta_d
        phi_p = -2.0 * theta
        phi_d_p = c2 * (1.0 - c2) * theta_d
        return np.array([theta_p, theta_p - phi_p, theta_d_p, theta_d_p - phi_d_p])

    def impact_jacobian(self, x_minus: np.ndarray) -> np.ndarray:
        """d(impact)/dx_minus."""
        theta, _, theta_d, _ = x_minus
        c2, s2 = math.cos(2.0 * theta), math.sin(2.0 * theta)
        jac = np.zeros((4, 4))
        jac[0, 0] = -1.0
        jac[1, 0] = 1.0
        jac[2, 0] = -2.0 * s2 * theta_d
        jac[2, 2] = c2
        # theta_sw_d+ = c2^2 theta_d
        jac[3, 0] = -4.0 * c2 * s2 * theta_d
        jac[3, 2] = c2**2
        return jac

    def energy(self, x: np.ndarray) -> tuple[float, float]:
        """Hip mass only (the foot masses are infinitesimal): stance-leg pendulum energy."""
        theta, _, theta_d, _ = x
        return 0.5 * theta_d**2, math.cos(theta - self.slope)

    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        return np.array([x_plus[0], x_plus[2]])

    def from_section(self, z: np.ndarray) -> np.ndarray:
        theta, theta_d = z
        c2 = math.cos(2.0 * theta)
        return np.array([theta, -theta, theta_d, c2 * theta_d])
