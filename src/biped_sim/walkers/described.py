"""The compliant walker built from its description (a described walker's own, a bundled kind's expansion by
:func:`~biped_sim.walkers.describe.describe`): any planar tree of bodies.

The description (:class:`~biped_sim.config.description.WalkerDescription`) gives bodies in frames whose origin is the
joint to the parent (the root's: the hip), joints placing a child's origin in its parent's frame, one-sided joint stops
and passive elements (springs, dampers), feet on bodies and the legs. :func:`resolve_tree` folds the point masses into
their bodies (mass, centre of mass, parallel-axis inertia) and orders the bodies parents first;
:func:`planar_tree_system` makes the planar absolute-coordinate system of it (each body at its centre of mass, a
revolute joint per child, the hip joint first, each stop a compliant contact of :mod:`biped_sim.contact.stop` with the
law, stiffness and restitution it names and ``contact.exponent``, a latching stop released by its leg's foot; each
joint element a row of :mod:`biped_sim.contact.joint_element`), which
:func:`~biped_sim.walkers.described_start.build_described` starts rolling on its stance leg's foot.
``formulation.kind: minimal`` converts that system (:func:`~biped_sim.walkers.model.minimal_model`), so both
formulations describe one walker.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.config import Config
from biped_sim.config.description import LATERAL, WalkerDescription
from biped_sim.config.feet import FootSpec
from biped_sim.contact.joint_element import JOINT_ELEMENT_LAWS, JointElements, element_parameters, make_elements
from biped_sim.contact.normal import NORMAL_LAWS, normal_parameters
from biped_sim.contact.profile import profile_ground
from biped_sim.contact.response import BODY_TOO_FAR, LEG_TOO_FAR, NO_BODY_FALLS
from biped_sim.contact.stop import NOT_LATCHING, Stops, make_stops
from biped_sim.errors import ConfigError
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.walkers.model import (
    contact_arrays,
    contact_limits,
)


@dataclass(frozen=True)
class Tree:
    """A walker description resolved to arrays, bodies parents first (the root, body 0, first)."""

    names: list[str]
    parent: np.ndarray  # (nb,) int: -1 for the root
    joint_at: np.ndarray  # (nb, 2) the body's origin in its parent's frame (root: 0)
    mass: np.ndarray  # (nb,) with its point masses
    com: np.ndarray  # (nb, 2) centre of mass in the body frame (from the origin)
    inertia: np.ndarray  # (nb,) about the centre of mass
    spatial_inertia: np.ndarray  # (nb, 3, 3) about the centre of mass in the body frame (z' the joints' axis)
    stops: list[tuple[int, int, str, float, str, float, float, bool]]  # parent, child, side, angle, law, K, e, latch
    elements: list[tuple[int, int, str, np.ndarray]]  # child, the body it acts against (-1: ground), law, parameters
    fall_angle: list[float | None]  # per body: its own fall angle (a body off the legs), else None
    foot_body: np.ndarray  # (nf,) int
    foot_centre: np.ndarray  # (nf, 2) in the body frame
    foot_radius: np.ndarray  # (nf,)
    foot_lateral: np.ndarray  # (nf,) along the joints' axis (the spatial formulation's)
    joint_lateral: np.ndarray  # (nb,) each body's origin along z' from its joint's ``at`` (the spatial formulation's)
    foot_names: list[str]
    legs: list[list[int]]  # body indices, hip down
    com_lateral: np.ndarray  # (nb,) centre of mass along z' from the body's origin (the spatial formulation's)
    joint_axis: np.ndarray  # (nb, 3) the axis of the body's joint in its parent's frame (root: z')
    foot_hertz: np.ndarray  # (nf,) the radius of Hertz's sphere at each foot's bottom (an arc's: its radius)
    foot_shape: np.ndarray  # (nf, 16) the spatial formulation's foot (:func:`foot_in_space`)


def _tree_order(description: WalkerDescription) -> list[str]:
    """The body names, parents before children, otherwise in the description's order."""
    parent = {j.child: j.parent for j in description.joints}
    order = [description.bodies[0].name]
    while len(order) < len(description.bodies):
        order += [b.name for b in description.bodies if b.name not in order and parent.get(b.name) in order]
    return order


def _fold(description: WalkerDescription, name: str) -> tuple[float, np.ndarray, float]:
    """(mass, centre of mass, inertia about it) of body ``name`` with its point masses."""
    body = next(b for b in description.bodies if b.name == name)
    parts = [(body.mass, np.array(body.com))] + [
        (p.mass, np.array(p.at)) for p in description.point_masses if p.body == name
    ]
    mass = sum(m for m, _ in parts)
    if mass <= 0.0:
        raise ConfigError(f"walker.description.bodies.{name}.mass", "a body needs mass (its own or a point mass)")
    com = sum(m * r for m, r in parts) / mass
    inertia = body.moment_of_inertia + sum(m * float((r[0] - com[0]) ** 2 + (r[1] - com[1]) ** 2) for m, r in parts)
    return mass, com, inertia


def _spatial_inertia(description: WalkerDescription, name: str, com: np.ndarray, inertia: float) -> np.ndarray:
    """Body ``name``'s inertia tensor about its folded centre of mass ``com`` (3, 3): its ``spatial_inertia`` with
    its parts added by parallel axes (all in the sagittal plane z' = 0), ``inertia`` (the folded moment) about z';
    none given, ``inertia`` about every axis; its ``inertia_tensor`` or a centre of mass off the plane
    (:func:`_tensor_in_space`)."""
    body = next(b for b in description.bodies if b.name == name)
    laterals = [body.com_lateral] + [p.lateral for p in description.point_masses if p.body == name]
    if body.inertia_tensor is not None or any(laterals):
        return _tensor_in_space(description, name)
    if body.spatial_inertia is None:
        return np.eye(3) * inertia
    xx, yy, xy = body.spatial_inertia
    parts = [(body.mass, np.array(body.com))] + [(p.mass, np.array(p.at)) for p in description.point_masses
                                                   if p.body == name]  # fmt: skip
    for m, r in parts:
        dx, dy = r - com
        xx, yy, xy = xx + m * dy**2, yy + m * dx**2, xy - m * dx * dy
    return np.array([[xx, xy, 0.0], [xy, yy, 0.0], [0.0, 0.0, inertia]])


def _tensor_in_space(description: WalkerDescription, name: str) -> np.ndarray:
    """Body ``name``'s inertia tensor about its folded centre of mass in space (the point masses at their lateral): its
    ``inertia_tensor`` (or its moment about every axis) and each part's m (|d|^2 1 - d d^T)."""
    body = next(b for b in description.bodies if b.name == name)
    own = body.inertia_tensor.matrix() if body.inertia_tensor is not None else np.eye(3) * body.moment_of_inertia
    parts = [(body.mass, np.array([*body.com, body.com_lateral]))] + [
        (p.mass, np.array([*p.at, p.lateral])) for p in description.point_masses if p.body == name
    ]
    com = sum(m * r for m, r in parts) / sum(m for m, _ in parts)
    return own + sum(m * ((r - com) @ (r - com) * np.eye(3) - np.outer(r - com, r - com)) for m, r in parts)


def resolve_tree(description: WalkerDescription) -> Tree:
    """The description as arrays (:class:`Tree`)."""
    names = _tree_order(description)
    index = {name: k for k, name in enumerate(names)}
    nb = len(names)
    parent, joint_at, joint_lateral = np.full(nb, -1, dtype=np.int64), np.zeros((nb, 2)), np.zeros(nb)
    stops = []
    for joint in description.joints:
        c = index[joint.child]
        parent[c], joint_at[c], joint_lateral[c] = index[joint.parent], joint.at, joint.lateral
        stops += [(parent[c], c, s.side, s.angle, s.model, s.stiffness, s.restitution, s.latch) for s in joint.stops]
    folded = [_fold(description, name) for name in names]
    feet = description.feet
    return Tree(
        names=names,
        parent=parent,
        joint_at=joint_at,
        mass=np.array([f[0] for f in folded]),
        com=np.array([f[1] for f in folded]),
        inertia=np.array([f[2] for f in folded]),
        spatial_inertia=np.array(
            [_spatial_inertia(description, n, com, j) for n, (_, com, j) in zip(names, folded, strict=True)]
        ),
        stops=sorted(stops, key=lambda s: s[1]),
        elements=[
            (child, other, e.law, element_parameters(e.law, **e.values()))
            for child, other, e in description.element_bodies(index)
        ],
        foot_body=np.array([index[f.body] for f in feet], dtype=np.int64),
        foot_centre=np.array([f.sagittal_arc()[0] for f in feet], dtype=np.float64).reshape(-1, 2),
        foot_radius=np.array([f.sagittal_arc()[1] for f in feet]),
        foot_lateral=np.array([f.lateral for f in feet]),
        joint_lateral=joint_lateral,
        foot_names=[f.name for f in feet],
        com_lateral=np.array([_com_lateral(description, name) for name in names]),
        joint_axis=np.array([_axis(description, name) for name in names]),
        foot_shape=np.array([foot_in_space(f) for f in feet]).reshape(-1, 16),
        foot_hertz=np.array([f.in_space().hertz_radius for f in feet]),
        legs=[[index[b] for b in leg] for leg in description.legs],
        fall_angle=[next(b.fall_angle for b in description.bodies if b.name == name) for name in names],
    )


def foot_in_space(foot: FootSpec) -> np.ndarray:
    """(16,): the foot's centre (x', y'), disc axis (an arc's or torus's plane normal, z' unless given otherwise; 0
    for a sphere or an ellipsoid), radius, tube and quadric (an ellipsoid's diag(ax^2, ay^2, az^2), else 0)."""
    axis = (0.0,) * 3 if foot.shape in ("sphere", "ellipsoid") else foot.plane_normal
    quadric = np.diag(np.square(foot.axes)) if foot.axes is not None else np.zeros((3, 3))
    return np.array([*foot.centre, *axis, foot.radius, foot.tube, *quadric.ravel()])


def _com_lateral(description: WalkerDescription, name: str) -> float:
    """Body ``name``'s folded centre of mass along z' (its point masses at their ``lateral``)."""
    body = next(b for b in description.bodies if b.name == name)
    masses = [p for p in description.point_masses if p.body == name]
    moment = body.mass * body.com_lateral + sum(p.mass * p.lateral for p in masses)
    return moment / (body.mass + sum(p.mass for p in masses)) if moment else 0.0


def _axis(description: WalkerDescription, name: str) -> np.ndarray:
    """The unit axis of body ``name``'s joint in its parent's frame (the root's: z')."""
    axis = np.array(next((j.axis for j in description.joints if j.child == name), LATERAL), dtype=np.float64)
    return axis / np.linalg.norm(axis)


def rotate(phi: float, v: np.ndarray) -> np.ndarray:
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def leg_feet(tree: Tree) -> list[list[int]]:
    """The feet of each leg."""
    return [[i for i, b in enumerate(tree.foot_body) if b in leg] for leg in tree.legs]


def stance_feet(tree: Tree) -> tuple[int, ...]:
    """The feet the walker starts on: the first foot of the stance leg's last body and each of that body's feet at
    the same sagittal place (the four-legged machine's pair stands on two feet, which share its weight)."""
    first = next(i for i in leg_feet(tree)[0] if tree.foot_body[i] == tree.legs[0][-1])
    return tuple(
        i
        for i in leg_feet(tree)[0]
        if tree.foot_body[i] == tree.foot_body[first]
        and tree.foot_radius[i] == tree.foot_radius[first]
        and np.array_equal(tree.foot_centre[i], tree.foot_centre[first])
    )


def foot_partners(tree: Tree) -> np.ndarray:
    """Each foot's partner: the other leg's foot of the same rank on its leg (the four-legged machine's foot on the
    same side), else its first; -1 without two legs or for a foot off the legs."""
    partner = np.full(len(tree.foot_names), -1, dtype=np.int64)
    feet = leg_feet(tree)
    if len(tree.legs) == 2 and all(feet):
        for leg, other in ((0, 1), (1, 0)):
            for k, foot in enumerate(feet[leg]):
                partner[foot] = feet[other][k if k < len(feet[other]) else 0]
    return partner


def planar_stops(tree: Tree, config: Config, length: float) -> Stops:
    """The joint stops as compliant contacts: indices of the bodies' angles and rates in the planar state, side,
    limit and rate floor (``contact.impact_velocity_floor`` over the leg length), law and parameters
    (``contact.exponent``; Kelvin-Voigt's damping from the child's inertia about the joint), latches."""
    nb = len(tree.names)
    rows = [[3 * c + 2, 3 * p + 2, 3 * nb + 3 * c + 2, 3 * nb + 3 * p + 2] for p, c, *_ in tree.stops]
    floor = config.contact.impact_velocity_floor / length
    limits = [[1.0 if side == "upper" else -1.0, angle, floor] for _, _, side, angle, *_ in tree.stops]
    params = [
        normal_parameters(
            law, k, config.contact.exponent, e, None, tree.inertia[c] + tree.mass[c] * tree.com[c] @ tree.com[c]
        )
        for _, c, _, _, law, k, e, _ in tree.stops
    ]
    laws = [NORMAL_LAWS[law].index for *_, law, _, _, _ in tree.stops]
    return make_stops(np.array(rows), np.array(limits), np.array(laws), np.array(params), latch_feet(tree))


def planar_elements(tree: Tree) -> JointElements:
    """The joint elements: indices of their two bodies' angles and rates in the planar state (-1: the ground),
    laws, parameters."""
    nb = len(tree.names)
    rows = [[3 * c + 2, 3 * a + 2, 3 * nb + 3 * c + 2, 3 * nb + 3 * a + 2] if a >= 0 else
            [3 * c + 2, -1, 3 * nb + 3 * c + 2, -1] for c, a, _, _ in tree.elements]  # fmt: skip
    laws = [JOINT_ELEMENT_LAWS[law].index for _, _, law, _ in tree.elements]
    return make_elements(np.array(rows), np.array(laws), np.array([p for *_, p in tree.elements]))


def fall_angles(tree: Tree, config: Config) -> np.ndarray:
    """(nb,): the angle from the slope normal past which each body has fallen [rad]: a leg's body
    ``simulation.fall_leg_angle``, a body off the legs its own ``fall_angle`` (by default the same)."""
    return np.array([config.simulation.fall_leg_angle if angle is None else angle for angle in tree.fall_angle])


def body_falls(tree: Tree, config: Config) -> np.ndarray:
    """The system's ``body_falls``: none when every body is on a leg (each falls as a leg), else per body its fall
    angle and code (LEG_TOO_FAR, or BODY_TOO_FAR + b for body b off the legs: the run's reason names it)."""
    on_legs = {b for leg in tree.legs for b in leg}
    if len(on_legs) == len(tree.names):
        return NO_BODY_FALLS
    codes = [LEG_TOO_FAR if b in on_legs else BODY_TOO_FAR + b for b in range(len(tree.names))]
    return np.column_stack([fall_angles(tree, config), np.array(codes, dtype=np.float64)])


def latch_feet(tree: Tree) -> np.ndarray:
    """(ns, 2): each latching stop's FOOT, the first of the leg holding its joint (whose toe-off begins the
    release), and PARTNER, the other leg's first foot (whose strike the release waits out); NOT_LATCHING for a
    plain stop (the description checks that a latching stop's leg has a foot, and that there are two legs)."""
    feet = leg_feet(tree)
    leg_of = {b: k for k, leg in enumerate(tree.legs) for b in leg}
    rows = [
        [feet[leg_of[c]][0], feet[1 - leg_of[c]][0]] if latch else [NOT_LATCHING, NOT_LATCHING]
        for _, c, *_, latch in tree.stops
    ]
    return np.array(rows, dtype=np.int64).reshape(-1, 2)


def planar_tree_system(tree: Tree, config: Config, stiffness: float, length: float) -> PlanarSystem:
    """The planar absolute-coordinate system of ``tree``: bodies at their centres of mass, a revolute joint per
    child (parent, child; the joints at the hip first, so that joint 0 is the hip), the feet, the stops."""
    if np.any(tree.inertia <= 0.0):
        name = tree.names[int(np.argmax(tree.inertia <= 0.0))]
        raise ConfigError(
            f"walker.description.bodies.{name}.inertia",
            "absolute coordinates need each body's inertia about its centre of mass > 0 (use formulation.kind: "
            "minimal, or give it its inertia)",
        )
    children = sorted(range(1, len(tree.names)), key=lambda b: (tree.parent[b] != 0 or np.any(tree.joint_at[b]), b))
    joints = np.array([[tree.parent[b], b] for b in children], dtype=np.int64).reshape(-1, 2)
    points = np.array(
        [[*(tree.joint_at[b] - tree.com[tree.parent[b]]), *(0.0 - tree.com[b])] for b in children]
    ).reshape(-1, 4)
    g, gamma = config.gravity, config.ground.slope
    normal, friction, switches = contact_arrays(config, stiffness, float(np.sum(tree.mass)))
    return PlanarSystem(
        body_mass=tree.mass.copy(),
        body_inertia=tree.inertia.copy(),
        joint_bodies=joints,
        joint_points=points,
        foot_body=tree.foot_body.copy(),
        foot_center=tree.foot_centre - tree.com[tree.foot_body],
        foot_radius=tree.foot_radius.copy(),
        foot_partner=foot_partners(tree),
        gravity=np.array([g * math.sin(gamma), -g * math.cos(gamma)]),
        baumgarte=np.array([config.formulation.baumgarte.alpha, config.formulation.baumgarte.beta]),
        normal_params=normal,
        friction_params=friction,
        switches=switches,
        limits=contact_limits(config, length),
        ground=profile_ground(config.ground.profile, gamma),
        stops=planar_stops(tree, config, length),
        elements=planar_elements(tree),
        body_falls=body_falls(tree, config),
    )
