"""A walker's description laid out as the records of the compiled rigid kernels (:class:`.tree_layout.RigidTree`).

Coordinates in role order (the stance leg's bodies from the hip down, then the swing leg's); every point the
equations need is the pinned foot's contact plus sum_k Rot(theta_k) w_k, and this module computes the w_k from the
tree; the rows (bodies with their point masses folded in), the light rows and flags, the locks, the phases and the
heel strike's relabelling. :class:`~biped_sim.rigid.tree.RigidWalker` is the model built on it.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from biped_sim.config import Config, FootSpec, WalkerDescription
from biped_sim.contact.joint_element import JOINT_ELEMENT_LAWS, N_ELEMENT_PARAMS, element_parameters
from biped_sim.errors import ConfigError
from biped_sim.rigid.tree_kernels import PAST, RELEASED, STOP, STRIKE
from biped_sim.rigid.tree_layout import COORD, ELEMENT, LOCK, PHASE, ROW, RigidTree, gravity_vector, workspace_size

Vec = np.ndarray
SPACING_TOLERANCE = 1e-9  # a wheel's feet: equal radii and spacing to this relative tolerance


def _rot(theta: float, v: Vec) -> Vec:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


class Tree:
    """The description in role order: coordinate k is body ``order[k]`` (the stance leg's hip down, then the swing
    leg's); a point's position is sum_k Rot(theta_k) w[k] (+ the pinned foot's contact). ``feet``: the stance foot
    and the one that lands next; ``shift``: the landing foot's angle from the stance foot's about the hip (a wheel)."""

    def __init__(self, d: WalkerDescription) -> None:
        legs = [b for leg in d.legs for b in leg]
        self.off_legs = [b.name for b in d.bodies if b.name not in legs]  # a torso: its coordinates after the legs'
        self.order = legs + self.off_legs
        self.leg_size = len(d.legs[0])
        if len(d.legs) > 2 or (self.off_legs and len(d.legs) != 2):
            raise ConfigError(
                "walker.description.legs", "rigid dynamics needs one or two legs, and two to carry a body off them"
            )
        if any(f.body in self.off_legs for f in d.feet):
            raise ConfigError("walker.description.feet", "rigid dynamics takes feet on the legs only")
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


def _rows(tree: Tree, d: WalkerDescription, pinned: FootSpec) -> list[tuple[float, float, int, dict[int, Vec]]]:
    """(mass, inertia, coordinate, w) of each body with mass or inertia, its point masses folded in (their mass, the
    joint centre of mass, the parallel-axis inertia about it)."""
    rows = []
    for b in d.bodies:
        parts = [(b.mass, np.array(b.com))] + [(pm.mass, np.array(pm.at)) for pm in d.point_masses if pm.body == b.name]
        mass = sum(m for m, _ in parts)
        if mass == 0.0 and b.moment_of_inertia == 0.0:
            continue
        com = sum((m * at for m, at in parts), np.zeros(2)) / mass if mass > 0.0 else parts[0][1]
        inertia = b.moment_of_inertia + sum(m * float((at - com) @ (at - com)) for m, at in parts)
        rows.append((mass, inertia, tree.index[b.name], tree.at(b.name, (float(com[0]), float(com[1])), pinned)))
    return rows


def _light_rows(tree: Tree, pinned: FootSpec) -> list[tuple[float, float, int, dict[int, Vec]]]:
    """The feet's infinitesimal masses, unit weights (the stance and the landing foot, in that order)."""
    return [(1.0, 0.0, tree.index[f.body], tree.at(f.body, f.centre, pinned)) for f in tree.feet]


def _light_flags(tree: Tree, rows: list, locks: list, radius: float, rolling: int, n: int) -> list[float]:
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


def tree_locks(tree: Tree, d: WalkerDescription) -> list[tuple[int, int, float, float, float, int]]:
    """(parent, child, limit, sign, active, leg) of every stop; a leg joint needs one stop, or two at one angle (a
    locked joint: leg -1, never a phase), the hip none. ``active`` at a step's start: 1 held (the stance leg's), or
    RELEASED (held, but let go through the heel strike: ``release_at_heel_strike``), 0 free (the swing leg's)."""
    locks, released = [], set()
    for j in d.joints:
        leg = next((i for i, leg in enumerate(d.legs) if j.child in leg), None)
        if leg is None or j.parent not in d.legs[leg]:
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
        active = (RELEASED if stop.release_at_heel_strike else 1.0) if leg == 0 else 0.0
        locks.append((tree.index[j.parent], tree.index[j.child], stop.angle, sign, active, leg))
        released.add(stop.release_at_heel_strike)
    if len(released) > 1:
        raise ConfigError(
            "walker.description.joints",
            "release_at_heel_strike: rigid dynamics needs it on every leg stop or none (the legs swap roles)",
        )
    return locks


def tree_elements(tree: Tree, d: WalkerDescription) -> list[list[float]]:
    """(law, child, other, the law's parameters) of every joint element: a torque on the child's coordinate and its
    opposite on the other body's (the joint's parent, or the body it acts against; -1, the ground, takes none)."""
    return [
        [JOINT_ELEMENT_LAWS[e.law].index, child, other, *element_parameters(e.law, **e.values())]
        for child, other, e in d.element_bodies(tree.index)
    ]


def _is_odd(law: str, params: np.ndarray) -> bool:
    """The element's law turned around: its torque odd and its energy even in (theta, thetadot), so acting on the
    pair's other body it is the same element (a linear spring at rest angle 0, a damper); probed at one state."""
    registered = JOINT_ELEMENT_LAWS[law]  # its plain Python (a kernel has no Python entry point)
    function, energy = (getattr(f, "py_func", f) for f in (registered.function, registered.energy))
    theta, rate = 0.37, -1.3
    torque = function(theta, rate, params)[0]
    return math.isclose(function(-theta, -rate, params)[0], -torque, rel_tol=1e-12) and math.isclose(
        energy(-theta, params), energy(theta, params), rel_tol=1e-12
    )


def check_elements_mirrored(d: WalkerDescription, elements: list[list[float]], perm: list[int]) -> None:
    """Refuse a joint element the heel strike's relabelling would move onto another body.

    At a strike the legs swap coordinates (``perm``) while every element stays on its coordinates, so after it each
    element acts where its image under the swap would: the walker is the same only if every element's image is an
    element of the walker (a spring to each leg alike, or the element acting between the two swapped bodies with a
    law that is the same turned around). Otherwise (a hip spring with a nonzero rest angle, a torso spring to one
    leg only, a leg held against the ground) it would act on the other physical leg after every strike, which the
    compliant run does not do, and the step map of limit cycles and basins would not be one map."""
    keys = [(law, child, other, *values) for law, child, other, *values in elements]
    present = Counter(keys)
    for (joint, element, _), (law, child, other, *values) in zip(d.joint_elements(), keys, strict=True):
        image = (perm[int(child)], -1 if other < 0 else perm[int(other)])
        turned_around = image == (other, child) and _is_odd(element.law, np.array(values))
        if turned_around or present[(law, *image, *values)] > 0:
            continue
        raise ConfigError(
            "walker.description.joints",
            f"{joint.name}.{element.name}: rigid dynamics swaps the legs' coordinates at each heel strike and this "
            "element has no mirror image on the other leg, so it would act on the other leg after every strike "
            "(give the other leg the same element, or use dynamics: compliant)",
        )


def _fall_angles(tree: Tree, d: WalkerDescription, config: Config) -> list[float]:
    """Each coordinate's fall angle from the slope normal: a leg's body simulation.fall_leg_angle, a body off the
    legs (a torso) its own ``fall_angle`` (by default the same), as in compliant dynamics."""
    own = {b.name: b.fall_angle for b in d.bodies if b.name in tree.off_legs}
    angles = [own.get(name) for name in tree.order]
    return [config.simulation.fall_leg_angle if angle is None else angle for angle in angles]


def _relabelling(tree: Tree, n: int) -> tuple[list[int], list[float]]:
    """(perm, shift) of the heel strike: coordinate k after it is coordinate perm[k] before plus shift[k] (the legs
    swap; a body off them keeps its coordinate)."""
    if tree.shift:
        return [0], [tree.shift]
    half = tree.leg_size
    return [half + k for k in range(half)] + list(range(half)) + list(range(2 * half, n)), [0.0] * n


def _leg_lean(tree: Tree, n: int, locks: list) -> tuple[float, float]:
    """(depth, lean) of the stance foot's centre below the hip with the leg locked at its stops and its hip body
    vertical, and its angle from the hip body's axis (phi = atan2(d, l - R) for the compass)."""
    foot = point_of(tree, tree.at(tree.feet[0].body, tree.feet[0].centre, tree.feet[0]), n, locks)
    return -foot[1], math.atan2(foot[0], -foot[1])


def _table(items: list, dtype: np.dtype) -> np.ndarray:
    """The record array of ``items`` (tuples of the dtype's fields), its fields read as attributes."""
    return np.array(items, dtype=dtype).view(np.recarray)


def _points(tree: Tree, rows: list, light: list, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(rows, w) of both tables: each table's rows, then the hip and the landing foot (table 0's in both), then its
    light rows (:class:`~biped_sim.rigid.tree_layout.RigidTree`)."""
    marks = [(0.0, 0.0, 0, tree.origin(tree.root, tree.feet[0])),
             (0.0, 0.0, 0, tree.at(tree.feet[1].body, tree.feet[1].centre, tree.feet[0]))]  # fmt: skip
    tables = [rows[t] + marks + light[t] for t in (0, 1)]
    records = _table([[row[:3] for row in table] for table in tables], ROW).reshape(2, -1)
    w = np.array([[np.reshape(_flat(row[3], n), (n, 2)) for row in table] for table in tables]).reshape(2, -1, n, 2)
    return records, w


def _nonzero_columns(w: np.ndarray, rolling: list[int], radius: float) -> tuple[np.ndarray, np.ndarray]:
    """(columns, n_columns) of :class:`~biped_sim.rigid.tree_layout.RigidTree`: each point's coordinates whose w
    vector is nonzero, or that of the body whose foot rolls in its table (its Jacobian column has (-R, 0) too),
    descending and padded with -1; the other columns of its Jacobian are zero."""
    tables, points, n = w.shape[:3]
    columns, n_columns = np.full((tables, points, n), -1, dtype=np.int64), np.zeros((tables, points), dtype=np.int64)
    for t in range(tables):
        for i in range(points):
            nonzero = [k for k in range(n) if np.any(w[t, i, k] != 0.0) or (k == rolling[t] and radius != 0.0)]
            columns[t, i, : len(nonzero)] = nonzero[::-1]
            n_columns[t, i] = len(nonzero)
    return columns, n_columns


def tree_params(config: Config, d: WalkerDescription, gravity: float) -> RigidTree:
    """The records of the kernels (the tables, locks, phases, relabelling, elements) and their workspace."""
    tree = Tree(d)
    n = len(tree.order)
    locks = tree_locks(tree, d)
    rows = [_rows(tree, d, foot) for foot in tree.feet]
    rolling = [tree.index[foot.body] for foot in tree.feet]
    flags = [_light_flags(tree, rows[t], locks, tree.feet[t].radius, rolling[t], n) for t in (0, 1)]
    light = [_light_rows(tree, foot) for foot in tree.feet] if any(map(any, flags)) else [[], []]
    phases = [(STOP, j) for j, lock in enumerate(locks) if lock[5] == 1]
    phases += [(PAST, 0), (STRIKE, 0)] if len(d.legs) == 2 else [(STRIKE, 0)]
    perm, shift = _relabelling(tree, n)
    depth, lean = _leg_lean(tree, n, locks)
    radius = tree.feet[0].radius
    gx, gy = gravity_vector(gravity, config.ground.slope)
    elements = tree_elements(tree, d)
    check_elements_mirrored(d, elements, perm)
    records, w = _points(tree, rows, light, n)
    columns, n_columns = _nonzero_columns(w, rolling, radius)
    coords = list(zip(perm, shift, *(map(bool, f) for f in flags), _fall_angles(tree, d, config), strict=True))
    return RigidTree(
        n=n, leg_length=float(depth + radius), radius=float(radius), landing_radius=float(tree.feet[1].radius),
        lean=float(lean), gx=float(gx), gy=float(gy), fall=float(config.simulation.fall_leg_angle),
        n_points=len(rows[0]), n_light=len(light[0]), n_off=len(tree.off_legs), rolling=(rolling[0], rolling[1]),
        rows=records, w=np.ascontiguousarray(w, dtype=float), columns=columns, n_columns=n_columns,
        locks=_table([lock[:5] for lock in locks], LOCK), phases=_table(phases, PHASE),
        coords=_table(coords, COORD), elements=_table([tuple(e[:3]) for e in elements], ELEMENT),
        element_params=np.array([e[3:] for e in elements], dtype=float).reshape(len(elements), N_ELEMENT_PARAMS),
        matrix=np.zeros((n + len(locks), n + len(locks))),
        work=np.zeros(workspace_size(n, len(rows[0]), len(light[0]), len(locks))), jacobian=np.zeros((n, 2)),
        trig=np.zeros((n, 2)),
    )  # fmt: skip


def point_of(tree: Tree, w: dict[int, Vec], n: int, locks: list) -> Vec:  # type: ignore[type-arg]
    """A point's position (relative to the hip's w-sum) with every leg joint at its stop and the legs vertical."""
    angles = np.zeros(n)
    for parent, child, limit, *_ in locks:
        angles[child] = angles[parent] + limit
    return sum((_rot(angles[k], v) for k, v in w.items()), np.zeros(2)) - sum(
        (_rot(angles[k], v) for k, v in tree.origin(tree.root, tree.feet[0]).items()), np.zeros(2)
    )
