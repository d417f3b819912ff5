"""A walker's rigid model: its description's tree laid out for the compiled kernels of :mod:`.tree_kernels`.

Every rigid walker is one of these, built from its description (:func:`biped_sim.walkers.describe.describe`: the
compass, Garcia's simplest walker, the rimless wheel, or a walker written as YAML). Two kinds of tree walk:

* two alike legs (a leg: the bodies from the hip down), one foot on each, an arc or a point: the phases follow
  from the description: the swing leg's stops strike one after another (the kneed walker: its unlocked three-link
  swing ends at the knee strike), then the hip passes over the stance foot, then the heel strikes with every stop
  of both legs locked through it (but those ``release_at_heel_strike`` lets go on the trailing leg: McGeer's free
  trailing knee, whose rates join the section), and the new swing leg's stops unlock at once. The stance leg's
  stops stay locked (a straight stance leg, as Chen 2007 and McGeer 1990 model it);
* one body with N >= 2 point feet evenly spaced about its origin (the rimless wheel): the next spoke strikes.

Massless legs (Garcia's simplest walker) are the limit of infinitesimal foot masses (:mod:`.tree_kernels`).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, WalkerDescription
from biped_sim.config.description import angles_then_rates
from biped_sim.errors import ConfigError
from biped_sim.rigid.tree_build import Tree, tree_locks, tree_params
from biped_sim.rigid.tree_kernels import (
    PAST,
    RELEASED,
    STOP,
    STRIKE,
    after_phase,
    begin_step,
    skip_phase,
    tree_energy,
    tree_guard,
    tree_impact,
    tree_light_rates,
    tree_push,
    tree_rhs,
)
from biped_sim.rigid.tree_layout import point, point_velocity


class RigidWalker:
    """A walker's rigid model for the step map and the limit-cycle tools.

    State: the angles, then the rates, in role order (``state_names``: the description's keys). Just after a heel
    strike every stop is locked (each leg a rigid body) and both feet touch: the section is the stance leg's
    hip-body angle and the legs' rates (the compass's three; two when the swing leg is light, its rate then set
    by the strike; the wheel's one rate, its angle being fixed by the strike).
    """

    def __init__(
        self, config: Config, description: WalkerDescription, name: str, gravity: float, checked: bool = True
    ) -> None:
        self.name, self.description, self.config, self.gravity = name, description, config, gravity
        self.params = tree_params(config, description, gravity)
        self.n_q = self.params.n
        self.state_names = angles_then_rates(description.state_keys())
        self.slope, self.fall_leg_angle = config.ground.slope, config.simulation.fall_leg_angle
        self.fall_angles = self.params.coords["fall_angle"].copy()  # a torso's its own
        self.leg_length, self.foot_radius = self.params.leg_length, self.params.radius
        self.reference_mass = float(sum(self.params.rows["mass"][0, : self.n_points]))
        tree = Tree(description)
        locks = tree_locks(tree, description)
        self.shift, self.lean = tree.shift, self.params.lean
        self.n_feet = len(description.feet) if len(description.legs) == 1 else 2
        self.leg_offsets = np.zeros(self.n_q)  # each body's angle from its leg's hip body with the stops locked
        for parent, child, limit, *_ in locks:
            self.leg_offsets[child] = self.leg_offsets[parent] + limit
        self.start_locks = [(parent, child, limit) for parent, child, limit, *_, leg in locks if leg != 1]
        n, half = self.n_q, tree.leg_size
        self.leg_size, self.off_legs = half, list(range(2 * half if len(description.legs) == 2 else n, n))
        # the swing leg's locks, hip down (parent, child, whether the heel strike leaves it free: its stops released),
        # and the bodies whose rates are free just after the strike: its hip body, each released stop's child
        released = any(lock[4] == RELEASED for lock in locks)
        self.swing_locks = [
            (lock[0], lock[1], released and lock[5] == 1) for lock in locks if half <= lock[1] < 2 * half
        ]
        self.free_swing = [half] + [child for _, child, free in self.swing_locks if free]
        if self.shift:
            self.section_indices = [1]
        else:  # the stance angle and rate, the swing leg's free rates (none when light), each off-leg angle and rate
            swing_light = bool(self.params.coords["stance_light"][half])
            swing = [] if swing_light else [n + k for k in self.free_swing]
            self.section_indices = [0, n, *swing, *self.off_legs, *(n + k for k in self.off_legs)]
            if checked:  # not checked: a walker whose kernels' argument types alone are wanted (simulate.aside)
                self._check_alike()
        self.section_names = tuple(self.state_names[i] for i in self.section_indices)

    @property
    def n_points(self) -> int:
        return self.params.n_points

    def _check_alike(self) -> None:
        """The next step reuses the stance table after the roles swap: the legs must be alike (same flow)."""
        rng = np.random.default_rng(0)
        x = rng.uniform(-0.3, 0.3, 2 * self.n_q)
        d = self.description
        swapped = tree_params(self.config, d.model_copy(update={"legs": [d.legs[1], d.legs[0]]}), self.gravity)
        a, b = np.zeros_like(x), np.zeros_like(x)
        tree_rhs(self.params, x, a)
        tree_rhs(swapped, x, b)  # the other leg in stance, the same state in roles: the same flow
        if not np.allclose(a, b, rtol=1e-10, atol=1e-10):
            raise ConfigError("walker.description", "rigid dynamics needs two alike legs (the same bodies and stops)")

    # --- the flow, the phases and the strikes (the kernels) --------------------------------------------------
    def rhs(self, x: np.ndarray) -> np.ndarray:
        """Time derivative of the state."""
        out = np.zeros(2 * self.n_q)
        tree_rhs(self.params, np.asarray(x, dtype=float), out)
        return out

    def begin_step(self) -> None:
        """A step begins: the swing leg's stops unlock."""
        begin_step(self.params)

    def skip_phase(self, index: int, x: np.ndarray) -> bool:
        """Whether phase ``index`` has nothing to wait for at x (the hip already past the stance foot); a phase
        after the walker's own (a ground profile's) is never skipped here."""
        if index >= len(self.params.phases):
            return False
        return bool(skip_phase(self.params, index, np.asarray(x, dtype=float)))

    def after_phase(self, index: int, x: np.ndarray) -> np.ndarray:
        """The state after phase ``index`` ended (a stop strike's plastic impact; otherwise x)."""
        x = np.array(x, dtype=float)
        after_phase(self.params, index, x, np.zeros_like(x))
        return x

    def phases(self) -> list[tuple[int, str]]:
        """(kind, name) of each phase, in order."""
        names = {STOP: "stop_strike", PAST: "stance_past_normal", STRIKE: "heel_strike"}
        kinds = [int(kind) for kind in self.params.phases["kind"]]
        return [(kind, names[kind]) for kind in kinds]

    def guard_phases(self) -> list[tuple[str, object]]:
        """(name, g(x)) per phase: its downward zero ends it; the last is the heel strike."""
        return [
            (name, lambda x, k=k: float(tree_guard(self.params, k, x))) for k, (_, name) in enumerate(self.phases())
        ]

    def impact(self, x_minus: np.ndarray) -> np.ndarray:
        """The post-impact state (new stance leg first) from the pre-impact state."""
        out = np.zeros(2 * self.n_q)
        tree_impact(self.params, np.asarray(x_minus, dtype=float), True, out)
        return out

    def hip_push(self, x: np.ndarray, impulse: np.ndarray) -> tuple[np.ndarray, float]:
        """(the state just after an impulse on the hip, the ground's normal impulse): :func:`tree_push`."""
        out = np.zeros(2 * self.n_q)
        normal = tree_push(self.params, np.asarray(x, dtype=float), float(impulse[0]), float(impulse[1]), out)
        return out, float(normal)

    def energy(self, x: np.ndarray) -> tuple[float, float]:
        """Kinetic and potential energy (potential zero with every point on the ground line)."""
        kinetic, potential = tree_energy(self.params, np.asarray(x, dtype=float))
        return float(kinetic), float(potential)

    # --- geometry -----------------------------------------------------------------------------------------------
    @property
    def landing_index(self) -> int:
        """The coordinate of the landing leg's hip body (the wheel's one angle)."""
        return int(self.params.coords["perm"][0])

    def next_stance_angle(self, x_minus: np.ndarray) -> float:
        """Angle of the leg (spoke) about to touch down, just before the strike."""
        return float(x_minus[self.landing_index]) + self.shift

    def swing_foot(self, x: np.ndarray, origin: float, level: float) -> tuple[float, float]:
        """(x, height) of the landing foot's lowest point, the stance contact at (origin - R theta, level)."""
        fx, fy = point(self.params, self.n_points + 1, np.asarray(x[: self.n_q], dtype=float))
        return origin + fx, level + fy - self.params.landing_radius

    def contact_point(self, q: np.ndarray) -> np.ndarray:
        """The stance contact point (the frame of :func:`~.tree_kernels.point`)."""
        return np.array([-self.foot_radius * q[self.params.rolling[0]], 0.0])

    def leg_lines(self, x: np.ndarray) -> dict[str, float]:
        """The angle of each leg's line from the hip to its foot (the point, or the arc's centre) from the slope normal
        (+ foot downhill; a straight leg's angle plus its foot's lean), and the inter-leg angle, stance minus swing
        (empty for a wheel: its spokes' angles are its state)."""
        if self.shift:
            return {}
        q = np.asarray(x[: self.n_q], dtype=float)
        hip = self.hip(q)
        stance = self.contact_point(q) + np.array([0.0, self.foot_radius])
        swing = np.array(point(self.params, self.n_points + 1, q))
        stance_line, swing_line = (math.atan2(foot[0] - hip[0], hip[1] - foot[1]) for foot in (stance, swing))
        return {
            "stance_line_angle": stance_line,
            "swing_line_angle": swing_line,
            "inter_leg_angle": stance_line - swing_line,
        }

    def hip_height(self, x: np.ndarray) -> float:
        """The hip's height above the stance foot's ground line."""
        return float(point(self.params, self.n_points, np.asarray(x[: self.n_q], dtype=float))[1])

    def hip_past_stance_foot(self, x: np.ndarray) -> bool:
        """Whether the hip is downhill of the stance contact (a biped cannot start there: just after a strike)."""
        past = next((k for k, (kind, _) in enumerate(self.phases()) if kind == PAST), None)
        return past is not None and float(tree_guard(self.params, past, np.asarray(x, dtype=float))) < 0.0

    def hip(self, q: np.ndarray) -> np.ndarray:
        """The hip's position (the frame of :meth:`contact_point`)."""
        return np.array(point(self.params, self.n_points, np.asarray(q, dtype=float)))

    def linear_momentum(self, x: np.ndarray) -> np.ndarray:
        """The walker's linear momentum (its heavy rows')."""
        n, p = self.n_q, self.params
        q, qd = np.asarray(x[:n], dtype=float), np.asarray(x[n:], dtype=float)
        masses = p.rows["mass"][0]
        return sum((masses[i] * np.array(point_velocity(p, 0, i, q, qd)) for i in range(self.n_points)), np.zeros(2))

    def angular_momentum(self, x: np.ndarray, about: np.ndarray, coordinates: set[int] | None = None) -> float:
        """Angular momentum (z) about a fixed point of the rows whose inertia turns with ``coordinates`` (None:
        all): the bodies' centres of mass and the point masses, in the frame of :meth:`contact_point`."""
        n, p = self.n_q, self.params
        q, qd = np.asarray(x[:n], dtype=float), np.asarray(x[n:], dtype=float)
        total = 0.0
        for i in range(self.n_points):
            mass, inertia, own = p.rows[0, i]
            if coordinates is None or own in coordinates:
                rx, ry = np.array(point(p, i, q)) - about
                vx, vy = point_velocity(p, 0, i, q, qd)
                total += mass * (rx * vy - ry * vx) + inertia * qd[own]
        return float(total)

    # --- the state by name, the section --------------------------------------------------------------------------
    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        """Independent coordinates of a post-impact state."""
        return np.array([x_plus[i] for i in self.section_indices])

    def section_point(self, angle: float, rate: float, swing_rate: float) -> np.ndarray:
        """A section point of a typical passive gait: the stance angle and rate, every free swing rate
        ``swing_rate``, the bodies off the legs (a torso) upright and at rest."""
        swing = len(self.section_names) - 2 - 2 * len(self.off_legs)
        return np.array([angle, rate] + [swing_rate] * swing + [0.0] * (2 * len(self.off_legs)))

    def from_section(self, z: np.ndarray) -> np.ndarray:
        """Post-impact state from its section coordinates (the legs symmetric about -phi, every stop locked; the
        swing leg's bodies turning with its hip body but those the strike leaves free, which have their own rates)."""
        if self.shift:
            return np.array([0.5 * self.shift - self.lean, z[0]])
        half, off = self.leg_size, len(self.off_legs)
        swing = -z[0] - 2.0 * self.lean
        z_off = z[len(z) - 2 * off :]
        angles = np.concatenate(
            [z[0] + self.leg_offsets[:half], swing + self.leg_offsets[half : 2 * half], z_off[:off]]
        )
        rates = np.concatenate([np.full(half, z[1]), np.zeros(half), z_off[off:]])
        rates[self.free_swing[: len(z) - 2 - 2 * off]] = z[2 : len(z) - 2 * off]
        for parent, child, free in self.swing_locks:  # hip down: a held stop's child turns with its parent
            rates[child] = rates[child] if free else rates[parent]
        x = np.concatenate([angles, rates])
        tree_light_rates(self.params, x)
        return x

    def state_from_legs(self, legs: dict[str, float]) -> np.ndarray:
        """The state of the initial-state keys, on the joints locked at a step's start (the stance leg's stops:
        its keys below the hip body are then implied); a body off the legs without keys starts upright at rest."""
        n = self.n_q
        off = {self.state_names[k] for k in self.off_legs} | {self.state_names[n + k] for k in self.off_legs}
        x = np.array([legs.get(name, 0.0) if name in off else legs[name] for name in self.state_names], dtype=float)
        for parent, child, limit in self.start_locks:
            x[child], x[n + child] = x[parent] + limit, x[n + parent]
        return x

    def relabelled(self, x_minus: np.ndarray) -> np.ndarray:
        """A pre-impact state in the roles after the heel strike (the landing leg's bodies first), rates unchanged:
        the strike's relabelling without its impulse (coordinate k is coordinate perm[k] before plus shift[k])."""
        n, coords = self.n_q, self.params.coords
        perm = coords["perm"]
        return np.concatenate([x_minus[:n][perm] + coords["shift"], x_minus[n:][perm]])

    def guess_state(self, guess: dict[str, float]) -> np.ndarray:
        """The post-impact state of a guess: its section coordinates (:attr:`section_names`) or its initial-state
        keys (:meth:`state_from_legs`)."""
        if set(guess) == set(self.section_names):
            return self.from_section(np.array([guess[name] for name in self.section_names]))
        return self.state_from_legs(guess)

    def legs_state(self, x: np.ndarray) -> dict[str, float]:
        """The initial-state keys of a state (the wheel's 'swing' spoke: the one just behind its stance spoke)."""
        legs = {name: float(x[i]) for i, name in enumerate(self.state_names)}
        if self.shift:
            legs.update(swing_angle=float(x[0]) - self.shift, swing_rate=float(x[1]))
        return legs

    def fallen(self, x: np.ndarray) -> bool:
        """A leg's hip body, or a body off the legs (a torso), past the fall angle."""
        return any(abs(x[k]) >= self.fall_angles[k] for k in (0, self.landing_index, *self.off_legs))
