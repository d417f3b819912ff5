"""A described walker's foot: its shape on its body, and what the planar and the spatial models make of it.

A foot is an arc or a point in the body's sagittal plane; in space also a sphere, a ring or torus whose plane is
given by its normal (``normal``, or ``plane`` for the two common ones), or an ellipsoid. :meth:`FootSpec.in_space`
is the foot as the rigid model in space takes it (:class:`~biped_sim.config.space_description.SpaceFoot`, in its
leg frame), :meth:`FootSpec.sagittal_arc` the arc a planar model rolls on.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from biped_sim.config.base import IN_SPACE, Strict, Vector2
from biped_sim.config.space_description import SpaceFoot, Vector3

SAGITTAL_NORMAL = (0.0, 0.0, 1.0)  # a ring in the body's x'-y' plane (an arc): its normal z'
LATERAL_NORMAL = (1.0, 0.0, 0.0)  # a ring in the body's y'-z' plane: its normal x'
FLAT = 1e-12  # 1 - (n . y')^2 below this: a ring across the leg, standing flat on its whole edge upright


class FootSpec(Strict):
    """A foot: an arc (radius > 0) or a point (radius 0) on a body, its centre in the body frame; in space also a
    sphere, a torus or an ellipsoid (:class:`~biped_sim.config.space_description.SpaceFoot`'s shapes: an arc's or a
    torus's ring in the plane of its ``normal`` (by default the sagittal x'-y'), an ellipsoid's semi-axes along x',
    y', z')."""

    name: str = Field(..., min_length=1, description="Unique foot name.")
    body: str = Field(..., description="The body carrying it.")
    centre: Vector2 = Field(..., description="Arc centre in the body frame [m].")
    radius: float = Field(0.0, ge=0, description="Arc radius [m]; 0 = point foot.")
    lateral: float = Field(
        0.0,
        description="The spatial formulation's place of the foot along the joints' axis (z') [m], its arc in that "
        "plane; a planar model puts every foot in the sagittal plane. A walker with a foot off it stands on its "
        "feet in roll and yaw; one without is held in its plane.",
    )
    shape: Literal["arc", "sphere", "torus", "ellipsoid"] = Field(
        "arc",
        description="'arc' (a point at radius 0; in space a disc's edge in the plane of its ``normal``); with "
        f"{IN_SPACE}: 'sphere', 'torus' (a ring of ``radius`` in its plane thickened by ``tube``) or "
        "'ellipsoid' (``axes``).",
    )
    tube: float = Field(0.0, ge=0, description="A torus's tube radius [m] (the other shapes: 0).")
    plane: Literal["sagittal", "lateral"] = Field(
        "sagittal",
        description="A torus's ring's plane, the shorthand of two normals: 'sagittal' (x'-y', normal z': curved "
        "radius + tube fore-aft, tube sideways) or 'lateral' (y'-z', normal x': its lowest point ``radius`` below "
        "the centre: tube fore-aft, radius + tube sideways, a foot rounder sideways than fore-aft, which stands in "
        "roll).",
    )
    normal: Vector3 | None = Field(
        None,
        description="An arc's (radius > 0) or a torus's ring's plane normal in the body frame (x' forward, y' up "
        "the body, z' the walker's right; its length and sign immaterial), instead of ``plane``: e.g. a leg splayed "
        "by s about x' turns the sagittal [0, 0, 1] into [0, sin(s), cos(s)] (docs/guide/rigid.md); the mirrored "
        f"leg's z' component is negated. Off z' the ring is a foot in space ({IN_SPACE}).",
    )
    axes: Vector3 | None = Field(
        None,
        description="An ellipsoid's semi-axes along x', y', z' [m] (radius 0): curved ax^2 / ay fore-aft and az^2 / "
        "ay sideways at its bottom, upright. It starts on the arc of its y' semi-axis, exact upright (tilted, its "
        "bottom's height and rolling differ by (1 - ax^2 / ay^2) of the tilt's square: a short transient).",
    )

    @model_validator(mode="after")
    def _a_shape(self) -> FootSpec:
        if self.plane != "sagittal" and self.shape != "torus":
            raise ValueError("plane: only a torus's ring has a plane other than the sagittal")
        if self.normal is not None:
            if "plane" in self.model_fields_set:
                raise ValueError("normal: give the ring's plane by normal or by plane, not both")
            if not (self.shape == "torus" or (self.shape == "arc" and self.radius > 0.0)):
                raise ValueError("normal: only a ring's plane has one (an arc of radius > 0 or a torus)")
            if math.hypot(*self.normal) < 1e-12:
                raise ValueError("normal: a ring's plane normal must not be zero")
            nx, _, nz = self.plane_normal
            if nx * nx + nz * nz < FLAT:
                raise ValueError("normal: a ring across the leg (normal along y') stands flat on its edge; tilt it")
        self.in_space()  # SpaceFoot's checks of radius, tube and axes
        return self

    @property
    def plane_normal(self) -> Vector3:
        """The unit normal of an arc's or torus's ring's plane in the body frame: ``normal`` normalised, else z'
        (``plane: sagittal``, every arc's and the other shapes') or x' (``plane: lateral``)."""
        if self.normal is None:
            return SAGITTAL_NORMAL if self.plane == "sagittal" else LATERAL_NORMAL
        norm = math.hypot(*self.normal)
        return (self.normal[0] / norm, self.normal[1] / norm, self.normal[2] / norm)

    @property
    def planar(self) -> bool:
        """Whether a planar model represents the foot: an arc (or a point) in the sagittal plane, its normal z'."""
        nx, ny, _ = self.plane_normal
        return self.shape == "arc" and nx == 0.0 and ny == 0.0

    def in_space(self, side: float = -1.0) -> SpaceFoot:
        """The foot in the rigid model's leg frame (x', side z', y'; y by default the walker's left): an arc a ring
        (a point at radius 0), a torus's ring, each in the plane of its normal, an ellipsoid's axes (x', z', y')."""
        shape = {"arc": "point" if self.radius == 0.0 else "ring"}.get(self.shape, self.shape)
        axes = None if self.axes is None else (self.axes[0], self.axes[2], self.axes[1])
        nx, ny, nz = self.plane_normal
        return SpaceFoot(
            shape=shape, centre=(self.centre[0], side * self.lateral, self.centre[1]), radius=self.radius,
            tube=self.tube, axes=axes, normal=canonical_normal((nx, side * nz, ny)),
        )  # fmt: skip

    def sagittal_arc(self) -> tuple[tuple[float, float], float]:
        """(centre, radius) of the arc a planar model of the foot rolls on in its sagittal plane: an ellipsoid's
        its y' semi-axis, exact upright; a ring's (and a torus's, its tube added) the osculating circle at the
        bottom, upright, of the ring's outline in the x'-y' plane (an ellipse of semi-axes R and R |n.z'| for the
        unit normal n: radius R n_z^2 / (1 - n_y^2)^(3/2), its bottom R sqrt(1 - n_y^2) below the centre), which is
        the ring itself in the sagittal plane (n = z'), a point ``radius`` below the centre in the lateral (n = x'),
        and, tilted, exact upright and to second order in the pitch (a planar model refuses such a foot, a feature
        in space; the spatial formulation starts on it: a short transient)."""
        if self.axes is not None:
            return self.centre, self.axes[1]
        nx, ny, nz = self.plane_normal
        across = nx * nx + nz * nz  # 1 - n_y^2
        s = math.sqrt(across)
        curvature_radius = self.radius * nz * nz / (across * s)
        x = self.centre[0] + self.radius * nx * ny / s
        return (x, self.centre[1] + (curvature_radius - self.radius * s)), curvature_radius + self.tube

    @property
    def sagittal_radius(self) -> float:
        """The radius of :meth:`sagittal_arc`, its centre's reach below the foot's centre added [m]: the bottom's
        depth below the centre upright."""
        (_, y), radius = self.sagittal_arc()
        return radius + (self.centre[1] - y)


def canonical_normal(normal: Vector3) -> Vector3:
    """A plane's normal with its sign fixed (its largest component, the first of equals, positive; no -0.0): the
    plane of a leg and of its mirror image are then the same numbers."""
    k = max(range(3), key=lambda i: abs(normal[i]))
    sign = -1.0 if normal[k] < 0.0 else 1.0
    return (sign * normal[0] + 0.0, sign * normal[1] + 0.0, sign * normal[2] + 0.0)
