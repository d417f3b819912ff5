"""The ground profile's schema (``ground.profile``) and its compilation into the arrays of :mod:`.ground`.

Every profile lives in the slope frame: positions x along the slope (downhill positive, the stance
foot starts at x = 0), heights h along the slope normal (up positive). Heights are continuous except
at declared step edges, where a step is a vertical riser at x = at. Kinds:

* ``flat``: the plane h = 0 (the default; bit for bit the walker of before profiles);
* ``steps``: level changes ``{at: x, height: dh}`` (dh > 0 up, < 0 down), ``at`` increasing;
* ``slope_change``: the slope angle becomes ``slope`` (gamma2, downhill positive like ``ground.slope``)
  from x = ``at`` on: h = -(x - at) tan(gamma2 - gamma) beyond it;
* ``polyline``: heights ``height`` at increasing ``x``, level beyond both ends;
* ``random``: piecewise-linear heights every ``spacing`` metres from x = ``start`` over ``length``,
  normal with standard deviation ``roughness`` (numpy's default generator seeded with ``seed``),
  h = 0 at ``start`` and level beyond the last point.

A config with a profile, from Python (what a robustness study does), validated with every cross-check::

    derive(config, {"ground.profile": StepsProfile(steps=[Step(at=0.6, height=-0.01)]).model_dump()})
    derive(config, {"ground.profile": {"kind": "random", "seed": 3}})

The compiled side (:mod:`.ground`) reads :func:`profile_arrays` (a system holds :func:`profile_ground`);
``ground_height(x, vertices, ends)`` there
is h(x) for compiled callers, ``ground_height_at`` for Python ones.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, Protocol

import numpy as np
from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

from biped_sim.contact.ground import FLAT_ENDS, FLAT_GROUND, FLAT_VERTICES, Ground, ProfileGround, ground_height_at

MAX_RANDOM_POINTS = 1_000_000


class _Profile(BaseModel):
    """Base of the profile kinds: unknown keys are errors, numbers are finite and never true/false (strict)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, strict=True)


class FlatProfile(_Profile):
    """The plane of the slope."""

    kind: Literal["flat"] = "flat"


class Step(_Profile):
    """One level change at x = ``at``."""

    at: float = Field(..., description="Position of the riser along the slope [m].")
    height: float = Field(..., description="Level change [m] (> 0 up, < 0 down), not 0.")

    @model_validator(mode="after")
    def _changes_level(self) -> Step:
        if self.height == 0.0:
            raise ValueError("height: a step must change the level (0 given)")
        return self


class StepsProfile(_Profile):
    """Level changes (vertical risers) along the slope."""

    kind: Literal["steps"] = "steps"
    steps: list[Step] = Field(..., min_length=1, description="The steps, ``at`` strictly increasing.")

    @model_validator(mode="after")
    def _increasing(self) -> StepsProfile:
        if any(b.at <= a.at for a, b in zip(self.steps, self.steps[1:], strict=False)):
            raise ValueError("steps: 'at' must be strictly increasing")
        return self


class SlopeChangeProfile(_Profile):
    """The slope angle changes to ``slope`` at x = ``at``."""

    kind: Literal["slope_change"] = "slope_change"
    at: float = Field(..., description="Position of the slope change along the slope [m].")
    slope: float = Field(..., gt=-math.pi / 2, lt=math.pi / 2, description="New downhill slope angle gamma2 [rad].")


class PolylineProfile(_Profile):
    """Heights at given positions, linear between them, level beyond both ends."""

    kind: Literal["polyline"] = "polyline"
    x: list[float] = Field(..., min_length=2, description="Positions along the slope [m], strictly increasing.")
    height: list[float] = Field(..., min_length=2, description="Heights along the slope normal [m], one per x.")

    @model_validator(mode="after")
    def _consistent(self) -> PolylineProfile:
        if len(self.x) != len(self.height):
            raise ValueError(f"height: {len(self.height)} values for {len(self.x)} positions x")
        if any(b <= a for a, b in zip(self.x, self.x[1:], strict=False)):
            raise ValueError("x: must be strictly increasing (a step is a 'steps' profile)")
        return self


class RandomProfile(_Profile):
    """Piecewise-linear random heights (seeded)."""

    kind: Literal["random"] = "random"
    spacing: float = Field(0.05, gt=0, description="Distance between height points along the slope [m].")
    roughness: float = Field(0.002, ge=0, description="Standard deviation of the heights [m].")
    seed: int = Field(0, ge=0, description="Seed of numpy's default random generator.")
    start: float = Field(0.3, description="Where the rough ground begins (h = 0 there) [m].")
    length: float = Field(20.0, gt=0, description="Length of the rough ground [m]; level beyond it.")

    @model_validator(mode="after")
    def _bounded(self) -> RandomProfile:
        if self.length / self.spacing > MAX_RANDOM_POINTS:
            raise ValueError(f"spacing: length / spacing over {MAX_RANDOM_POINTS} height points")
        return self


def _kind_tag(value: object) -> str | None:
    """The union member of a raw mapping or a model (its capitalised ``kind``, which error messages drop)."""
    kind = value.get("kind", "flat") if isinstance(value, dict) else getattr(value, "kind", None)
    return str(kind).title().replace("_", "") if isinstance(kind, str) else None


GroundProfile = Annotated[
    Annotated[FlatProfile, Tag("Flat")]
    | Annotated[StepsProfile, Tag("Steps")]
    | Annotated[SlopeChangeProfile, Tag("SlopeChange")]
    | Annotated[PolylineProfile, Tag("Polyline")]
    | Annotated[RandomProfile, Tag("Random")],
    Discriminator(_kind_tag, custom_error_type="profile_kind", custom_error_message="unknown profile kind"),
]


def profile_arrays(profile: GroundProfile, slope: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 2), ends (2,)) of :mod:`.ground` for ``profile`` on a slope of angle ``slope``."""
    if isinstance(profile, FlatProfile):
        return FLAT_VERTICES.copy(), FLAT_ENDS.copy()
    ends = np.zeros(2)
    if isinstance(profile, StepsProfile):
        points, level = [], 0.0
        for step in profile.steps:
            points += [(step.at, level), (step.at, level + step.height)]
            level += step.height
    elif isinstance(profile, SlopeChangeProfile):
        points = [(profile.at, 0.0)]
        ends[1] = -math.tan(profile.slope - slope)
    elif isinstance(profile, PolylineProfile):
        points = list(zip(profile.x, profile.height, strict=True))
    else:
        count = math.floor(profile.length / profile.spacing) + 1
        heights = np.random.default_rng(profile.seed).normal(0.0, profile.roughness, count)
        heights[0] = 0.0
        points = list(zip(profile.start + profile.spacing * np.arange(count), heights, strict=True))
    return np.array(points, dtype=float).reshape(-1, 2), ends


def profile_ground(profile: GroundProfile, slope: float) -> Ground:
    """A system's typed ground (:mod:`.ground`): FLAT_GROUND for the flat profile, else its arrays."""
    return FLAT_GROUND if isinstance(profile, FlatProfile) else ProfileGround(*profile_arrays(profile, slope))


class SlopedGround(Protocol):
    """The config's ground section as the support check reads it."""

    slope: float
    profile: GroundProfile


def profile_support_error(ground: SlopedGround, dynamics: str, friction: str) -> str | None:
    """Why ``ground.profile`` cannot run with these settings (a one-line reason), or None.

    The walker starts with its stance foot at x = 0 on level ground; profiles other than flat run in
    every compliant formulation (the spatial one: :mod:`biped_sim.multibody.spatial_feet`), without LuGre friction
    (one bristle state per foot cannot serve two contact features), and in the rigid models (their heel strike
    reads the profile: :mod:`biped_sim.rigid.ground`).
    """
    profile = ground.profile
    if isinstance(profile, FlatProfile):
        return None
    if dynamics == "compliant" and friction == "lugre":
        return "profiles other than flat do not support friction.model: lugre"
    vertices, ends = profile_arrays(profile, ground.slope)
    behind = vertices[vertices[:, 0] <= 0.0]
    if ends[0] != 0.0 or np.any(behind[:, 1] != 0.0) or (len(behind) == 0 and vertices[0, 1] != 0.0):
        return "must be level (height 0) up to x = 0, where the stance foot starts"
    return None


def profile_outline(vertices: np.ndarray, ends: np.ndarray, x_min: float, x_max: float) -> np.ndarray:
    """The profile over [x_min, x_max] as (k, 2) points (x, h) for drawing: exact, the vertices inside and both ends."""
    inside = vertices[(vertices[:, 0] > x_min) & (vertices[:, 0] < x_max)]
    ends_h = ground_height_at(np.array([x_min, x_max]), vertices, ends)
    return np.vstack([[x_min, ends_h[0]], inside, [x_max, ends_h[1]]])
