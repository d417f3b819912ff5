"""The walker section of the schema: one member per ``walker.kind``, each with its own fields only (MODEL.md 1).

A bundled kind (a preset: compass, four-legged, simplest, rimless wheel) has its parameters, which
``walkers.describe`` expands into bodies; a described walker (``walker.kind: description``) has its named
parameters and its description, resolved by :mod:`biped_sim.config.parameters`. The union picks the member by
``kind`` (``compass`` when not given); a field of another kind is refused in one line naming it.
"""

from __future__ import annotations

import copy
import math
from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Discriminator,
    Field,
    PrivateAttr,
    SerializerFunctionWrapHandler,
    Tag,
    ValidationError,
    ValidatorFunctionWrapHandler,
    model_serializer,
    model_validator,
)

from biped_sim.config.base import Strict
from biped_sim.config.description import JointSpec, WalkerDescription
from biped_sim.config.parameters import ParameterSpec, mirror_legs, parameter_values, resolve_numbers
from biped_sim.config.space_description import SpaceDescription
from biped_sim.config.space_form import space_form
from biped_sim.errors import quote


class Preset(Strict):
    """A bundled walker kind: its parameters, expanded into bodies by ``walkers.describe`` (never in the config)."""

    kind: str = Field(..., description="The walker kind (each member of WalkerConfig names its own).")

    @model_validator(mode="before")
    @classmethod
    def _parameters_are_fields(cls, data: Any) -> Any:
        """``parameters`` (NAME -> value, or a list of name and value) sets the preset's fields of those names:
        every walker's physical parameters are ``walker.parameters.NAME`` (a preset's also ``walker.NAME``)."""
        if not isinstance(data, dict) or "parameters" not in data:
            return data
        given = data["parameters"]
        if isinstance(given, list):
            given = {p.get("name"): p.get("value") for p in given if isinstance(p, dict)}
        own = [name for name in cls.model_fields if name != "kind"]
        if not isinstance(given, dict):
            raise ValueError("parameters: expected NAME: value entries")
        if unknown := [name for name in given if name not in own]:
            listed = ", ".join(own) or "none"
            kind = data.get("kind")
            raise ValueError(
                f"parameters: the {kind} walker has no parameter {quote(unknown[0])}; its parameters: {listed}"
            )
        return {**{k: v for k, v in data.items() if k != "parameters"}, **given}

    @model_validator(mode="before")
    @classmethod
    def _no_other_kinds_fields(cls, data: Any) -> Any:
        if isinstance(data, dict) and "description" in data:
            raise ValueError(f"description: only walker.kind: description has one, not the {data.get('kind')} walker")
        others = set(LeggedPreset.model_fields) | set(FourLeggedWalker.model_fields) | {"spokes"}
        if isinstance(data, dict) and (given := sorted((others & set(data)) - set(cls.model_fields))):
            raise ValueError(f"{given[0]}: the {data.get('kind')} walker has no {given[0]} (another kind's field)")
        return data

    @property
    def description(self) -> None:
        """A preset carries no description of its own (``walkers.describe`` expands its kind)."""
        return None

    @property
    def point_feet(self) -> bool:
        """Whether a foot is a point (radius 0), which no Hertz contact can take."""
        return getattr(self, "foot_radius", 0.0) == 0.0


class LeggedPreset(Preset):
    """Straight legs with round feet, hinged at a hip (MODEL.md 1): the compass's parameters."""

    leg_length: float = Field(0.5, gt=0, description="Hip to foot bottom, l [m].")
    foot_radius: float = Field(
        0.15,
        ge=0,
        description="Foot arc radius R [m]; arc centre on the leg axis at l - R from the hip; 0 = point foot.",
    )
    leg_mass: float = Field(1.0, gt=0, description="Mass of one leg, m [kg].")
    leg_com_from_hip: float = Field(0.15, ge=0, description="Leg centre of mass distance from the hip, c [m].")
    leg_inertia: float = Field(0.005, ge=0, description="Leg moment of inertia about its centre of mass, I [kg m^2].")
    leg_com_offset: float = Field(0.0, description="Leg centre of mass across the leg, w [m] (McGeer's w), + downhill.")
    foot_offset: float = Field(0.0, description="Foot arc centre across the leg, d [m] (McGeer's d), + downhill.")
    hip_mass: float = Field(2.0, ge=0, description="Hip point mass M_H [kg], split half to each leg at the hip.")

    @model_validator(mode="after")
    def _geometry_is_possible(self) -> LeggedPreset:
        if self.foot_radius >= self.leg_length:
            raise ValueError("foot_radius: must be smaller than walker.leg_length")
        if self.leg_com_from_hip > self.leg_length:
            raise ValueError("leg_com_from_hip: must not exceed walker.leg_length")
        # the leg's mass and its foot arc centre stay within the leg's reach (the arc centre below the hip)
        if math.hypot(self.leg_com_from_hip, self.leg_com_offset) > self.leg_length:
            raise ValueError("leg_com_offset: puts the centre of mass farther than walker.leg_length from the hip")
        if abs(self.foot_offset) >= self.leg_length - self.foot_radius:
            raise ValueError("foot_offset: |foot_offset| must be smaller than walker.leg_length - walker.foot_radius")
        return self


class CompassWalker(LeggedPreset):
    """The compass walker: two straight legs, round feet, a hip joint."""

    kind: Literal["compass"] = Field("compass", description="Two straight legs, round feet, hip joint.")


class FourLeggedWalker(LeggedPreset):
    """Liu's machine: an outer and an inner pair of legs, each pair joined rigidly by a cross bar, the pairs by a
    hip axle, four disc feet (compliant; formulation.kind: spatial, or minimal for its sagittal motion)."""

    kind: Literal["four_legged"] = Field("four_legged", description="Liu's four-legged machine.")
    foot_spacing_outer: float = Field(
        0.2, gt=0, description="Lateral distance between the two outer legs (and feet) [m]."
    )
    foot_spacing_inner: float = Field(
        0.1, gt=0, description="Lateral distance between the two inner legs (and feet) [m]."
    )
    crossbar_mass: float = Field(
        0.1, ge=0, description="Mass of each cross bar [kg], a uniform rod along the hip axle joining one pair."
    )

    @model_validator(mode="after")
    def _pairs_nested(self) -> FourLeggedWalker:
        if self.foot_spacing_inner >= self.foot_spacing_outer:
            raise ValueError("foot_spacing_inner: must be smaller than walker.foot_spacing_outer")
        return self


class SimplestWalker(Preset):
    """Garcia's simplest walker (rigid only): massless legs, a hip mass, in units of g = l = hip mass = 1."""

    kind: Literal["simplest"] = Field("simplest", description="Garcia's simplest walker (rigid only, g = l = 1).")

    @property
    def leg_length(self) -> float:
        """l = 1: Garcia's unit of length."""
        return 1.0

    @property
    def point_feet(self) -> bool:
        return True


class RimlessWheelWalker(Preset):
    """The rimless wheel (rigid only): massless spokes of length leg_length, a unit point mass at the hub."""

    kind: Literal["rimless_wheel"] = Field("rimless_wheel", description="Spokes around a hub (rigid only).")
    spokes: int = Field(8, ge=3, description="Number of spokes.")
    leg_length: float = Field(0.5, gt=0, description="Spoke length, hub to foot, l [m].")

    @property
    def point_feet(self) -> bool:
        return True


class DescribedWalker(Strict):
    """A walker written as data (``walker.kind: description``): a tree of bodies, no preset's parameters.

    Its numbers may be expressions over its named ``parameters``, and its leg may be written once
    (``description.leg``, mirrored): ``description`` is the resolved tree of plain numbers, which the models
    read; the config keeps (dumps and hashes) what was written, so a study that sets a parameter changes every
    number that uses it (:mod:`biped_sim.config.parameters`).
    """

    kind: Literal["description"] = Field("description", description="The walker written in walker.description.")
    parameters: list[ParameterSpec] = Field(
        default_factory=list, description="Named numbers (name, value, unit) the description's expressions use."
    )
    description: WalkerDescription = Field(..., description="The walker as a tree of bodies (WalkerDescription).")
    _written: dict[str, Any] | None = PrivateAttr(None)  # the description as written, when it differs
    _space: SpaceDescription | None = PrivateAttr(None)  # its rigid form in space, once built

    @model_validator(mode="before")
    @classmethod
    def _no_preset_fields(cls, data: Any) -> Any:
        preset_fields = set(LeggedPreset.model_fields) | set(FourLeggedWalker.model_fields) | {"spokes"}
        if isinstance(data, dict) and (given := sorted(preset_fields & set(data) - {"kind"})):
            raise ValueError(
                f"{given[0]}: a described walker has no {given[0]} (walker.kind: description): its bodies, joints "
                "and feet are in walker.description"
            )
        return data

    @model_validator(mode="wrap")
    @classmethod
    def _resolve(cls, data: Any, handler: ValidatorFunctionWrapHandler) -> DescribedWalker:
        if not isinstance(data, dict) or not isinstance(data.get("parameters", []), list):
            return handler(data)
        try:
            parameters = [ParameterSpec.model_validate(p) for p in data.get("parameters", [])]
        except ValidationError:
            return handler(data)  # which names the parameter at fault
        names = parameter_values(parameters)
        written = data.get("description")
        evaluated = resolve_numbers(WalkerDescription, written, names, "walker.description")
        if isinstance(written, dict) and isinstance(written.get("leg"), dict):  # a leg's parts are a description's
            evaluated["leg"] = resolve_numbers(WalkerDescription, written["leg"], names, "walker.description.leg")
        if isinstance(written, dict) and isinstance(written.get("hip"), dict):  # the mirrored legs' hip joint
            evaluated["hip"] = resolve_numbers(JointSpec, written["hip"], names, "walker.description.hip")
        try:
            resolved = mirror_legs(evaluated)
        except ValueError as exc:
            raise ValueError(f"walker.description.{exc}") from None
        walker = handler({**data, "description": resolved})
        if resolved != written:
            walker._written = copy.deepcopy(written)
        return walker

    @model_serializer(mode="wrap")
    def _as_written(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        out = handler(self)
        if self._written is not None:
            out["description"] = copy.deepcopy(self._written)
        return out

    @property
    def leg_length(self) -> float:
        """Hip to the lowest foot bottom with every angle zero [m]: the walker's length scale."""
        return self.description.leg_length()

    @property
    def point_feet(self) -> bool:
        """Whether every foot is a point (radius 0): Hertz takes the largest foot's radius, and none has one."""
        return all(foot.radius == 0.0 for foot in self.description.feet)

    @property
    def space(self) -> SpaceDescription:
        """The description as the rigid model in space takes it (:func:`~biped_sim.config.space_form.space_form`;
        the config's ``in_space`` has checked that it does)."""
        if self._space is None:
            self._space = space_form(self.description)
        return self._space


_WALKER_TAGS = {
    "compass": "CompassWalker",
    "four_legged": "FourLeggedWalker",
    "simplest": "SimplestWalker",
    "rimless_wheel": "RimlessWheelWalker",
    "description": "DescribedWalker",
}  # the union's tags: class names, which the one-line error drops from a field's key


def _walker_kind(data: Any) -> Any:
    """The walker's ``kind`` (``compass`` when not given) checked before the union picks its member."""
    if not isinstance(data, dict):
        return data
    kind = data.get("kind", "compass")
    if not isinstance(kind, str) or kind not in _WALKER_TAGS:
        raise ValueError(f"kind: unknown name {quote(kind)}; expected one of {', '.join(map(repr, _WALKER_TAGS))}")
    return {"kind": kind, **data}


def _walker_tag(data: Any) -> str:
    return _WALKER_TAGS[data["kind"] if isinstance(data, dict) else data.kind]


WalkerConfig = Annotated[
    Annotated[CompassWalker, Tag("CompassWalker")]
    | Annotated[FourLeggedWalker, Tag("FourLeggedWalker")]
    | Annotated[SimplestWalker, Tag("SimplestWalker")]
    | Annotated[RimlessWheelWalker, Tag("RimlessWheelWalker")]
    | Annotated[DescribedWalker, Tag("DescribedWalker")],
    Discriminator(_walker_tag),
    BeforeValidator(_walker_kind),
]
"""The walker (MODEL.md 1): one member per ``walker.kind``, each with its own fields only (a described walker
has no compass fields, a compass no description)."""
