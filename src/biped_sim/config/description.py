"""The walker description: a walker as data, a planar tree of rigid bodies joined by revolute joints (with
one-sided stops), its feet and its legs (``walker.kind: description``; the bundled kinds expand into it)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Literal

from pydantic import Field, model_validator

from biped_sim.config.base import IN_SPACE, NormalModelName, Strict, Vector2
from biped_sim.config.feet import FootSpec
from biped_sim.config.space_description import InertiaSpec, Vector3
from biped_sim.contact.joint_element import ELEMENT_PARAMETERS, JOINT_ELEMENT_LAWS

SIDES = ("stance", "swing")
JointElementName = Literal[tuple(JOINT_ELEMENT_LAWS)]  # type: ignore[valid-type]
GROUND = "ground"  # an element's ``against`` for the slope normal (body -1 to the kernels): it holds an absolute angle
MAX_PARTS = 1000  # bodies, point masses, joints, feet or legs of a description: more is a generated typo, refused
LATERAL = (0.0, 0.0, 1.0)  # the joints' default axis z' (the walker's right): a planar walker's hinges


def leg_keys(n_legs: int, roles: list[str]) -> tuple[str, ...]:
    """Initial-state keys of ``n_legs`` legs (stance, then swing) with these body roles ('' for a one-body leg):
    per leg and body, angle then rate (the README's order)."""
    prefixes = [""] if roles == [""] else [f"{role}_" for role in roles]
    return tuple(
        f"{side}_{p}{what}" for side in SIDES[: min(n_legs, 2)] for p in prefixes for what in ("angle", "rate")
    )


def angles_then_rates(keys: tuple[str, ...]) -> tuple[str, ...]:
    """The state-vector order of the keys: every angle, then every rate (stance first)."""
    return tuple(k for k in keys if k.endswith("_angle")) + tuple(k for k in keys if k.endswith("_rate"))


LEG_KEYS = leg_keys(2, [""])  # stance_angle, stance_rate, swing_angle, swing_rate: a two-legged walker's keys
STATE_KEYS = angles_then_rates(LEG_KEYS)  # the rigid state vector's and the touchdown's order


class BodySpec(Strict):
    """A rigid body of a walker's tree (its frame: origin at its joint to the parent, -y along it to the foot)."""

    name: str = Field(..., min_length=1, description="Unique body name.")
    mass: float = Field(..., ge=0, description="Mass [kg].")
    inertia: float | None = Field(
        None, ge=0, description="Moment of inertia about its centre of mass [kg m^2] (none given: 0)."
    )
    radius_of_gyration: float | None = Field(
        None, ge=0, description="Or its radius of gyration about the centre of mass [m]: inertia = mass r^2."
    )
    com: Vector2 = Field((0.0, 0.0), description="Centre of mass in the body frame [m]: (across + downhill, along).")
    spatial_inertia: tuple[float, float, float] | None = Field(
        None,
        description="The spatial formulation's inertia about the centre of mass across the sagittal plane: the "
        "moments about the body's x and y axes and the tensor's xy entry (xx, yy, xy) [kg m^2], its point masses "
        "added by parallel axes; none given: the moment of inertia about every axis (a walker kept planar).",
    )
    inertia_tensor: InertiaSpec | None = Field(
        None,
        description="The full inertia tensor about the centre of mass in the body frame (x' forward, y' up the body, "
        "z' the walker's right) [kg m^2], its point masses added by parallel axes; its zz is the body's moment in "
        "the plane (instead of inertia, radius_of_gyration or spatial_inertia).",
    )
    com_lateral: float = Field(
        0.0,
        description="The spatial formulation's centre of mass along z' from the body's origin [m] (a planar model "
        "puts every body in the sagittal plane); the mirrored leg's is negated.",
    )
    fall_angle: float | None = Field(
        None,
        gt=0,
        description="A body off the legs (a torso): the walker has fallen when the body is this far from the slope "
        "normal [rad] (none given: simulation.fall_leg_angle); the legs' bodies fall past simulation.fall_leg_angle.",
    )

    @model_validator(mode="after")
    def _one_inertia(self) -> BodySpec:
        if self.inertia is not None and self.radius_of_gyration is not None:
            raise ValueError("radius_of_gyration: give inertia or radius_of_gyration, not both")
        others = (self.inertia, self.radius_of_gyration, self.spatial_inertia)
        if self.inertia_tensor is not None and any(v is not None for v in others):
            raise ValueError("inertia_tensor: the full tensor replaces inertia, radius_of_gyration and spatial_inertia")
        return self

    @property
    def moment_of_inertia(self) -> float:
        """The moment of inertia about the centre of mass [kg m^2] (about z'): ``inertia``, or mass r^2, or the
        tensor's zz, or 0."""
        if self.inertia_tensor is not None:
            return self.inertia_tensor.matrix()[2, 2]
        if self.radius_of_gyration is not None:
            return self.mass * self.radius_of_gyration**2
        return self.inertia or 0.0


class PointMassSpec(Strict):
    """A point mass fixed on a body (folded into it: mass, centre of mass, parallel-axis inertia)."""

    name: str = Field(..., min_length=1, description="Unique name.")
    body: str = Field(..., description="The body carrying it.")
    at: Vector2 = Field((0.0, 0.0), description="Where, in the body frame [m].")
    lateral: float = Field(0.0, description="In space: its place along z' [m] (the mirrored leg's negated).")
    mass: float = Field(..., ge=0, description="Mass [kg].")


class StopSpec(Strict):
    """A one-sided limit of a joint's relative angle (child angle - parent angle), e.g. a knee's hyperextension;
    optionally latching (a knee latch, as on McGeer's machines and in Chen's model: the straight stance knee)."""

    side: Literal["upper", "lower"] = Field(..., description="'upper': angle <= limit; 'lower': angle >= limit.")
    angle: float = Field(0.0, description="The limit [rad].")
    model: NormalModelName = Field(
        "hunt_crossley", description="Compliant dynamics: the normal law of the stop (rigid: a plastic strike)."
    )
    stiffness: float = Field(1.0e4, gt=0, description="Compliant dynamics: the stop's stiffness [N m/rad^n].")
    restitution: float = Field(0.0, ge=0, le=1, description="Compliant dynamics: the stop's restitution.")
    latch: bool = Field(
        False,
        description="Compliant dynamics: a latch engages when the stop is struck (and at the start on the stance "
        "leg) and holds the joint at its limit from both sides with the stop's law until the leg's foot leaves the "
        "ground behind the other leg's; only for a joint within one leg (a knee) of a two-legged walker whose leg "
        "has a foot. Rigid dynamics locks a struck stop until its leg swings again, latch or not.",
    )
    release_at_heel_strike: bool = Field(
        False,
        description="Rigid dynamics: the trailing leg's stop lets go at the heel strike, its joint free through the "
        "strike's impulse (McGeer's free trailing knee; the section gains the new swing leg's rates below its hip "
        "body); default: held through the strike. Set it on both legs' stops alike.",
    )


class ElementSpec(Strict):
    """A passive element of a joint (:mod:`biped_sim.contact.joint_element`): a torque between the joint's child
    and its parent (or ``against``, another body) from their relative angle theta = child angle - its angle."""

    name: str = Field(..., min_length=1, description="Element name, unique on its joint (dotted keys use it).")
    law: JointElementName = Field(..., description="The element's law: linear_spring or linear_damper.")
    stiffness: float | None = Field(
        None, ge=0, description="A spring's stiffness k [N m/rad]: tau = -k (theta - theta_0)."
    )
    rest_angle: float | None = Field(None, description="A spring's rest angle theta_0 [rad] (none given: 0).")
    damping: float | None = Field(None, ge=0, description="A damper's coefficient c [N m s/rad]: tau = -c thetadot.")
    against: str | None = Field(
        None,
        description="The body the element acts against instead of the joint's parent, usually one hinged at the "
        "same point (a torso's spring to the other leg); the torque is a couple on the two bodies either way. "
        "`ground`: the slope normal, theta the child's absolute angle (a torso held in the world, as by a "
        "controller; the torque's reaction goes to the ground).",
    )

    @model_validator(mode="after")
    def _the_law_s_parameters(self) -> ElementSpec:
        law = JOINT_ELEMENT_LAWS[self.law]
        for name in law.needs:
            if getattr(self, name) is None:
                raise ValueError(f"{name}: a {self.law} needs it")
        for name in ELEMENT_PARAMETERS:
            if getattr(self, name) is not None and name not in law.reads:
                raise ValueError(f"{name}: a {self.law} reads only {', '.join(law.reads)}")
        return self

    def values(self) -> dict[str, float | None]:
        """The law's parameters by name (for :func:`~biped_sim.contact.joint_element.element_parameters`)."""
        return {name: getattr(self, name) for name in ELEMENT_PARAMETERS}


class JointSpec(Strict):
    """A revolute joint: the child body's origin at ``at`` in the parent's frame, free about the plane normal."""

    name: str = Field(..., min_length=1, description="Unique joint name.")
    kind: Literal["revolute"] = Field("revolute", description="Joint type (a spatial walker adds roll and yaw).")
    parent: str = Field(..., description="Parent body.")
    child: str = Field(..., description="Child body.")
    at: Vector2 = Field((0.0, 0.0), description="The child's origin in the parent frame [m].")
    lateral: float = Field(
        0.0,
        description="The spatial formulation's offset of the child's origin along the joint's axis z' (the walker's "
        "right) from ``at`` [m]: a hip width, the second leg's hip point beside the first's (the mirrored leg's "
        "``hip``); a planar model hinges every body in the sagittal plane.",
    )
    axis: Vector3 = Field(
        LATERAL,
        description="The spatial formulation's joint axis in the parent's frame (x' forward, y' up the body, z' the "
        "walker's right; every body frame is its parent's with the joint at 0): z' hinges in the sagittal plane, x' "
        "rolls, y' yaws; its stops and elements act on the angle about it. Another than z' needs "
        f"{IN_SPACE}; the body hung on it starts with the joint at its initial angle and rate (the body's state "
        "keys, relative to its parent) and the mirrored leg's is mirrored (x' and y' components negated).",
    )
    stops: list[StopSpec] = Field(default_factory=list, description="One-sided limits of the relative angle.")
    elements: list[ElementSpec] = Field(
        default_factory=list, description="Passive elements (springs, dampers) acting across the joint."
    )

    @model_validator(mode="after")
    def _one_stop_per_side(self) -> JointSpec:
        names = [e.name for e in self.elements]
        if len(set(names)) != len(names):
            raise ValueError("elements: names must be unique on a joint")
        if math.hypot(*self.axis) < 1e-12:
            raise ValueError("axis: a joint's axis must not be zero")
        sides = [stop.side for stop in self.stops]
        if len(set(sides)) != len(sides):
            raise ValueError("stops: at most one stop per side")
        if len(self.stops) == 2 and self.lower_upper()[0] > self.lower_upper()[1]:
            raise ValueError("stops: the lower stop's angle must not be above the upper stop's (equal: locked)")
        return self

    @property
    def lateral_axis(self) -> bool:
        """Whether the joint hinges about z' (in the sagittal plane: the planar formulation's joints)."""
        return self.axis[0] == 0.0 and self.axis[1] == 0.0 and self.axis[2] > 0.0

    def lower_upper(self) -> tuple[float, float]:
        """The (lower, upper) limits of the relative angle (-inf / +inf where the joint has no stop)."""
        lower = next((s.angle for s in self.stops if s.side == "lower"), -math.inf)
        upper = next((s.angle for s in self.stops if s.side == "upper"), math.inf)
        return lower, upper


class WalkerDescription(Strict):
    """A walker as data: a tree of rigid bodies joined by revolute joints, with feet, and its legs.

    The first body is the root (its origin is the hip). A body's angle is its -y axis's angle from the slope
    normal, positive when the distal end is downhill (the README's leg-angle convention). ``legs`` lists the
    bodies that swap stance and swing at a heel strike, from the hip down; the initial-state keys follow from it
    (:meth:`state_keys`).
    """

    bodies: list[BodySpec] = Field(
        ..., min_length=1, max_length=MAX_PARTS, description="The bodies; the first is the root."
    )
    point_masses: list[PointMassSpec] = Field(
        default_factory=list, max_length=MAX_PARTS, description="Point masses on bodies."
    )
    joints: list[JointSpec] = Field(
        default_factory=list, max_length=MAX_PARTS, description="Revolute joints, one per non-root body."
    )
    feet: list[FootSpec] = Field(..., min_length=1, max_length=MAX_PARTS, description="Feet (arcs or points).")
    legs: list[list[str]] = Field(
        ..., min_length=1, max_length=MAX_PARTS, description="Each leg's bodies, hip first; legs alike."
    )

    @model_validator(mode="after")
    def _a_tree(self) -> WalkerDescription:
        names = [b.name for b in self.bodies]
        named = (
            ("bodies", self.bodies),
            ("point_masses", self.point_masses),
            ("joints", self.joints),
            ("feet", self.feet),
        )
        for field_name, items in named:
            labels = [item.name for item in items]
            if len(set(labels)) != len(labels):
                raise ValueError(f"{field_name}: names must be unique")
        for field_name, bodies in (
            ("point_masses", [p.body for p in self.point_masses]),
            ("feet", [f.body for f in self.feet]),
            ("joints", [j.parent for j in self.joints] + [j.child for j in self.joints]),
            ("legs", [b for leg in self.legs for b in leg]),
            ("joints", [e.against for j in self.joints for e in j.elements if e.against not in (None, GROUND)]),
        ):
            if unknown := [b for b in bodies if b not in names]:
                raise ValueError(f"{field_name}: unknown body {unknown[0]!r}")
        if GROUND in names:
            raise ValueError(f"bodies: {GROUND!r} names the ground (an element's against); rename the body")
        children = [j.child for j in self.joints]
        if sorted(children) != sorted(names[1:]):
            raise ValueError("joints: every body but the first (the root) must be the child of exactly one joint")
        depth = {names[0]: 0}
        for _ in self.joints:  # a tree: every body reached from the root
            depth.update({j.child: depth[j.parent] + 1 for j in self.joints if j.parent in depth})
        if len(depth) != len(names):
            raise ValueError("joints: the bodies must form one tree hanging from the first body")
        self._legs_alike()
        self._latches_on_legs()
        off_legs = self.off_leg_bodies()
        if leg_body := next((b.name for b in self.bodies if b.fall_angle is not None and b.name not in off_legs), None):
            raise ValueError(  # the full key: a validator's own dotted field is taken as it is
                f"walker.description.bodies.{leg_body}.fall_angle: only a body off the legs (a torso) has its own; "
                "the legs' bodies fall past simulation.fall_leg_angle"
            )
        keys = self.state_keys()
        if clash := next((k for k in self.off_leg_keys() if keys.count(k) > 1), None):
            raise ValueError(f"bodies: the state key {clash!r} of a body off the legs is a leg's too; rename the body")
        for joint, element, other in self.joint_elements():
            if other == joint.child:
                raise ValueError(f"joints: element {element.name!r} of joint {joint.name!r} acts against its own body")
        return self

    def features_in_space(self) -> list[str]:
        """The dotted fields that only the spatial formulation represents: joints about another axis than z', feet
        of another shape than an arc, arcs out of the sagittal plane (a planar model refuses them, naming the
        first)."""
        joints = [f"joints.{j.name}.axis" for j in self.joints if not j.lateral_axis]
        feet = [f"feet.{f.name}.{'shape' if f.shape != 'arc' else 'normal'}" for f in self.feet if not f.planar]
        return [f"walker.description.{key}" for key in joints + feet]

    def joint_elements(self) -> list[tuple[JointSpec, ElementSpec, str]]:
        """Every joint's passive elements with the body each acts against (its ``against``, or the joint's parent),
        in the joints' order."""
        return [(j, e, e.against or j.parent) for j in self.joints for e in j.elements]

    def element_bodies(self, index: Mapping[str, int]) -> list[tuple[int, int, ElementSpec]]:
        """(child, other, element) of every joint element, the bodies numbered by ``index`` and the ground -1 (as
        the kernels read it: angle and rate 0, :func:`biped_sim.contact.stop.joint_entry`)."""
        return [(index[j.child], -1 if other == GROUND else index[other], e) for j, e, other in self.joint_elements()]

    def _latches_on_legs(self) -> None:
        """A latching stop holds a joint within one leg (a knee): it is released by that leg's foot."""
        leg_of = {b: k for k, leg in enumerate(self.legs) for b in leg}
        feet = {leg_of.get(f.body) for f in self.feet}
        for j, joint in enumerate(self.joints):
            for k, stop in enumerate(joint.stops):
                leg = leg_of.get(joint.child)
                if stop.latch and not (len(self.legs) == 2 and leg is not None and leg_of.get(joint.parent) == leg
                                       and leg in feet):  # fmt: skip
                    raise ValueError(  # the full key: a validator's own dotted field is taken as it is
                        f"walker.description.joints.{j}.stops.{k}.latch: a latch needs the joint within one leg "
                        "(parent and child on it) of a two-legged walker, with a foot on that leg (its toe-off "
                        "releases the latch)"
                    )

    def _legs_alike(self) -> None:
        flat = [b for leg in self.legs for b in leg]
        if len(set(flat)) != len(flat):
            raise ValueError("legs: a body belongs to one leg at most")
        if len({len(leg) for leg in self.legs}) != 1:
            raise ValueError("legs: every leg needs the same number of bodies")
        if len(self.legs[0]) > 1 and len(set(self.roles())) != len(self.legs[0]):
            raise ValueError("legs: the bodies of a leg need distinct roles (names like thigh_1, shank_1)")

    def massless_bodies(self) -> list[str]:
        """The bodies with no mass of their own nor a point mass on them (a compliant or a described rigid walker
        cannot move them: their mass matrix rows are zero)."""
        carried = {p.body for p in self.point_masses if p.mass > 0.0}
        return [b.name for b in self.bodies if b.mass <= 0.0 and b.name not in carried]

    def roles(self) -> list[str]:
        """The body roles of a leg, hip down: a body's name without its trailing '_<leg>' (thigh_1 -> thigh)."""
        first = self.legs[0]
        roles = [name.rsplit("_", 1)[0] if "_" in name else name for name in first]
        for leg in self.legs[1:]:
            if [name.rsplit("_", 1)[0] if "_" in name else name for name in leg] != roles:
                raise ValueError("legs: every leg's bodies need the same roles in the same order (thigh_1, thigh_2)")
        return roles

    def leg_length(self) -> float:
        """Hip to the lowest foot bottom with every angle zero [m] (the legs along the slope normal): the walker's
        length scale."""
        joint_of = {j.child: j for j in self.joints}
        origin = {self.bodies[0].name: (0.0, 0.0)}
        while len(origin) < len(self.bodies):  # a tree (checked): each pass places the children of placed bodies
            for child, joint in joint_of.items():
                if joint.parent in origin and child not in origin:
                    origin[child] = (origin[joint.parent][0] + joint.at[0], origin[joint.parent][1] + joint.at[1])
        return -min(origin[f.body][1] + f.centre[1] - f.sagittal_radius for f in self.feet)

    def state_keys(self) -> tuple[str, ...]:
        """The initial-state keys: per leg role (stance, then swing if two legs) and body role, angle then rate,
        then each body off the legs by its name (:meth:`off_leg_keys`).

        A one-body leg keeps the README's keys (stance_angle, stance_rate, swing_angle, swing_rate); a kneed
        leg gives stance_thigh_angle, stance_thigh_rate, stance_shank_angle, ...; a torso torso_angle, torso_rate.
        """
        return leg_keys(len(self.legs), [""] if len(self.legs[0]) == 1 else self.roles()) + self.off_leg_keys()

    def off_leg_bodies(self) -> list[str]:
        """The bodies on no leg (a torso), in the description's order."""
        on_legs = {b for leg in self.legs for b in leg}
        return [b.name for b in self.bodies if b.name not in on_legs]

    def off_leg_keys(self) -> tuple[str, ...]:
        """The initial-state keys of the bodies off the legs, ``<body>_angle`` and ``<body>_rate`` (optional in
        ``simulation.initial``: a body whose keys are not given starts at angle 0, at rest)."""
        return tuple(f"{name}_{what}" for name in self.off_leg_bodies() for what in ("angle", "rate"))
