"""The rigid model's data of a walker in space: two legs, rigid bodies in three dimensions, joined by a lateral hinge,
and perhaps a torso on it (built from a described walker of that form by
:func:`~biped_sim.config.space_form.space_form`; ``walker.space`` of a described walker).

The leg is written once, as the left leg in its own frame (x forward, y along the hinge axis pointing away from
the other leg, z from the foot up the leg; origin at its hip point), and the right leg is its mirror image
(y -> -y). The two hip points lie on the hinge axis ``hip_width`` apart (a splayed leg is its numbers turned about
x: docs/guide/rigid.md). A foot is a point, a sphere, a ring (a thin circular edge whose plane
is normal to ``normal``), a torus (a ring of radius ``radius`` thickened by a tube of radius ``tube``: at its
bottom it is curved with radius ``radius + tube`` in the ring's plane and ``tube`` across it, so that its two
curvatures are set apart; e.g. its plane lateral, normal x, gives a foot rounder sideways than fore-aft) or an
ellipsoid (semi-axes along the leg's axes); a planar walker is the special case of zero hip width, a centre of
mass in the leg's x-z plane and a sphere or ring foot in it.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from biped_sim.config.base import Strict
from biped_sim.contact.joint_element import JOINT_ELEMENT_LAWS

Vector3 = tuple[float, float, float]
ElementLaw = Literal[tuple(JOINT_ELEMENT_LAWS)]  # type: ignore[valid-type]
# a thin rod's principal moments (0, I, I) meet the triangle inequality with equality: its published tensor, rounded
# to 4 digits (Coleman et al.'s legs), misses it by a few 1e-4 of the largest moment, which is taken as rounding
INERTIA_ROUNDING = 1e-3
# simulation.initial of a walker in space: the rigid gait's post-strike state (the stance leg's attitude and angular
# velocity in the slope frame, the hinge angle and rate; rigid.space_model's STATE_NAMES)
SPACE_STATE_KEYS = ("heading", "bank", "pitch", "swing_angle", "omega_x", "omega_y", "omega_z", "swing_rate")
# and a torso's: its angle from the stance leg about y (+ with its top forward) and its rate (optional, 0 if left out)
SPACE_TORSO_KEYS = ("torso_angle", "torso_rate")
MAX_TORSO_ELEMENTS = 8  # a torso's elements (each acting against both legs): the compiled model's room for them


class InertiaSpec(Strict):
    """An inertia tensor about the centre of mass, in the leg's frame [kg m^2] (products as +integral x y dm,
    so the tensor is [[xx, -xy, -xz], [-xy, yy, -yz], [-xz, -yz, zz]], the convention of Coleman et al. 2001's
    table, whose Ixy etc. are the tensor's off-diagonal entries with their sign: give ``products: tensor``)."""

    xx: float = Field(..., ge=0, description="Moment about x [kg m^2].")
    yy: float = Field(..., ge=0, description="Moment about y [kg m^2].")
    zz: float = Field(..., ge=0, description="Moment about z [kg m^2].")
    xy: float = Field(0.0, description="Product xy [kg m^2].")
    xz: float = Field(0.0, description="Product xz [kg m^2].")
    yz: float = Field(0.0, description="Product yz [kg m^2].")
    products: Literal["tensor", "integral"] = Field(
        "tensor",
        description="'tensor': xy, xz, yz are the tensor's off-diagonal entries; 'integral': they are +integral "
        "x y dm etc. (the tensor's entries are their negatives).",
    )

    @model_validator(mode="after")
    def _physical(self) -> InertiaSpec:
        moments = np.linalg.eigvalsh(self.matrix())
        a, b, c = sorted(moments)
        if a < -INERTIA_ROUNDING * c or a + b < c * (1.0 - INERTIA_ROUNDING):
            raise ValueError(
                "xx: not an inertia tensor (principal moments "
                f"{a:.4g}, {b:.4g}, {c:.4g}: each must be >= 0 and at most the sum of the other two)"
            )
        return self

    def matrix(self) -> np.ndarray:
        """The 3 x 3 tensor in the leg's frame."""
        sign = 1.0 if self.products == "tensor" else -1.0
        xy, xz, yz = sign * self.xy, sign * self.xz, sign * self.yz
        return np.array([[self.xx, xy, xz], [xy, self.yy, yz], [xz, yz, self.zz]])


class SpaceFoot(Strict):
    """A foot: a point, a sphere (rolling), a ring (a thin circular edge rolling on the ground), a torus or an
    ellipsoid (semi-axes ``axes`` along the leg's x, y, z: at its bottom, upright, curved ax^2 / az fore-aft and
    ay^2 / az sideways)."""

    shape: Literal["point", "sphere", "ring", "torus", "ellipsoid"] = Field(
        ..., description="'point', 'sphere', 'ring', 'torus' or 'ellipsoid'."
    )
    centre: Vector3 = Field(..., description="The point, or the round foot's centre, from the hip point [m].")
    radius: float = Field(0.0, ge=0, description="Sphere, ring or torus (major) radius [m] (a point, an ellipsoid: 0).")
    tube: float = Field(0.0, ge=0, description="A torus's tube radius [m] (the other shapes: 0).")
    axes: Vector3 | None = Field(None, description="An ellipsoid's semi-axes along the leg's x, y, z [m].")
    normal: Vector3 = Field(
        (0.0, 1.0, 0.0),
        description="A ring's or torus's plane normal in the leg's frame (default y: its plane the x-z plane).",
    )

    @model_validator(mode="after")
    def _radius_fits_shape(self) -> SpaceFoot:
        if self.shape == "point" and self.radius != 0.0:
            raise ValueError("radius: a point foot has radius 0 (a round foot is a sphere or a ring)")
        if self.shape == "ellipsoid" and self.radius != 0.0:
            raise ValueError("radius: an ellipsoid foot has radius 0 (its size is its axes)")
        if self.shape not in ("point", "ellipsoid") and self.radius <= 0.0:
            raise ValueError(f"radius: a {self.shape} foot needs a radius > 0")
        if self.shape in ("ring", "torus") and math.hypot(*self.normal) < 1e-12:
            raise ValueError(f"normal: a {self.shape}'s plane normal must not be zero")
        if (self.shape == "torus") != (self.tube > 0.0):
            raise ValueError("tube: a torus foot needs a tube radius > 0 (the other shapes have none)")
        if (self.shape == "ellipsoid") != (self.axes is not None) or (self.axes is not None and min(self.axes) <= 0):
            raise ValueError("axes: an ellipsoid foot needs three semi-axes > 0 (the other shapes have none)")
        return self

    @property
    def reach(self) -> float:
        """From the centre to the bottom with the leg upright [m]: a ring's radius times the sine of its plane's
        tilt from the horizontal (1 for a plane through z) plus a torus's tube, a sphere's radius, an ellipsoid's
        z semi-axis."""
        if self.axes is not None:
            return self.axes[2]
        if self.shape not in ("ring", "torus"):
            return self.radius
        nz = self.normal[2] / math.hypot(*self.normal)
        return self.radius * math.sqrt(1.0 - nz * nz) + self.tube

    @property
    def hertz_radius(self) -> float:
        """The radius [m] of the sphere whose Hertz contact with a plane matches the foot's at its bottom, upright:
        sqrt(R1 R2) of its two principal radii there (Johnson, Contact Mechanics, 1985, section 4.2: the equivalent
        radius of an elliptical contact, exact but for correction factors near 1 while the radii are not far apart):
        a torus's (radius + tube) and tube, an ellipsoid's ax^2 / az and ay^2 / az; a sphere's or ring's its radius
        (a ring: as a disc), a point's 0. The stiffness stays that of the upright bottom as the foot rolls."""
        if self.axes is not None:
            return self.axes[0] * self.axes[1] / self.axes[2]
        if self.shape == "torus":
            return math.sqrt((self.radius + self.tube) * self.tube)
        return self.radius

    def quadric(self) -> np.ndarray:
        """An ellipsoid's diag(ax^2, ay^2, az^2) in the leg's frame: its points are centre + Q^(1/2) u, |u| = 1
        (zero for the other shapes)."""
        return np.diag(np.square(self.axes)) if self.axes is not None else np.zeros((3, 3))


class SpaceKnee(Strict):
    """A knee: the leg's lower body (the shank, which carries the foot) hinged to its upper body about the leg's y
    axis at ``at``, with one stop at the straight knee, which it strikes plastically and where it then stays locked
    (the rigid model's knee: McGeer 1990, Chen 2007). The shank's numbers are in the leg's frame with the knee
    straight."""

    at: Vector3 = Field(..., description="The knee's point on the hinge axis y, from the hip point [m].")
    flexion: Literal[1, -1] = Field(
        1, description="+1: the knee bends with the foot swinging behind (about +y); -1: ahead."
    )
    mass: float = Field(..., gt=0, description="The shank's mass [kg].")
    com: Vector3 = Field(..., description="The shank's centre of mass from the hip point, the knee straight [m].")
    inertia: InertiaSpec = Field(..., description="The shank's inertia tensor about its centre of mass [kg m^2].")


class SpaceLeg(Strict):
    """The left leg in its frame (x forward, y along the hinge away from the other leg, z up; origin at the hip
    point): its mass, centre of mass, inertia about the centre of mass, and foot; with a knee, those are the upper
    body's (the thigh's) and the foot is on the shank."""

    mass: float = Field(..., gt=0, description="Mass [kg] (with a knee: the thigh's).")
    com: Vector3 = Field(..., description="Centre of mass from the hip point [m].")
    inertia: InertiaSpec = Field(..., description="Inertia tensor about the centre of mass [kg m^2].")
    foot: SpaceFoot = Field(..., description="The foot.")
    knee: SpaceKnee | None = Field(None, description="A knee and the shank below it (none: a rigid leg).")


class SpaceElement(Strict):
    """A torso's passive element, acting alike against each leg (:mod:`biped_sim.contact.joint_element`'s law
    ``law``): its torque from the torso's angle relative to the leg about the lateral axis, in the planar sense
    (about the walker's right: minus the angle about y)."""

    law: ElementLaw = Field(..., description="The element's law: linear_spring or linear_damper.")
    stiffness: float = Field(0.0, ge=0, description="A spring's stiffness [N m/rad].")
    rest_angle: float = Field(0.0, description="A spring's rest angle [rad].")
    damping: float = Field(0.0, ge=0, description="A damper's coefficient [N m s/rad].")


class SpaceTorso(Strict):
    """A torso: a body hinged to the legs at the hinge's midpoint about the hinge axis, symmetric about the
    sagittal plane (the mirror after each strike leaves it unchanged), held by elements against both legs alike.
    Its numbers are in the walker frame with the torso along the stance leg (its angle 0)."""

    mass: float = Field(..., gt=0, description="Mass [kg].")
    com: tuple[float, float] = Field(..., description="Centre of mass (x, z) from the hinge's midpoint [m].")
    inertia: InertiaSpec = Field(..., description="Inertia tensor about the centre of mass (xy = yz = 0) [kg m^2].")
    elements: tuple[SpaceElement, ...] = Field((), description="Elements, each acting against each leg.")


class SpaceDescription(Strict):
    """Two alike legs (the left written, the right its mirror) joined by one hinge along the lateral axis, and
    perhaps a torso on the hinge."""

    hip_width: float = Field(0.0, ge=0, description="Distance between the two hip points along the hinge [m].")
    hip_mass: float = Field(0.0, ge=0, description="A point mass at the hinge's midpoint [kg].")
    leg: SpaceLeg = Field(..., description="The left leg (the right leg is its mirror image).")
    torso: SpaceTorso | None = Field(None, description="A torso on the hinge (none: the legs alone).")

    @model_validator(mode="after")
    def _foot_below_hip(self) -> SpaceDescription:
        if self.leg_length() <= 0.0:
            raise ValueError(
                "leg.foot.centre: the foot's bottom must be below the hip (z of centre minus radius and tube < 0)"
            )
        return self

    def leg_length(self) -> float:
        """The hip point to the foot's bottom with the leg upright [m]: the walker's length scale."""
        return -(self.leg.foot.centre[2] - self.leg.foot.reach)
