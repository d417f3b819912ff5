"""A walker's description in the spatial formulation (the compass, Liu's four-legged machine), and the pieces every
spatial builder shares.

Body frames: x' forward, y' along the leg towards the hip, z' lateral (the hip axle), so that a
rotation phi about z' is the planar leg angle. A planar state (x, y, phi) maps to r = (x, y, 0),
p = (cos phi/2, 0, 0, sin phi/2) and omega = (0, 0, phidot) to pdot = (omega/2) (-sin phi/2, 0, 0, cos phi/2).

:func:`spatial_described` lifts the description's planar model (:mod:`biped_sim.walkers.described`: same bodies,
same initial state, converted): disc feet in their bodies' sagittal planes at their ``lateral`` places, a revolute
joint (a SPHERICAL and two PERPENDICULAR primitives) per planar joint. A walker whose feet all lie in its
sagittal plane (the compass) also has a planar joint from its root to the ground frame (IN_PLANE z = 0 and the
root's axle perpendicular to x and y): its motion stays in the sagittal plane by construction, not only by
symmetry, so that a lateral round-off never grows (a single disc foot is laterally unstable); its bodies'
inertias about x' and y' do not act and are taken equal to the sagittal one so that the mass matrix is well
conditioned. A walker standing on feet apart (the four-legged machine's pairs, two feet each) has no such joint:
roll and yaw are free, and its bodies' ``spatial_inertia`` acts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from biped_sim.config import Config, InitialState
from biped_sim.errors import ConfigError
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.multibody.hinge import FRAME, hinge_index, make_hinge_elements, make_hinge_stops
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.spatial import IN_PLANE, PERPENDICULAR, SPHERICAL, SpatialSystem
from biped_sim.walkers.describe import describe
from biped_sim.walkers.described import Tree, resolve_tree
from biped_sim.walkers.described_start import described_start, settle_start_modes
from biped_sim.walkers.model import BuiltModel
from biped_sim.walkers.space_start import held_initial, turn_joints

X, Y, Z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)


def across(axis: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Two unit vectors u, v = axis x u perpendicular to the unit ``axis`` (z': x', y'; else u from x', or y' for an
    axis along x')."""
    u = np.array(X) - axis[0] * axis
    u = u if np.linalg.norm(u) > 1e-6 else np.array(Y) - axis[1] * axis
    u /= np.linalg.norm(u)
    return tuple(u), tuple(np.cross(axis, u))


def revolute(
    body_a: int, point_a: tuple[float, ...], body_b: int, point_b: tuple[float, ...], axis: tuple[float, ...] = Z
) -> list[tuple[int, int, int, tuple[float, ...]]]:
    """Revolute joint about ``axis`` (body a's frame, body b's alike at the joint's zero) at the point ``point_a``
    of body a and ``point_b`` of body b: the two points coincide, body a's two vectors across the axis stay
    perpendicular to body b's axis."""
    u, v = across(np.asarray(axis, dtype=np.float64))
    axis = tuple(float(a) for a in axis)
    return [
        (SPHERICAL, body_a, body_b, (*point_a, *point_b, 0.0)),
        (PERPENDICULAR, body_a, body_b, (*u, *axis, 0.0)),
        (PERPENDICULAR, body_a, body_b, (*v, *axis, 0.0)),
    ]


def planar_to_ground(body: int) -> list[tuple[int, int, int, tuple[float, ...]]]:
    """Planar joint of ``body`` to the ground frame: centre of mass in z = 0, axle z' along z."""
    return [
        (IN_PLANE, body, -1, (0.0, 0.0, 0.0, *Z, 0.0)),
        (PERPENDICULAR, body, -1, (*Z, *X, 0.0)),
        (PERPENDICULAR, body, -1, (*Z, *Y, 0.0)),
    ]


def jointed_bodies(
    inertia: np.ndarray, primitives: list[tuple[int, int, int, tuple[float, ...]]]
) -> dict[str, np.ndarray]:
    """The :class:`SpatialSystem` fields of bodies of ``inertia`` (nb, 3, 3) joined by ``primitives``, a list of
    (type, body a, body b, 7 numbers): the inertias and their inverses, and the constraint arrays."""
    kinds = np.array([kind for kind, _, _, _ in primitives], dtype=np.int64)
    return {
        "body_inertia": inertia,
        "body_inertia_inv": np.linalg.inv(inertia),
        "con_type": kinds,
        "con_bodies": np.array([[a, b] for _, a, b, _ in primitives], dtype=np.int64),
        "con_vecs": np.array([vec for _, _, _, vec in primitives], dtype=np.float64),
        "con_row": np.concatenate([[0], np.cumsum(np.where(kinds == SPHERICAL, 3, 1))[:-1]]).astype(np.int64),
    }


def sagittal_to_spatial(coords: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Planar (x, y, phi) and rates per body, (nb, 3) each, as spatial (r, p) and (rdot, pdot), (nb, 7) each."""
    q = np.zeros((len(coords), 7))
    qd = np.zeros((len(coords), 7))
    for b, ((x, y, phi), (vx, vy, omega)) in enumerate(zip(coords, rates, strict=True)):
        c, s = math.cos(0.5 * phi), math.sin(0.5 * phi)
        q[b] = [x, y, 0.0, c, 0.0, 0.0, s]
        qd[b] = [vx, vy, 0.0, -0.5 * omega * s, 0.0, 0.0, 0.5 * omega * c]
    return q, qd


def spatial_gravity(config: Config) -> np.ndarray:
    """Gravity in the slope frame: g (sin gamma, -cos gamma, 0)."""
    g, gamma = config.gravity, config.ground.slope
    return np.array([g * math.sin(gamma), -g * math.cos(gamma), 0.0])


def spatial_described(config: Config, initial: InitialState | Mapping[str, float]) -> BuiltModel:
    """The walker's description in Euler parameters: its planar model (:func:`~.described_start.described_start`, same
    bodies, feet and start) lifted, each foot at its ``lateral`` place, each body with its spatial inertia, a
    revolute joint per planar joint; a walker with every foot in its sagittal plane also held in it by a planar
    joint of its root to the ground frame (a single disc foot is laterally unstable), one standing on feet apart
    free in roll and yaw. The start's modes are settled in space, on the lifted start."""
    description = describe(config)
    tree = resolve_tree(description)
    start = described_start(config, held_initial(tree, initial, description.state_keys()))
    planar = start.model
    ps = planar.system
    nb = planar.n_bodies
    points = joint_points(tree, ps)
    primitives = [
        p for (a, b), (s_a, s_b) in zip(ps.joint_bodies, points, strict=True)
        for p in revolute(int(a), s_a, int(b), s_b, tuple(tree.joint_axis[int(b)]))
    ]  # fmt: skip
    lateral = lateral_places(tree)
    if not np.any(lateral[tree.foot_body] + tree.foot_lateral) and tree.com_lateral[0] == 0.0:
        primitives += planar_to_ground(0)
    inertia = tree.spatial_inertia
    if bad := [name for name, j in zip(tree.names, inertia, strict=True) if np.linalg.eigvalsh(j).min() <= 0.0]:
        raise ConfigError(f"walker.description.bodies.{bad[0]}.spatial_inertia", "must be positive definite")
    system = SpatialSystem(
        body_mass=ps.body_mass.copy(),
        **jointed_bodies(inertia, primitives),
        foot_body=ps.foot_body.copy(),
        foot_center=np.column_stack(
            [tree.foot_shape[:, :2] - tree.com[tree.foot_body], tree.foot_lateral - tree.com_lateral[tree.foot_body]]
        ),
        foot_axis=tree.foot_shape[:, 2:5].copy(),
        foot_radius=tree.foot_shape[:, 5].copy(),
        foot_tube=tree.foot_shape[:, 6].copy(),
        foot_quadric=tree.foot_shape[:, 7:].reshape(-1, 3, 3).copy(),
        foot_partner=ps.foot_partner.copy(),
        gravity=spatial_gravity(config),
        baumgarte=ps.baumgarte.copy(),
        normal_params=ps.normal_params,
        friction_params=ps.friction_params,
        switches=ps.switches,
        limits=ps.limits.copy(),
        stops=make_hinge_stops(
            ps.stops,
            _hinge_rows([(p, c) for p, c, *_ in tree.stops], nb),
            _frames(tree, [c for _, c, *_ in tree.stops]),
        ),
        elements=make_hinge_elements(
            ps.elements,
            _hinge_rows([(a, c) for c, a, *_ in tree.elements], nb),
            _frames(tree, [c for c, *_ in tree.elements]),
        ),
        ground=ps.ground,
    )
    q, qd = _spatial_state(planar, lateral + tree.com_lateral)
    on_parent = {int(b): np.array(s_a) for (_, b), (s_a, _) in zip(ps.joint_bodies, points, strict=True)}
    turn_joints(tree, description.state_keys(), initial, on_parent, q, qd)
    y0 = _state_vector(planar, system, q, qd)
    settle_start_modes(start, system, y0)  # in space: the planar model's update would compile for it alone
    return replace(planar, system=system, y0=y0)


def joint_points(tree: Tree, planar: PlanarSystem) -> list[tuple[tuple[float, ...], tuple[float, ...]]]:
    """Each joint's point on its parent and on its child from their centres of mass, body frames (the planar
    system's joints' order): the planar points, along z' the child's ``lateral`` offset and the centres of mass'
    ``com_lateral``."""
    return [
        (
            (float(xa), float(ya), tree.joint_lateral[b] - tree.com_lateral[a]),
            (float(xb), float(yb), 0.0 - tree.com_lateral[b]),
        )
        for (a, b), (xa, ya, xb, yb) in zip(planar.joint_bodies, planar.joint_points, strict=True)
    ]


def lateral_places(tree: Tree) -> np.ndarray:
    """(nb,): each body's centre of mass along z from the root's, the joints' ``lateral`` offsets summed down the
    tree (its bodies are in tree order: parents first)."""
    places = np.zeros(len(tree.names))
    for c in range(1, len(tree.names)):
        places[c] = places[tree.parent[c]] + tree.joint_lateral[c]
    return places


def _hinge_rows(pairs: list[tuple[int, int]], n_bodies: int) -> np.ndarray:
    """The spatial ``index`` rows of the joints between (other body, child) pairs (-1: the ground)."""
    return np.array([hinge_index(c, a, n_bodies) for a, c in pairs], dtype=np.int64).reshape(-1, 4)


def _frames(tree: Tree, children: list[int]) -> np.ndarray:
    """The hinge frames of the joints of these children: the joint's axis and a reference across it, alike in both
    bodies' frames (z' and x' for a planar joint: theta = phi_c - phi_p)."""
    rows = [[*tree.joint_axis[c], *across(tree.joint_axis[c])[0], *across(tree.joint_axis[c])[0]] for c in children]
    return np.array(rows, dtype=np.float64).reshape(-1, FRAME)


def _spatial_state(planar: BuiltModel, lateral: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The planar model's start as spatial (q, qd), one row per body, each body's centre of mass at its ``lateral``
    place."""
    planar_layout = formulation_of(planar.system).layout_of(planar.system)
    nb = planar.n_bodies
    q, qd = sagittal_to_spatial(
        np.array([planar.y0[planar_layout.position(b)] for b in range(nb)]),
        np.array([planar.y0[planar_layout.velocity(b)] for b in range(nb)]),
    )
    q[:, 2] = lateral
    return q, qd


def _state_vector(planar: BuiltModel, system: SpatialSystem, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """The spatial system's state of bodies (q, qd) and the planar start's bristles (which run along x)."""
    planar_layout, layout = (formulation_of(s).layout_of(s) for s in (planar.system, system))
    nb, nf = planar.n_bodies, planar.n_feet
    y0 = np.zeros(layout.size)
    for b in range(nb):
        y0[layout.position(b)] = q[b]
        y0[layout.velocity(b)] = qd[b]
    for foot in range(nf):
        y0[layout.bristle(foot).start] = planar.y0[planar_layout.bristle(foot).start]
    return y0
