"""A described walker's rigid model: the tree's points and locks laid out for :mod:`biped_sim.rigid.tree_kernels`.

The phases follow from the description: the swing leg's stops strike one after another (the kneed walker: its
unlocked three-link swing ends at the knee strike), then the hip passes over the stance foot, then the heel
strikes with every stop of both legs locked through it, and the new swing leg's stops unlock at once. The
stance leg's stops stay locked (a straight stance leg, as Chen 2007 and McGeer 1990 model it).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config, WalkerDescription
from biped_sim.config.description import angles_then_rates
from biped_sim.errors import ConfigError
from biped_sim.rigid.models import RigidWalker
from biped_sim.rigid.tree_kernels import (
    PAST,
    STOP,
    STRIKE,
    T_NPHASE,
    T_NPTS,
    T_RSW,
    after_phase,
    begin_step,
    layout_size,
    phase_offset,
    point,
    row_offset,
    skip_phase,
    tree_energy,
    tree_guard,
    tree_impact,
    tree_push,
    tree_rhs,
)

Vec = np.ndarray


def _rot(theta: float, v: Vec) -> Vec:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


class _Tree:
    """The description in role order: coordinate k is body ``order[k]`` (the stance leg's hip down, then the swing
    leg's); a point's position is sum_k Rot(theta_k) w[k] (+ the stance foot's contact)."""

    def __init__(self, d: WalkerDescription) -> None:
        self.order = [b for leg in d.legs for b in leg]
        names = [b.name for b in d.bodies]
        if len(d.legs) != 2 or sorted(self.order) != sorted(names):
            raise ConfigError("walker.description.legs", "rigid dynamics needs two legs holding every body")
        self.index = {name: k for k, name in enumerate(self.order)}
        self.body = {b.name: b for b in d.bodies}
        self.joint = {j.child: j for j in d.joints}
        self.root = d.bodies[0].name
        feet = [[f for f in d.feet if f.body in leg] for leg in d.legs]
        if any(len(f) != 1 for f in feet):
            raise ConfigError("walker.description.feet", "rigid dynamics needs one foot on each leg")
        self.feet = [f[0] for f in feet]

    def origin(self, name: str, stance: int) -> dict[int, Vec]:
        """w of body ``name``'s origin with leg ``stance``'s foot pinned (its contact point at the origin)."""
        if name == self.root:
            foot = self.feet[stance]
            w = {self.index[foot.body]: -np.array(foot.centre)}
            body = foot.body
            while body != self.root:  # up from the foot: origin(parent) = origin(body) - Rot(parent) at
                j = self.joint[body]
                w[self.index[j.parent]] = w.get(self.index[j.parent], np.zeros(2)) - np.array(j.at)
                body = j.parent
            return w
        j = self.joint[name]
        w = dict(self.origin(j.parent, stance))
        w[self.index[j.parent]] = w.get(self.index[j.parent], np.zeros(2)) + np.array(j.at)
        return w

    def at(self, name: str, local: tuple[float, float], stance: int) -> dict[int, Vec]:
        """w of a point fixed in body ``name``."""
        w = dict(self.origin(name, stance))
        w[self.index[name]] = w.get(self.index[name], np.zeros(2)) + np.array(local)
        return w


def _rows(tree: _Tree, d: WalkerDescription, stance: int) -> list[tuple[float, float, int, dict[int, Vec]]]:
    """(mass, inertia, coordinate, w) of every body's centre of mass and every point mass."""
    rows = [(b.mass, b.inertia, tree.index[b.name], tree.at(b.name, b.com, stance)) for b in d.bodies]
    rows += [(pm.mass, 0.0, tree.index[pm.body], tree.at(pm.body, pm.at, stance)) for pm in d.point_masses]
    return rows


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


def tree_params(config: Config, d: WalkerDescription) -> np.ndarray:
    """The parameter vector of the kernels (the shared header, the tables, locks, phases, permutation, workspace)."""
    tree = _Tree(d)
    n = len(tree.order)
    rows = [_rows(tree, d, stance) for stance in (0, 1)]
    locks = _locks(tree, d)
    phases = [(STOP, j) for j, lock in enumerate(locks) if lock[5] == 1] + [(PAST, 0), (STRIKE, 0)]
    half = n // 2
    perm = [half + k for k in range(half)] + list(range(half))
    leg_length = -point_of(tree, tree.at(tree.feet[0].body, tree.feet[0].centre, 0), n, locks)[1]
    header = [n, leg_length + tree.feet[0].radius, tree.feet[0].radius, 0.0, config.gravity, config.ground.slope,
              config.simulation.fall_leg_angle, 0.0, len(rows[0])]  # fmt: skip
    p = [*header, len(locks), len(phases), len(rows[0]), tree.feet[1].radius]
    for stance in (0, 1):
        p.append(tree.index[tree.feet[stance].body])
        for mass, inertia, own, w in rows[stance]:
            p += [mass, inertia, own, *_flat(w, n)]
    p += _flat(tree.origin(tree.root, 0), n) + _flat(tree.at(tree.feet[1].body, tree.feet[1].centre, 0), n)
    p += [v for lock in locks for v in lock[:5]] + [v for phase in phases for v in phase] + perm
    size, work = layout_size(n, len(rows[0]), len(locks), len(phases))
    assert len(p) == size, (len(p), size)
    return np.array(p + [0.0] * work, dtype=float)


def point_of(tree: _Tree, w: dict[int, Vec], n: int, locks: list) -> Vec:  # type: ignore[type-arg]
    """A point's position (relative to the hip's w-sum) with every leg joint at its stop and the legs vertical."""
    angles = np.zeros(n)
    for parent, child, limit, *_ in locks:
        angles[child] = angles[parent] + limit
    return sum((_rot(angles[k], v) for k, v in w.items()), np.zeros(2)) - sum(
        (_rot(angles[k], v) for k, v in tree.origin(tree.root, 0).items()), np.zeros(2)
    )


class TreeWalker(RigidWalker):
    """A described walker's rigid model for the step map and the limit-cycle tools (their :class:`RigidWalker`).

    State: the angles, then the rates, in role order (``state_names``: the description's keys). Just after a heel
    strike every stop is locked (each leg a rigid body) and both feet touch: the section is the stance leg's
    hip-body angle and the two legs' rates, as the compass's.
    """

    name = "description"
    section_names = ("stance_angle", "stance_rate", "swing_rate")

    def __init__(self, config: Config, description: WalkerDescription) -> None:
        self.description, self.config = description, config
        self.params = tree_params(config, description)
        self.n_q = int(self.params[0])
        self.state_names = angles_then_rates(description.state_keys())
        self.gravity, self.slope = config.gravity, config.ground.slope
        self.leg_length, self.foot_radius = float(self.params[1]), float(self.params[2])
        self.fall_leg_angle = config.simulation.fall_leg_angle
        self.reference_mass = float(sum(self.params[self._row(0, i)] for i in range(self.n_points)))
        tree = _Tree(description)
        locks = _locks(tree, description)
        self.leg_offsets = np.zeros(self.n_q)  # each body's angle from its leg's hip body with the stops locked
        for parent, child, limit, *_ in locks:
            self.leg_offsets[child] = self.leg_offsets[parent] + limit
        self.start_locks = [(parent, child, limit) for parent, child, limit, *_, leg in locks if leg != 1]
        foot = point_of(tree, tree.at(tree.feet[0].body, tree.feet[0].centre, 0), self.n_q, locks)
        self.phi = math.atan2(foot[0], -foot[1])  # the locked leg's foot centre leans phi from its hip body's axis
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
        swapped = tree_params(self.config, d.model_copy(update={"legs": [d.legs[1], d.legs[0]]}))
        a, b = np.zeros_like(x), np.zeros_like(x)
        tree_rhs(self.params, x, a)
        tree_rhs(swapped, x, b)  # the other leg in stance, the same state in roles: the same flow
        if not np.allclose(a, b, rtol=1e-10, atol=1e-10):
            raise ConfigError("walker.description", "rigid dynamics needs two alike legs (the same bodies and stops)")

    # --- the RigidWalker interface --------------------------------------------------------------------------
    def rhs(self, x: np.ndarray) -> np.ndarray:
        out = np.zeros(2 * self.n_q)
        tree_rhs(self.params, np.asarray(x, dtype=float), out)
        return out

    def begin_step(self) -> None:
        begin_step(self.params)

    def skip_phase(self, index: int, x: np.ndarray) -> bool:
        return bool(skip_phase(self.params, index, np.asarray(x, dtype=float)))

    def after_phase(self, index: int, x: np.ndarray) -> np.ndarray:
        x = np.array(x, dtype=float)
        after_phase(self.params, index, x, np.zeros_like(x))
        return x

    def phases(self) -> list[tuple[int, str]]:
        """(kind, name) of each phase, in order."""
        names = {STOP: "stop_strike", PAST: "stance_past_normal", STRIKE: "heel_strike"}
        kinds = [int(self.params[phase_offset(self.params, k)]) for k in range(int(self.params[T_NPHASE]))]
        return [(kind, names[kind]) for kind in kinds]

    def guard_phases(self) -> list[tuple[str, object]]:
        return [
            (name, lambda x, k=k: float(tree_guard(self.params, k, x))) for k, (_, name) in enumerate(self.phases())
        ]

    def impact(self, x_minus: np.ndarray) -> np.ndarray:
        out = np.zeros(2 * self.n_q)
        tree_impact(self.params, np.asarray(x_minus, dtype=float), True, out)
        return out

    def hip_push(self, x: np.ndarray, impulse: np.ndarray) -> tuple[np.ndarray, float]:
        """(the state just after an impulse on the hip, the ground's normal impulse): :func:`tree_push`."""
        out = np.zeros(2 * self.n_q)
        normal = tree_push(self.params, np.asarray(x, dtype=float), float(impulse[0]), float(impulse[1]), out)
        return out, float(normal)

    def swing_foot(self, x: np.ndarray, origin: float, level: float) -> tuple[float, float]:
        """(x, height) of the swing foot's lowest point, the stance contact at (origin - R theta, level)."""
        fx, fy = point(self.params, self.n_points + 1, np.asarray(x[: self.n_q], dtype=float))
        return origin + fx, level + fy - float(self.params[T_RSW])

    def energy(self, x: np.ndarray) -> tuple[float, float]:
        kinetic, potential = tree_energy(self.params, np.asarray(x, dtype=float))
        return float(kinetic), float(potential)

    def to_section(self, x_plus: np.ndarray) -> np.ndarray:
        half = self.n_q // 2
        return np.array([x_plus[0], x_plus[self.n_q], x_plus[self.n_q + half]])

    def from_section(self, z: np.ndarray) -> np.ndarray:
        half = self.n_q // 2
        swing = -z[0] - 2.0 * self.phi
        angles = np.concatenate([z[0] + self.leg_offsets[:half], swing + self.leg_offsets[half:]])
        return np.concatenate([angles, np.full(half, z[1]), np.full(half, z[2])])

    def next_stance_angle(self, x_minus: np.ndarray) -> float:
        return float(x_minus[self.landing_index])

    @property
    def landing_index(self) -> int:
        return self.n_q // 2

    def hip_height(self, x: np.ndarray) -> float:
        return float(point(self.params, self.n_points, np.asarray(x[: self.n_q], dtype=float))[1])

    def state_from_legs(self, legs: dict[str, float]) -> np.ndarray:
        """The state of the initial-state keys, on the joints locked at a step's start (the stance leg's stops:
        its keys below the hip body are then implied)."""
        x = super().state_from_legs(legs)
        n = self.n_q
        for parent, child, limit in self.start_locks:
            x[child], x[n + child] = x[parent] + limit, x[n + parent]
        return x

    def legs_state(self, x: np.ndarray) -> dict[str, float]:
        return {name: float(x[i]) for i, name in enumerate(self.state_names)}

    def fallen(self, x: np.ndarray) -> bool:
        half = self.n_q // 2
        return bool(abs(x[0]) >= self.fall_leg_angle or abs(x[half]) >= self.fall_leg_angle)
