"""A described walker in the rigid model's form in space: the one builder from ``walker.description`` to the rigid
space model's data (:class:`~biped_sim.config.space_description.SpaceDescription`), and when a described walker
takes it.

The rigid model in space (:mod:`biped_sim.rigid.space_model`) takes two legs joined by one hinge about the lateral
axis z' at their hip points (``hip_width`` apart along it), the second leg the first's mirror image, each one rigid
body or a thigh and a shank on a knee about z' with one stop at the straight knee, a foot per leg on its lowest
body (a point, a ring, a sphere, a torus or an ellipsoid), a mass on the hinge's midpoint, and perhaps a torso: one
body off the legs hinged about z' at the hinge's midpoint, symmetric about the sagittal plane, its springs and
dampers paired alike against the two legs. A description of that form (its leg written once,
``walker.description.leg``, and ``hip: {lateral: -hip_width}``; a point mass on the hip bodies at ``at: [0, 0]``,
``lateral: -hip_width / 2`` is the hip's mass, one elsewhere on a body is lumped into that body) is turned into it
here; what the model lacks (a second body off the legs, an unpaired or grounded torso element, stops or springs on
the hip, a knee stop elsewhere than straight) is refused naming the field.

Frames: a body's frame is x' forward, y' up the leg, z' the walker's right; the rigid model's leg frame is x
forward, y along the hinge away from the other leg, z up the leg. The first leg (the root) lies on the side away
from the second (the hip's ``lateral`` < 0: the second to its left, so the first is the right leg and y = z';
> 0: y = -z'); its numbers, so mapped, are the left leg's that the rigid model writes (the right leg being its
mirror image, the permutation (x', z', y') of the right leg is the left leg's (x, y, z)); a ring's plane normal is so
mapped too, its sign fixed (``feet.canonical_normal``: the mirrored leg's, its z' component negated, is the same
plane). Splay is plain geometry in the description (each leg's numbers turned about x', docs/guide/rigid.md). A
rotation about the lateral axis is the same on a leg and on its mirror image, and a planar angle (about z', the
walker's right, + with the distal end forward) is minus the rigid model's about y (+ with the foot behind).
"""

from __future__ import annotations

import numpy as np
from pydantic import ValidationError

from biped_sim.config.description import BodySpec, WalkerDescription
from biped_sim.config.space_description import (
    MAX_TORSO_ELEMENTS,
    InertiaSpec,
    SpaceDescription,
    SpaceElement,
    SpaceKnee,
    SpaceLeg,
    SpaceTorso,
    Vector3,
)

WHERE = "walker.description"
FORM = "the rigid model in space takes two legs on a hip hinge"


class FormError(ValueError):
    """A description the rigid model in space cannot take: the dotted field at fault and the reason."""

    def __init__(self, field: str, reason: str) -> None:
        super().__init__(f"{field}: {reason}")
        self.field, self.reason = field, reason


def in_space(description: WalkerDescription) -> bool:
    """Whether the description has a feature only a model in space represents: a hip width or any part off the
    sagittal plane (``lateral``, ``com_lateral``), a full inertia tensor, a joint about another axis than z', a foot
    of another shape than an arc."""
    return bool(
        description.features_in_space()
        or any(j.lateral for j in description.joints)
        or any(f.lateral for f in description.feet)
        or any(p.lateral for p in description.point_masses)
        or any(b.com_lateral or b.inertia_tensor is not None for b in description.bodies)
    )


def space_form(description: WalkerDescription) -> SpaceDescription:
    """The rigid model's data of a description of its form; :class:`FormError` naming the first field it cannot
    take."""
    if len(description.legs) != 2 or any(len(leg) not in (1, 2) for leg in description.legs):
        raise FormError(f"{WHERE}.legs", f"{FORM}, each one body or a thigh and a shank on a knee")
    hip = next(j for j in description.joints if {j.parent, j.child} == {leg[0] for leg in description.legs})
    first, second = hip.parent, hip.child
    if not hip.lateral_axis:
        raise FormError(f"{WHERE}.joints.{hip.name}.axis", f"{FORM} about z' (the lateral axis)")
    if hip.at != (0.0, 0.0):
        raise FormError(f"{WHERE}.joints.{hip.name}.at", f"{FORM}: the legs' hip points on its axis (at: [0, 0])")
    if hip.stops or hip.elements:
        part = "stops" if hip.stops else "elements"
        raise FormError(f"{WHERE}.joints.{hip.name}.{part}", f"{FORM} with no {part} (they are compliant's)")
    side = 1.0 if hip.lateral <= 0.0 else -1.0  # y of the first leg along z' (away from the second)
    midpoint = 0.5 * hip.lateral
    hip_mass = 0.0
    for mass in description.point_masses:
        at = midpoint if mass.body == first else -midpoint  # the second leg's origin is at hip.lateral
        if mass.body in (first, second) and mass.at == (0.0, 0.0) and mass.lateral == at:
            hip_mass += mass.mass  # on the hinge's midpoint: the model's hip mass
    roots = {first: side, second: -side}
    left, right = (_leg(description, leg, roots[leg[0]], midpoint if leg[0] == first else -midpoint)
                   for leg in description.legs)  # fmt: skip
    if left != right:
        raise FormError(f"{WHERE}.legs", f"{FORM}, the second the first's mirror image (write it once: {WHERE}.leg)")
    torso = _torso(description, {first: midpoint, second: -midpoint})
    try:
        return SpaceDescription(hip_width=abs(hip.lateral), hip_mass=hip_mass, leg=left, torso=torso)
    except ValidationError:
        foot = next(f.name for f in description.feet if f.body == description.legs[0][-1])
        raise FormError(f"{WHERE}.feet.{foot}.centre", "the foot's bottom must be below the hip") from None


def _leg(description: WalkerDescription, names: list[str], side: float, midpoint: float) -> SpaceLeg:
    """Leg ``names`` (its thigh and shank, or its one body) and its foot as the rigid model's left leg, its
    y = ``side`` z'; the point masses on its bodies (but the hip's, on the hinge's midpoint at lateral
    ``midpoint``) lumped into them."""
    bodies = [_body(description, name, side, midpoint if k == 0 else None) for k, name in enumerate(names)]
    feet = [f for f in description.feet if f.body in names]
    if len(feet) != 1 or feet[0].body != names[-1]:
        raise FormError(f"{WHERE}.feet", f"{FORM}, one foot on each leg's lowest body ({names[-1]!r})")
    foot = feet[0].in_space(side)
    if len(names) == 1:
        mass, com, inertia = bodies[0]
        return SpaceLeg(mass=mass, com=com, inertia=inertia, foot=foot)
    at, flexion = _knee(description, names, side)
    mass, com, inertia = bodies[1]
    knee = SpaceKnee(at=at, flexion=flexion, mass=mass, com=_shifted(com, at), inertia=inertia)
    foot = foot.model_copy(update={"centre": _shifted(foot.centre, at)})
    mass, com, inertia = bodies[0]
    return SpaceLeg(mass=mass, com=com, inertia=inertia, foot=foot, knee=knee)


def _torso(description: WalkerDescription, midpoints: dict[str, float]) -> SpaceTorso | None:
    """The body off the legs, if any, as the model's torso: hinged about z' at the hinge's midpoint (``midpoints``:
    its lateral offset from each leg's root), symmetric about the sagittal plane, its elements paired alike
    against the two legs' roots (the step map's mirror needs a symmetric walker)."""
    legs = {name for leg in description.legs for name in leg}
    extra = [b.name for b in description.bodies if b.name not in legs]
    if not extra:
        return None
    where = f"{WHERE}.bodies.{extra[0]}"
    joint = next((j for j in description.joints if j.child == extra[0] and j.parent in midpoints), None)
    if len(extra) > 1 or joint is None:
        raise FormError(where, f"{FORM}, one body off the legs: a torso, a child of a leg's hip body")
    at = f"{WHERE}.joints.{joint.name}"
    if not joint.lateral_axis:
        raise FormError(f"{at}.axis", f"{FORM}: a torso about z' (the lateral axis)")
    if joint.at != (0.0, 0.0) or joint.lateral != midpoints[joint.parent]:
        raise FormError(f"{at}.at", f"{FORM}: a torso hinged at the hinge's midpoint")
    if joint.stops:
        raise FormError(f"{at}.stops", f"{FORM}: a torso's joint with no stops (they are compliant's)")
    mass, com, inertia = _body(description, extra[0], 1.0, None)
    if com[1] != 0.0 or inertia.xy != 0.0 or inertia.yz != 0.0:
        raise FormError(f"{where}.com_lateral", f"{FORM}: a torso symmetric about the sagittal plane")
    paired: dict[str, list[tuple]] = {name: [] for name in midpoints}
    for element in joint.elements:
        against = element.against or joint.parent
        if against not in paired:
            raise FormError(f"{at}.elements.{element.name}.against", f"{FORM}: a torso's elements against the legs")
        values = {k: v for k, v in element.values().items() if v is not None}
        paired[against].append((element.law, tuple(sorted(values.items()))))
    first, second = (sorted(group) for group in paired.values())
    if first != second:
        raise FormError(f"{at}.elements", f"{FORM}: a torso's elements alike against each leg (a symmetric walker)")
    if len(first) > MAX_TORSO_ELEMENTS:
        raise FormError(f"{at}.elements", f"{FORM}: a torso of at most {MAX_TORSO_ELEMENTS} elements against each leg")
    elements = tuple(SpaceElement(law=law, **dict(values)) for law, values in first)
    return SpaceTorso(mass=mass, com=(com[0], com[2]), inertia=inertia, elements=elements)


def _shifted(point: Vector3, by: Vector3) -> Vector3:
    """``point`` + ``by``: a shank's point from the knee, from the hip point."""
    return (point[0] + by[0], point[1] + by[1], point[2] + by[2])


def _knee(description: WalkerDescription, names: list[str], side: float) -> tuple[Vector3, int]:
    """The knee joining thigh ``names[0]`` to shank ``names[1]``: its point in the leg frame (the shank's
    frame's origin) and its flexion's sign (:class:`~biped_sim.config.space_description.SpaceKnee`)."""
    knee = next((j for j in description.joints if (j.parent, j.child) == tuple(names)), None)
    if knee is None:
        raise FormError(f"{WHERE}.joints", f"{FORM}: the shank {names[1]!r} a child of its thigh on a knee")
    where = f"{WHERE}.joints.{knee.name}"
    if not knee.lateral_axis:
        raise FormError(f"{where}.axis", f"{FORM}: a knee about z' (the lateral axis)")
    if len(knee.stops) != 1 or knee.stops[0].angle != 0.0:
        raise FormError(f"{where}.stops", f"{FORM}: a knee with one stop, at the straight knee (angle 0)")
    if knee.elements:
        raise FormError(f"{where}.elements", f"{FORM}: a knee with no elements (they are compliant's)")
    # a planar angle about z' is minus the angle about y (module docstring): an upper stop lets the foot swing behind
    flexion = 1 if knee.stops[0].side == "upper" else -1
    return (knee.at[0], side * knee.lateral, knee.at[1]), flexion


def _body(
    description: WalkerDescription, name: str, side: float, midpoint: float | None
) -> tuple[float, Vector3, InertiaSpec]:
    """Body ``name``'s mass, centre of mass and inertia in the leg frame (from its frame's origin, y = ``side``
    z'), the point masses on it lumped in (parallel axes), but a hip mass on the hinge's midpoint (at lateral
    ``midpoint`` of a thigh)."""
    body = next(b for b in description.bodies if b.name == name)
    turn = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, side], [0.0, 1.0, 0.0]])  # (x', y', z') -> (x, y, z)
    mass, com = body.mass, np.array([body.com[0], side * body.com_lateral, body.com[1]])
    tensor = turn @ _tensor(body) @ turn.T
    lumped = [
        (m.mass, np.array([m.at[0], side * m.lateral, m.at[1]]))
        for m in description.point_masses
        if m.body == name and not (m.at == (0.0, 0.0) and m.lateral == midpoint)
    ]
    if lumped:  # else the body's own numbers, to the bit
        parts = [(mass, com), *lumped]
        mass = sum(m for m, _ in parts)
        com = sum(m * at for m, at in parts) / mass
        for m, at in parts:
            offset = at - com
            tensor = tensor + m * (offset @ offset * np.eye(3) - np.outer(offset, offset))
    if mass <= 0.0:
        raise FormError(f"{WHERE}.bodies.{name}.mass", f"{FORM}, each body of mass > 0")
    try:
        inertia = InertiaSpec(
            xx=tensor[0, 0], yy=tensor[1, 1], zz=tensor[2, 2], xy=tensor[0, 1], xz=tensor[0, 2], yz=tensor[1, 2]
        )
    except ValidationError:
        raise FormError(f"{WHERE}.bodies.{name}.spatial_inertia", "not an inertia tensor") from None
    return mass, (float(com[0]), float(com[1]), float(com[2])), inertia


def _tensor(body: BodySpec) -> np.ndarray:
    """The body's inertia tensor about its centre of mass in its frame: ``inertia_tensor``, or ``spatial_inertia``
    (xx, yy, xy) with its moment about z', or its moment about every axis."""
    if body.inertia_tensor is not None:
        return body.inertia_tensor.matrix()
    moment = body.moment_of_inertia
    if body.spatial_inertia is None:
        return np.eye(3) * moment
    xx, yy, xy = body.spatial_inertia
    return np.array([[xx, xy, 0.0], [xy, yy, 0.0], [0.0, 0.0, moment]])
