"""Any described walker as MJCF, MuJoCo's model format (plain XML text: MuJoCo is not imported here).

What is written, and how:

* A planar walker (every kind with a planar description, :func:`~biped_sim.walkers.describe.describe`): the tree of
  bodies with their point masses folded in (:func:`~biped_sim.walkers.described.resolve_tree`), in the slope frame
  (x downhill, z along the normal; the slope a plane tilted by gamma inside a static body, so gravity stays
  vertical). The description's body frame (x across, y along) is the MJCF's x-z plane. The root floats on a planar
  joint set (slide along x, slide along z, hinge about -y: a positive angle puts the distal end downhill, the
  README's convention), every other body hangs on a hinge about -y at its joint point, so a hinge's angle is the
  description's relative angle. Each body carries its mass at its centre of mass with its moment of inertia about
  every axis (the motion stays in the plane; a body with none, a point mass, gets ``INERTIA_FLOOR`` m l^2, as
  MuJoCo needs one), and a capsule from its origin to each child's joint and foot (drawn only: no mass, no
  contact). A round foot is a sphere of its radius at its centre; a point foot a sphere of ``POINT_FOOT`` l moved
  that far toward its body's origin, so that its bottom is the point. A stop is MuJoCo's joint limit on its side
  (the other side 1000 rad away) with MuJoCo's default softness, not our stop's law; a spring or damper is a fixed
  tendon over the hinges between its two bodies (its length their relative angle, its spring length the rest angle;
  both negated for a negative rest angle).
* A walker in space (``Config.in_space``): the left leg on a free joint (its body frame the walker
  frame: origin at the hinge's midpoint, x forward, y along the hinge, z up the leg), the right leg on a hinge about
  y; full inertia tensors (each principal moment floored as in the compliant builder); a sphere foot a sphere, a
  point foot a sphere of ``POINT_FOOT`` l above the point, a ring a flat cylinder (half-thickness ``RING_HALF_WIDTH``
  of its radius) whose axis is the ring's normal: its contact with a plane is its rim's lowest point, as a ring's;
  an ellipsoid MuJoCo's ellipsoid, its axes the leg's.
  The world is the rigid model's slope frame with gravity tilted by the slope.

What MuJoCo cannot represent, refused in one line: a torus foot (no such geom), a latch (a joint held from both
sides until its leg's foot leaves the ground: MuJoCo's constraints are not switched by events in the model). The
contact is matched (:mod:`.mujoco_contact`) at the whole weight on one foot, friction is MuJoCo's elliptic cone with
``mu_kinetic``.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.bench.mujoco_contact import IMPEDANCE, matched_solref
from biped_sim.config import Config, WalkerDescription
from biped_sim.config.description import GROUND
from biped_sim.config.space_description import SpaceDescription
from biped_sim.errors import ConfigError
from biped_sim.walkers.describe import describe
from biped_sim.walkers.described import Tree, resolve_tree
from biped_sim.walkers.model import contact_stiffness, static_contact_penetration
from biped_sim.walkers.space_geometry import TO_SPATIAL, LegGeometry, leg_geometry, with_point_mass
from biped_sim.walkers.space_walker import body_inertia

TIMESTEP = 1e-4  # [s] MuJoCo's step in the comparisons
POINT_FOOT = 1e-3  # a point foot's sphere radius [leg lengths]
INERTIA_FLOOR = 1e-6  # a planar body's least moment of inertia [m l^2]
RING_HALF_WIDTH = 1e-3  # a ring foot's cylinder half-thickness [ring radii]
FAR_LIMIT = 1000.0  # [rad] the free side of a one-sided stop
ROOT_HINGE = "theta"  # the root body's hinge: its angle from the slope normal, every body's absolute angle's first term


def numbers(*values: float) -> str:
    """Space-separated floats, every digit kept."""
    return " ".join(repr(float(v)) for v in values)


def contact_attributes(config: Config, mass: float, foot_radius: float, leg_length: float) -> str:
    """A foot geom's friction, solref and solimp: our contact matched at ``mass``'s weight on one foot."""
    stiffness = contact_stiffness(config, foot_radius)
    if stiffness <= 0.0:
        raise ConfigError("contact.stiffness", "a foot without a radius has no Hertz stiffness: give one for MJCF")
    k, b = matched_solref(config, mass, stiffness, static_contact_penetration(config, mass, stiffness, leg_length))
    return (
        f'friction="{config.friction.mu_kinetic!r} 0 0" solref="{-k!r} {-b!r}" solimp="{IMPEDANCE} {IMPEDANCE} 0.001"'
    )


def document(name: str, options: str, world: str, extra: str = "") -> str:
    """The MJCF document around a world body's contents."""
    return f"""<mujoco model="{name}">
  <compiler angle="radian" inertiafromgeom="false"/>
  <option {options} cone="elliptic"/>
  <worldbody>
{world}
  </worldbody>{extra}
</mujoco>
"""


def walker_mjcf(config: Config, timestep: float = TIMESTEP, integrator: str = "RK4") -> str:
    """MJCF of the walker of ``config`` on its slope: a planar description's tree or a walker in space."""
    if config.in_space:
        return space_mjcf(config, timestep, integrator)
    return planar_mjcf(config, timestep, integrator)


def planar_mjcf(config: Config, timestep: float = TIMESTEP, integrator: str = "RK4") -> str:
    """MJCF of a walker with a planar description (module docstring: how each part is written)."""
    description = describe(config)
    for j, joint in enumerate(description.joints):
        for k, stop in enumerate(joint.stops):
            if stop.latch:
                raise ConfigError(
                    f"walker.description.joints.{j}.stops.{k}.latch",
                    "MuJoCo has no latch (a joint held until its leg's foot leaves the ground): not written as MJCF",
                )
    tree = resolve_tree(description)
    length = description.leg_length()
    contact = contact_attributes(config, float(tree.mass.sum()), float(tree.foot_radius.max()), length)
    mu = config.friction.mu_kinetic
    root = "\n".join(
        f'        <joint name="{n}" type="{t}" axis="{a}"/>'
        for n, t, a in (("x", "slide", "1 0 0"), ("z", "slide", "0 0 1"), (ROOT_HINGE, "hinge", "0 -1 0"))
    )
    world = (
        f'    <body name="slope" euler="0 {config.ground.slope!r} 0">\n'
        f'      <geom name="ground" type="plane" size="50 1 0.1" friction="{mu!r} 0 0"/>\n'
        f"{_planar_body(tree, 0, root, contact, length, '      ')}\n    </body>"
    )
    options = f'timestep="{timestep!r}" integrator="{integrator}" gravity="0 0 {-config.gravity!r}"'
    return document("planar_walker", options, world, _tendons(description, tree))


def _in_plane(v: np.ndarray) -> str:
    """A description vector (x across, y along) as an MJCF position (x, 0, z)."""
    return numbers(v[0], 0.0, v[1])


def _planar_body(tree: Tree, b: int, joints: str, contact: str, length: float, indent: str) -> str:
    """Body ``b`` with its joints, inertia, feet, drawn segments and children (recursively)."""
    inertia = max(float(tree.inertia[b]), INERTIA_FLOOR * float(tree.mass[b]) * length**2)
    children = [c for c in range(len(tree.names)) if tree.parent[c] == b]
    feet = [f for f in range(len(tree.foot_names)) if tree.foot_body[f] == b]
    lines = [
        f'{indent}<body name="{tree.names[b]}" pos="{_in_plane(tree.joint_at[b])}">',
        joints,
        f'{indent}  <inertial pos="{_in_plane(tree.com[b])}" mass="{float(tree.mass[b])!r}" '
        f'diaginertia="{numbers(inertia, inertia, inertia)}"/>',
    ]
    for end in [tree.joint_at[c] for c in children] + [tree.foot_centre[f] for f in feet]:
        if math.hypot(*end) > 1e-9:
            lines.append(
                f'{indent}  <geom type="capsule" fromto="0 0 0 {_in_plane(end)}" size="{0.01 * length!r}" mass="0" '
                'contype="0" conaffinity="0" group="1"/>'
            )
    for f in feet:
        centre, radius = tree.foot_centre[f], float(tree.foot_radius[f])
        if radius == 0.0:
            radius = POINT_FOOT * length
            centre = centre - radius * centre / max(float(np.hypot(*centre)), radius)
        lines.append(
            f'{indent}  <geom name="{tree.foot_names[f]}" type="sphere" pos="{_in_plane(centre)}" size="{radius!r}" '
            f'mass="0" {contact}/>'
        )
    for c in children:
        lines.append(_planar_body(tree, c, _hinge(tree, c, indent + "    "), contact, length, indent + "  "))
    lines.append(f"{indent}</body>")
    return "\n".join(lines)


def _hinge(tree: Tree, c: int, indent: str) -> str:
    """The hinge of body ``c`` to its parent, limited by its stops."""
    stops = [s for s in tree.stops if s[1] == c]
    limits = ""
    if stops:
        lower = next((s[3] for s in stops if s[2] == "lower"), -FAR_LIMIT)
        upper = next((s[3] for s in stops if s[2] == "upper"), FAR_LIMIT)
        limits = f' limited="true" range="{numbers(lower, upper)}"'
    return f'{indent}<joint name="{tree.names[c]}" type="hinge" axis="0 -1 0"{limits}/>'


def _tendons(description: WalkerDescription, tree: Tree) -> str:
    """Each joint element as a fixed tendon whose length is the relative angle (child's minus the other body's)."""
    index = {name: k for k, name in enumerate(tree.names)}
    rows = []
    for joint, element, other in description.joint_elements():
        coef = {tree.names[b]: 1.0 for b in _path(tree, index[joint.child])}
        if other == GROUND:  # the child's absolute angle: the root's hinge too
            coef[ROOT_HINGE] = 1.0
        for b in _path(tree, index[other]) if other != GROUND else []:
            coef[tree.names[b]] = coef.get(tree.names[b], 0.0) - 1.0
        rest = element.rest_angle or 0.0
        sign = -1.0 if rest < 0.0 else 1.0  # MuJoCo reads a spring length of -1 as "the length at qpos0"
        rest *= sign
        refs = "".join(f'<joint joint="{b}" coef="{sign * c!r}"/>' for b, c in coef.items() if c != 0.0)
        rows.append(
            f'    <fixed name="{joint.name}.{element.name}" stiffness="{element.stiffness or 0.0!r}" '
            f'damping="{element.damping or 0.0!r}" springlength="{numbers(rest, rest)}">{refs}</fixed>'
        )
    return "\n  <tendon>\n" + "\n".join(rows) + "\n  </tendon>" if rows else ""


def _path(tree: Tree, b: int) -> list[int]:
    """The bodies from ``b`` up to the root's child (each hinged to its parent; the root's angle is common)."""
    path = []
    while tree.parent[b] >= 0:
        path.append(b)
        b = int(tree.parent[b])
    return path


def space_mjcf(config: Config, timestep: float = TIMESTEP, integrator: str = "RK4") -> str:
    """MJCF of the walker in space of ``config`` on its slope (module docstring: how each part is written)."""
    space = config.walker.space  # type: ignore[union-attr]
    if space.leg.knee is not None:
        raise ConfigError("walker.description.legs", "a walker in space is written as MJCF with one-body legs only")
    if space.torso is not None:
        raise ConfigError("walker.description.bodies", "a walker in space is written as MJCF without a torso")
    if space.leg.foot.shape == "torus":
        raise ConfigError("walker.description.feet", "a torus foot is not written as MJCF (MuJoCo has no torus)")
    legs = (with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1))
    shapes = [_foot_shape(space, leg) for leg in legs]
    contact = contact_attributes(config, legs[0].mass + legs[1].mass, space.leg.foot.radius, space.leg_length())
    g, slope, mu = config.gravity, config.ground.slope, config.friction.mu_kinetic
    world = f"""    <geom name="ground" type="plane" size="50 50 0.1" friction="{mu!r} 0 0"/>
    <body name="left">
      <freejoint name="base"/>
      {_space_leg(legs[0], "foot0", contact, shapes[0])}
      <body name="right">
        <joint name="hinge" type="hinge" axis="0 1 0"/>
        {_space_leg(legs[1], "foot1", contact, shapes[1])}
      </body>
    </body>"""
    gravity = numbers(g * math.sin(slope), 0.0, -g * math.cos(slope))
    return document("walker_in_space", f'timestep="{timestep!r}" integrator="{integrator}" gravity="{gravity}"', world)


def balanced(inertia: np.ndarray) -> np.ndarray:
    """``inertia`` with its smallest principal moment raised until the two smaller ones sum to the largest (MuJoCo
    refuses less): a published tensor rounded to 4 digits misses it by a few 1e-4 of the largest moment, which the
    description takes as rounding (:data:`~biped_sim.config.space_description.INERTIA_ROUNDING`)."""
    moments, axes = np.linalg.eigh(inertia)
    moments[0] = max(moments[0], (moments[2] - moments[1]) * (1.0 + 1e-9))
    return axes @ np.diag(moments) @ axes.T


def _foot_shape(space: SpaceDescription, leg: LegGeometry) -> str:
    """A foot geom's type, size, place and orientation (walker frame)."""
    foot = space.leg.foot
    if foot.axes is not None:  # an ellipsoid: its axes the leg's
        return f'type="ellipsoid" size="{numbers(*foot.axes)}" pos="{numbers(*leg.foot_centre)}"'
    if leg.foot_normal is not None:
        return (
            f'type="cylinder" size="{leg.foot_radius!r} {RING_HALF_WIDTH * leg.foot_radius!r}" '
            f'zaxis="{numbers(*leg.foot_normal)}" pos="{numbers(*leg.foot_centre)}"'
        )
    radius = leg.foot_radius or POINT_FOOT * space.leg_length()
    centre = leg.foot_centre + np.array([0.0, 0.0, radius - leg.foot_radius])
    return f'type="sphere" size="{radius!r}" pos="{numbers(*centre)}"'


def _space_leg(leg: LegGeometry, foot: str, contact: str, shape: str) -> str:
    """A leg's inertial element and foot geom (walker frame)."""
    j = balanced(TO_SPATIAL.T @ body_inertia(leg) @ TO_SPATIAL)
    inertial = (
        f'<inertial pos="{numbers(*leg.com)}" mass="{float(leg.mass)!r}" '
        f'fullinertia="{numbers(j[0, 0], j[1, 1], j[2, 2], j[0, 1], j[0, 2], j[1, 2])}"/>'
    )
    return f'{inertial}<geom name="{foot}" {shape} mass="0" {contact}/>'
