"""What every section of the schema shares: strict models (unknown keys, non-finite numbers and booleans-as-numbers
refused) and the names of the contact laws, read from their registries."""

from __future__ import annotations

import types
import typing
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, model_validator

from biped_sim.contact.friction import FRICTION_LAWS
from biped_sim.contact.normal import NORMAL_LAWS
from biped_sim.errors import quote

# the law names come from the registries: a new law is one function and one registry line
NormalModelName = Literal[tuple(NORMAL_LAWS)]  # type: ignore[valid-type]
FrictionModelName = Literal[tuple(FRICTION_LAWS)]  # type: ignore[valid-type]
Vector2 = tuple[float, float]  # a point in a body's plane (x', y')
IN_SPACE = "formulation.kind: spatial with dynamics: compliant"  # where a description's features in space act


def is_number_annotation(annotation: Any) -> bool:
    """Whether a field's type is a number (float, int, or one of them or None)."""
    if annotation in (float, int):
        return True
    if typing.get_origin(annotation) is tuple:  # a vector of numbers (simulation.pushes' impulse)
        return all(is_number_annotation(arg) for arg in typing.get_args(annotation))
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return any(is_number_annotation(arg) for arg in typing.get_args(annotation))
    return False


class Strict(BaseModel):
    """Base for every section: unknown keys are rejected, numbers are finite and never true/false."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _booleans_are_not_numbers(cls, data: Any) -> Any:
        # YAML reads `true` as a boolean and pydantic would take it as 1.0 for a mass or a time
        if isinstance(data, dict):
            for name, value in data.items():
                field = cls.model_fields.get(name)
                numbers = value if isinstance(value, list) else [value]
                if (
                    field is not None
                    and is_number_annotation(field.annotation)
                    and any(isinstance(v, bool) for v in numbers)
                ):
                    raise ValueError(f"{name}: expected a number, got {quote(value).lower()}")
        return data
