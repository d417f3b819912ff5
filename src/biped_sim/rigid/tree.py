"""A walker's rigid model: its description's tree laid out for the compiled kernels of :mod:`.tree_kernels`.

Every rigid walker is one of these, built from its description (:func:`biped_sim.walkers.describe.describe`: the
compass, Garcia's simplest walker, the rimless wheel, or a walker written as YAML). Two kinds of tree walk:

* two alike legs (a leg: the bodies from the hip down), one foot on each, an arc or a point: the phases follow
  from the description: the swing leg's stops strike one after another (the kneed walker: its unlocked three-link
  swing ends at the knee strike), then the hip passes over the stance foot, then the heel strikes with every stop
  of both legs locked through it, and the new swing leg's stops unlock at once. The stance leg's stops stay locked
  (a straight stance leg, as Chen 2007 and McGeer 1990 model it);
* one body with N >= 2 point feet evenly spaced about its origin (the rimless wheel): the next spoke strikes.

Massless legs (Garcia's simplest walker) are the limit of infinitesimal foot masses (:mod:`.tree_kernels`).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, FootSpec, WalkerDescription
from biped_sim.config.description import angles_then_rates
from biped_sim.errors import ConfigError
from biped_sim.rigid.tree_kernels import (
    PAST,
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
from biped_sim.rigid.tree_layout import (
    T_NPHASE,
    T_NPTS,
    T_RSW,
    T_TABLES,
    layout_size,
    perm_offset,
    phase_offset,
    point,
    point_velocity,
    row_offset,
)

Vec = np.ndarray
SPACING_TOLERANCE = 1e-9  # a wheel's feet: equal radii and spacing to this relative tolerance


def _rot(theta: float, v: Vec) -> Vec:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


class _Tree:
    """The description in role order: coordinate k is body ``order[k]`` (the stance leg's hip down, then the swing
    leg's); a point's position is sum_k Rot(theta_k) w[k] (+ the pinned foot's contact). ``feet``: the stance foot
    and the one that lands next; ``shift``: the landing foot's angle from the stance foot's about the hip (a wheel)."""

    def __init__(self, d: WalkerDescription) -> None:
        self.order = [b for leg in d.legs for b in leg]
        names = [b.name for b in d.bodies]
        if len(d.legs) > 2 or sorted(self.order) != sorted(names):
            raise ConfigError("walker.description.legs", "rigid dynamics needs one or two legs holding every body")
        self.index = {name: k for k, name in enumerate(self.order)}
        self.body = {b.name: b for b in d.bodies}
        self.joint = {j.child: j for j in d.joints}
        self.root = d.bodies[0].name
        self.shift = 0.0
        if len(d.legs) == 2:
            feet = [[f for f in d.feet if f.body in leg] for leg in d.legs]
            if any(len(f) != 1 for f in feet):
                raise ConfigError("walker.description.feet", "rigid dynamics needs one foot on each leg")
            self.feet = (feet[0][0], feet[1][0])
        else:
            self.feet = (d.feet[0], d.feet[1]) if len(d.feet) > 1 else (d.feet[0], d.feet[0])
            self.shift = _wheel_spacing(d)

    def origin(self, name: str, pinned: FootSpec) -> dict[int, Vec]:
        """w of body ``name``'s origin with foot ``pinned``'s centre at the origin (its contact below it)."""
        if name == self.root:
            w = {self.index[pinned.body]: -np.array(pinned.centre)}
            body = pinned.body
            while body != self.root:  # up from the foot: origin(parent) = origin(body) - Rot(parent) at
                j = self.joint[body]
                w[self.index[j.parent]] = w.get(self.index[j.parent], np.zeros(2)) - np.array(j.at)
                body = j.parent
            return w
        j = self.joint[name]
        w = dict(self.origin(j.parent, pinned))
        w[self.index[j.parent]] = w.get(self.index[j.parent], np.zeros(2)) + np.array(j.at)
        return w

    def at(self, name: str, local: tuple[float, float], pinned: FootSpec) -> dict[int, Vec]:
        """w of a point fixed in body ``name``."""
        w = dict(self.origin(name, pinned))
        w[self.index[name]] = w.get(self.index[name], np.zeros(2)) + np.array(local)
        return w


def _wheel_spacing(d: WalkerDescription) -> float:
    """The angle between a one-body walker's consecutive feet (ConfigError unless they are N >= 2 point feet evenly
    spaced on a circle about the body's origin, counted around it, the centre of mass at the origin)."""
    field = "walker.description.feet"
    if len(d.legs[0]) != 1 or len(d.feet) < 2 or any(f.radius != 0.0 for f in d.feet):
        raise ConfigError(field, "a one-legged rigid walker needs one body with two or more point feet (a wheel)")
    radii = [math.hypot(*f.centre) for f in d.feet]
    angles = [math.atan2(f.centre[0], -f.centre[1]) for f in d.feet]
    spacing = 2.0 * math.pi / len(d.feet)
    steps = [(b - a) % (2.0 * math.pi) for a, b in zip(angles, angles[1:] + angles[:1], strict=True)]
    if max(radii) - min(radii) > SPACING_TOLERANCE * max(radii) or any(
        abs(step - spacing) > SPACING_TOLERANCE for step in steps
    ):
        raise ConfigError(field, "a rigid wheel's feet must be evenly spaced on a circle about its origin, in order")
    if any(b.com != (0.0, 0.0) for b in d.bodies) or any(pm.at != (0.0, 0.0) for pm in d.point_masses):
        raise ConfigError("walker.description.bodies", "a rigid wheel's mass must be at its hub (the body's origin)")
    return spacing


def _rows(tree: _Tree, d: WalkerDescription, pinned: FootSpec) -> list[tuple[float, float, int, dict[int, Vec]]]:
    """(mass, inertia, coordinate, w) of every body's centre of mass and every point mass."""
    rows = [(b.mass, b.inertia, tree.index[b.name], tree.at(b.name, b.com, pinned)) for b in d.bodies]
    rows += [(pm.mass, 0.0, tree.index[pm.body], tree.at(pm.body, pm.at, pinned)) for pm in d.point_masses]
    return rows


def _light_rows(tree: _Tree, pinned: FootSpec) -> list[tuple[float, float, int, dict[int, Vec]]]:
    """The feet's infinitesimal masses, unit weights (the stance and the landing foot, in that order)."""
    return [(1.0, 0.0, tree.index[f.body], tree.at(f.body, f.centre, pinned)) for f in tree.feet]


def _light_flags(tree: _Tree, rows: list, locks: list, radius: float, rolling: int, n: int) -> list[float]:
    """1 for each coordinate that no mass, inertia or lock turns with (a massless body's), else 0."""
    heavy = set()
    for mass, inertia, own, w in rows:
        if inertia > 0.0:
            heavy.add(own)
        if mass > 0.0:
            heavy.update(k for k, v in w.items() if np.any(v != 0.0))
            heavy.update([rolling] if radius > 0.0 else [])
    heavy.update(k for lock in locks for k in lock[:2])
    return [0.0 if k in heavy else 1.0 for k in range(n)]


def _flat(w: dict[int, Vec], n: int) -> list[float]:
    out = np.zeros((n, 2))
    for k, v in w.items():
        out[k] = v
    return out.ravel().tolist()


def _locks(tree: _Tree, d: WalkerDescription) -> list[tuple[int, int, float, float, float, int]]:
    """(parent, child, limit, sign, active, leg) of every stop; a leg joint needs one stop, or two at one angle (a
    locked joint: leg -1, never a phase), the hip none."""
    locks = []
    for j in d.joints:
        leg = next(i for i, leg in enumerate(d.legs) if j.child in leg)
        if j.parent not in d.legs[leg]:
            if j.stops:
                raise ConfigError("walker.description.joints", f"{j.name}: rigid dynamics takes stops in legs only")
            continue
        lower, upper = j.lower_upper()
        if len(j.stops) == 2 and lower == upper:
            locks.append((tree.index[j.parent], tree.index[j.child], upper, 1.0, 1.0, -1))
            continue
        if len(j.stops) != 1:
            raise ConfigError(
                "walker.description.joints",
                f"{j.name}: rigid dynamics needs one stop (or two at one angle) in a leg",
            )
        stop = j.stops[0]
        sign = 1.0 if stop.side == "upper" else -1.0
        locks.append((tree.index[j.parent], tree.index[j.child], stop.angle, sign, float(leg == 0), leg))
    return locks


def _relabelling(tree: _Tree, n: int) -> tuple[list[int], list[float]]:
    """(perm, shift) of the heel strike: coordinate k after it is coordinate perm[k] before plus shift[k]."""
    if tree.shift:
        return [0], [tree.shift]
    half = n // 2
    return [half + k for k in range(half)] + list(range(half)), [0.0] * n


def _leg_lean(tree: _Tree, n: int, locks: list) -> tuple[float, float]:
    """(depth, lean) of the stance foot's centre below the hip with the leg locked at its stops and its hip body
    vertical, and its angle from the hip body's axis (phi = atan2(d, l - R) for the compass)."""
    foot = point_of(tree, tree.at(tree.feet[0].body, tree.feet[0].centre, tree.feet[0]), n, locks)
    return -foot[1], math.atan2(foot[0], -foot[1])


def tree_params(config: Config, d: WalkerDescription, gravity: float) -> np.ndarray:
    """The parameter vector of the kernels (the header, the tables, locks, phases, relabelling, workspace)."""
    tree = _Tree(d)
    n = len(tree.order)
    locks = _locks(tree, d)
    rows = [_rows(tree, d, foot) for foot in tree.feet]
    rolling = [tree.index[foot.body] for foot in tree.feet]
    flags = [_light_flags(tree, rows[t], locks, tree.feet[t].radius, rolling[t], n) for t in (0, 1)]
    light = [_light_rows(tree, foot) for foot in tree.feet] if any(map(any, flags)) else [[], []]
    phases = [(STOP, j) for j, lock in enumerate(locks) if lock[5] == 1]
    phases += [(PAST, 0), (STRIKE, 0)] if len(d.legs) == 2 else [(STRIKE, 0)]
    perm, shift = _relabelling(tree, n)
    depth, lean = _leg_lean(tree, n, locks)
    radius = tree.feet[0].radius
    header = [n, depth + radius, radius, lean, gravity, config.ground.slope, config.simulation.fall_leg_angle]
    p = [*header, len(locks), len(phases), len(rows[0]), tree.feet[1].radius, len(light[0])]
    for t in (0, 1):
        p.append(rolling[t])
        for mass, inertia, own, w in rows[t] + light[t]:
            p += [mass, inertia, own, *_flat(w, n)]
    p += _flat(tree.origin(tree.root, tree.feet[0]), n)
    p += _flat(tree.at(tree.feet[1].body, tree.feet[1].centre, tree.feet[0]), n)
    p += [v for lock in locks for v in lock[:5]] + [v for phase in phases for v in phase]
    p += perm + shift + flags[0] + flags[1]
    size, work = layout_size(n, len(rows[0]), len(light[0]), len(locks), len(phases))
    assert len(p) == size, (len(p), size)
    return np.array(p + [0.0] * work, dtype=float)


def point_of(tree: _Tree, w: dict[int, Vec], n: int, locks: list) -> Vec:  # type: ignore[type-arg]
    """A point's position (relative to the hip's w-sum) with every leg joint at its stop and the legs vertical."""
    angles = np.zeros(n)
    for parent, child, limit, *_ in locks:
        angles[child] = angles[parent] + limit
    return sum((_rot(angles[k], v) for k, v in w.items()), np.zeros(2)) - sum(
        (_rot(angles[k], v) for k, v in tree.origin(tree.root, tree.feet[0]).items()), np.zeros(2)
    )


class RigidWalker:
    """A walker's rigid model for the step map and the limit-cycle tools.

    State: the angles, then the rates, in role order (``state_names``: the description's keys). Just after a heel
    strike every stop is locked (each leg a rigid body) and both feet touch: the section is the stance leg's
    hip-body angle and the legs' rates (the compass's three; two when the swing leg is light, its rate then set
    by the strike; the wheel's one rate, its angle being fixed by the strike).
    """

    def __init__(self, config: Config, description: WalkerDescription, name: str, gravity: float) -> None:
        self.name, self.description, self.config, self.gravity = name, description, config, gravity
        self.params = tree_params(config, description, gravity)
        self.n_q = int(self.params[0])
        self.state_names = angles_then_rates(description.state_keys())
        self.slope, self.fall_leg_angle = config.ground.slope, config.simulation.fall_leg_angle
        self.leg_length, self.foot_radius = float(self.params[1]), float(self.params[2])
        self.reference_mass = float(sum(self.params[self._row(0, i)] for i in range(self.n_points)))
        tree = _Tree(description)
        locks = _locks(tree, description)
        self.shift, self.lean = tree.shift, float(self.params[3])
        self.n_feet = len(description.feet) if len(description.legs) == 1 else 2
        self.leg_offsets = np.zeros(self.n_q)  # each body's angle from its leg's hip body with the stops locked
        for parent, child, limit, *_ in locks:
            self.leg_offsets[child] = self.leg_offsets[parent] + limit
        self.start_locks = [(parent, child, limit) for parent, child, limit, *_, leg in locks if leg != 1]
        n, half = self.n_q, self.n_q // 2
        if self.shift:
            self.section_names: tuple[str, ...] = (self.state_names[1],)
        else:
            swing_light = self.params[perm_offset(self.params) + 2 * n + half] != 0.0
            self.section_names = (self.state_names[0], self.state_names[n], self.state_names[n + half])
            self.section_names = self.section_names[:2] if swing_light else self.section_names
            self._check_alike()

    @property
    def n_points(self) -> int:
        return int(self.params[T_NPTS])

    def _row(self, table: int, i: int) -> int:
        return int(row_offset(self.params, table, i))

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
        if index >= int(self.params[T_NPHASE]):
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
        kinds = [int(self.params[phase_offset(self.params, k)]) for k in range(int(self.params[T_NPHASE]))]
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
        return int(self.params[perm_offset(self.params)])

    @property
    def landing_foot_body(self) -> int:
        """The coordinate of the body carrying the landing foot (table 1's rolling coordinate)."""
        return int(self.params[row_offset(self.params, 1, 0) - 1])

    def next_stance_angle(self, x_minus: np.ndarray) -> float:
        """Angle of the leg (spoke) about to touch down, just before the strike."""
        return float(x_minus[self.landing_index]) + self.shift

    def swing_foot(self, x: np.ndarray, origin: float, level: float) -> tuple[float, float]:
        """(x, height) of the landing foot's lowest point, the stance contact at (origin - R theta, level)."""
        fx, fy = point(self.params, self.n_points + 1, np.asarray(x[: self.n_q], dtype=float))
        return origin + fx, level + fy - float(self.params[T_RSW])

    def contact_point(self, q: np.ndarray) -> np.ndarray:
        """The stance contact point (the frame of :func:`~.tree_kernels.point`)."""
        rolling = int(self.params[T_TABLES])  # table 0's rolling coordinate
        return np.array([-self.foot_radius * q[rolling], 0.0])

    def step_length(self, x_start: np.ndarray, x_minus: np.ndarray) -> float:
        """Advance of the contact point over a step: from the stance contact at the start to the landing foot's."""
        return float(self.swing_foot(x_minus, 0.0, 0.0)[0] - self.contact_point(np.asarray(x_start))[0])

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
        rows = [self._row(0, i) for i in range(self.n_points)]
        return sum((p[o] * np.array(point_velocity(p, 0, i, q, qd)) for i, o in enumerate(rows)), np.zeros(2))

    def angular_momentum(self, x: np.ndarray, about: np.ndarray, coordinates: set[int] | None = None) -> float:
        """Angular momentum (z) about a fixed point of the rows whose inertia turns with ``coordinates`` (None:
        all): the bodies' centres of mass and the point masses, in the frame of :meth:`contact_point`."""
        n, p = self.n_q, self.params
        q, qd = np.asarray(x[:n], dtype=float), np.asarray(x[n:], dtype=float)
        total = 0.0
        for i in range(self.n_points):
            o = self._row(0, i)
            mass, inertia, own = p[o], p[o + 1], int(p[o + 2])
            if coordinates is None or own in coordinates:
                rx, ry = np.array(point(p, i, q)) - about
                vx, vy = point_velocity(p, 0, i, q, qd)
                total += mass * (rx * vy - ry * vx) + inertia * qd[own]
        return float(total)

    # --- the state by name, the section --------------------------------------------------------------------------
    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        """Independent coordinates of a post-impact state."""
        n = self.n_q
        indices = [n] if self.shift else [0, n, n + n // 2][: len(self.section_names)]
        return np.array([x_plus[i] for i in indices])

    def from_section(self, z: np.ndarray) -> np.ndarray:
        """Post-impact state from its section coordinates (the legs symmetric about -phi, every stop locked)."""
        if self.shift:
            return np.array([0.5 * self.shift - self.lean, z[0]])
        half = self.n_q // 2
        swing = -z[0] - 2.0 * self.lean
        angles = np.concatenate([z[0] + self.leg_offsets[:half], swing + self.leg_offsets[half:]])
        swing_rate = z[2] if len(z) > 2 else 0.0
        x = np.concatenate([angles, np.full(half, z[1]), np.full(half, swing_rate)])
        tree_light_rates(self.params, x)
        return x

    def state_from_legs(self, legs: dict[str, float]) -> np.ndarray:
        """The state of the initial-state keys, on the joints locked at a step's start (the stance leg's stops:
        its keys below the hip body are then implied)."""
        x = np.array([legs[name] for name in self.state_names], dtype=float)
        n = self.n_q
        for parent, child, limit in self.start_locks:
            x[child], x[n + child] = x[parent] + limit, x[n + parent]
        return x

    def legs_state(self, x: np.ndarray) -> dict[str, float]:
        """The initial-state keys of a state (the wheel's 'swing' spoke: the one just behind its stance spoke)."""
        legs = {name: float(x[i]) for i, name in enumerate(self.state_names)}
        if self.shift:
            legs.update(swing_angle=float(x[0]) - self.shift, swing_rate=float(x[1]))
        return legs

    def fallen(self, x: np.ndarray) -> bool:
        """A leg's hip body past the fall angle."""
        return bool(abs(x[0]) >= self.fall_leg_angle or abs(x[self.landing_index]) >= self.fall_leg_angle)
