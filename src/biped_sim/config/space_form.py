"""A described walker in the rigid model's form in space: the one builder from ``walker.description`` to the rigid
space model's data (:class:`~biped_sim.config.space_description.SpaceDescription`), and when a described walker
takes it.

The rigid model in space (:mod:`biped_sim.rigid.space_model`) takes two legs, each one rigid body, joined by one
hinge about the lateral axis z' at their hip points (``hip_width`` apart along it), the second leg the first's
mirror image, a foot per leg (a point, a ring, a sphere, a torus or an ellipsoid), and a mass on the hinge's
midpoint. A description of that form (its leg written once, ``walker.description.leg``, and ``hip: {lateral:
-hip_width}``; a point mass on the hip bodies at ``at: [0, 0]``, ``lateral: -hip_width / 2`` is the hip's mass)
is turned into it here; what the model lacks (knees, a torso, stops or springs on the hip, point masses off the
hinge) is refused naming the field.

Frames: a body's frame is x' forward, y' up the leg, z' the walker's right; the rigid model's leg frame is x
forward, y along the hinge away from the other leg, z up the leg. The first leg (the root) lies on the side away
from the second (the hip's ``lateral`` < 0: the second to its left, so the first is the right leg and y = z';
> 0: y = -z'); its numbers, so mapped, are the left leg's that the rigid model writes (the right leg being its
mirror image, the permutation (x', z', y') of the right leg is the left leg's (x, y, z)); a ring's plane normal is so
mapped too, its sign fixed (``feet.canonical_normal``: the mirrored leg's, its z' component negated, is the same
plane). Splay is plain geometry in the description (each leg's numbers turned about x', docs/guide/rigid.md).
"""

from __future__ import annotations

import numpy as np
from pydantic import ValidationError

from biped_sim.config.description import BodySpec, WalkerDescription
from biped_sim.config.space_description import InertiaSpec, SpaceDescription, SpaceLeg

WHERE = "walker.description"
FORM = "the rigid model in space takes two one-body legs on a hip hinge"


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
    if len(description.legs) != 2 or any(len(leg) != 1 for leg in description.legs):
        raise FormError(f"{WHERE}.legs", f"{FORM} (knees: dynamics: compliant)")
    legs = {name for (name,) in description.legs}
    if extra := [b.name for b in description.bodies if b.name not in legs]:
        raise FormError(f"{WHERE}.bodies.{extra[0]}", f"{FORM}, no body off the legs (a torso: dynamics: compliant)")
    hip = description.joints[0]  # the one joint of a two-body tree
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
        if mass.at != (0.0, 0.0) or mass.lateral != at:
            raise FormError(
                f"{WHERE}.point_masses.{mass.name}",
                f"{FORM}: a point mass only on the hinge's midpoint (at: [0, 0], lateral: {at:g})",
            )
        hip_mass += mass.mass
    left, right = (_leg(description, name, s) for name, s in ((first, side), (second, -side)))
    if left != right:
        raise FormError(f"{WHERE}.legs", f"{FORM}, the second the first's mirror image (write it once: {WHERE}.leg)")
    try:
        return SpaceDescription(hip_width=abs(hip.lateral), hip_mass=hip_mass, leg=left)
    except ValidationError:
        foot = next(f.name for f in description.feet if f.body == first)
        raise FormError(f"{WHERE}.feet.{foot}.centre", "the foot's bottom must be below the hip") from None


def _leg(description: WalkerDescription, name: str, side: float) -> SpaceLeg:
    """Body ``name`` and its foot as the rigid model's left leg, its y = ``side`` z'."""
    body = next(b for b in description.bodies if b.name == name)
    feet = [f for f in description.feet if f.body == name]
    if len(feet) != 1:
        raise FormError(f"{WHERE}.feet", f"{FORM}, one foot on each (body {name!r} has {len(feet)})")
    if body.mass <= 0.0:
        raise FormError(f"{WHERE}.bodies.{name}.mass", f"{FORM}, each of mass > 0")
    turn = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, side], [0.0, 1.0, 0.0]])  # (x', y', z') -> (x, y, z)
    tensor = turn @ _tensor(body) @ turn.T
    com = (body.com[0], side * body.com_lateral, body.com[1])
    try:
        inertia = InertiaSpec(
            xx=tensor[0, 0], yy=tensor[1, 1], zz=tensor[2, 2], xy=tensor[0, 1], xz=tensor[0, 2], yz=tensor[1, 2]
        )
    except ValidationError:
        raise FormError(f"{WHERE}.bodies.{name}.spatial_inertia", "not an inertia tensor") from None
    return SpaceLeg(mass=body.mass, com=com, inertia=inertia, foot=feet[0].in_space(side))


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
