"""A described walker's named parameters and its mirrored leg: what a user writes, resolved into plain numbers.

``walker.parameters`` declares named numbers (name, value, unit); a number of the description (a mass, an
inertia, a coordinate of a centre of mass, a joint's place, a stop's angle, a foot's radius) may be an
arithmetic expression over them, read by walking its syntax tree (numbers, names, + - * / **, parentheses and a
few functions), never by ``eval``. A leg may be written once (``description.leg``) and mirrored into two legs
with the hip joint between them, so "the thigh's mass" is one number. The config keeps what was written; the
walker's model reads the resolved description (:func:`resolve_description`).
"""

from __future__ import annotations

import ast
import copy
import functools
import math
import operator
import types
import typing
from collections.abc import Callable, Mapping
from typing import Any

from pydantic import BaseModel, Field

from biped_sim.config.base import Strict, is_number_annotation
from biped_sim.errors import quote

MAX_EXPRESSION = 200  # characters: a formula, not a program

_OPERATORS: dict[type, Callable[..., float]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.USub: operator.neg,
    ast.UAdd: operator.pos,
}
FUNCTIONS: dict[str, Callable[..., float]] = {
    "sqrt": math.sqrt, "sin": math.sin, "cos": math.cos, "tan": math.tan, "atan": math.atan, "atan2": math.atan2,
    "exp": math.exp, "log": math.log, "abs": abs, "min": min, "max": max,
}  # fmt: skip
CONSTANTS = {"pi": math.pi}


class ParameterSpec(Strict):
    """A named number of a described walker, used by name in its description's expressions."""

    name: str = Field(..., pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", description="The name expressions use.")
    value: float = Field(..., description="Its value, in its unit.")
    unit: str = Field("", description="Its unit (documentation: kg, m, kg m^2, rad, ...).")


def evaluate(text: str, names: Mapping[str, float]) -> float:
    """The value of arithmetic expression ``text`` over ``names``; ValueError with a one-line reason."""
    if len(text) > MAX_EXPRESSION:
        raise ValueError(f"expression longer than {MAX_EXPRESSION} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise ValueError(f"{quote(text)} is not an arithmetic expression") from None
    try:
        value = float(_value(tree.body, names))
    except (ArithmeticError, TypeError, ValueError) as exc:
        if isinstance(exc, _RefusedError):
            raise ValueError(f"{exc} in {quote(text)}") from None
        raise ValueError(f"{quote(text)} has no finite value ({exc})") from None
    if not math.isfinite(value):
        raise ValueError(f"{quote(text)} has no finite value")
    return value


class _RefusedError(ValueError):
    """A part of an expression that is not arithmetic on the known names."""


def _value(node: ast.AST, names: Mapping[str, float]) -> float:
    """One node of an expression's syntax tree, evaluated (numbers as floats: no huge integers)."""
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return float(node.value)
    if isinstance(node, ast.Name):
        if node.id in names:
            return names[node.id]
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        known = ", ".join(sorted(names)) or "none"
        raise _RefusedError(f"unknown name {quote(node.id)} (the parameters: {known})")
    if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
        return _OPERATORS[type(node.op)](_value(node.left, names), _value(node.right, names))
    if isinstance(node, ast.UnaryOp) and type(node.op) in _OPERATORS:
        return _OPERATORS[type(node.op)](_value(node.operand, names))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS:
        if node.keywords:
            raise _RefusedError(f"{node.func.id}() takes no keywords")
        return float(FUNCTIONS[node.func.id](*(_value(arg, names) for arg in node.args)))
    allowed = ", ".join(FUNCTIONS)
    raise _RefusedError(f"only numbers, parameter names, + - * / ** and {allowed} are allowed")


def parameter_values(parameters: list[ParameterSpec]) -> dict[str, float]:
    """Name -> value; ValueError naming a parameter given twice."""
    values: dict[str, float] = {}
    for p in parameters:
        if p.name in values or p.name in CONSTANTS or p.name in FUNCTIONS:
            raise ValueError(f"parameters: {p.name!r} is given twice or names a constant or function")
        values[p.name] = p.value
    return values


def resolve_numbers(model: type[BaseModel], data: Any, names: Mapping[str, float], where: str) -> Any:
    """A copy of raw ``data`` for ``model`` with every expression in a number field evaluated (lists of records
    and nested records followed); ValueError ``"<dotted field>: reason"`` for an expression that fails."""
    if not isinstance(data, dict):
        return data
    numbers, records = _field_kinds(model)
    out = dict(data)
    for key, value in data.items():
        if key in numbers and isinstance(value, str | list | tuple):  # an expression, or a vector of them
            out[key] = _numbers(value, names, f"{where}.{key}")
        elif key in records and isinstance(value, list):
            out[key] = [resolve_numbers(records[key], item, names, f"{where}.{key}.{_label(item, i)}") for i, item in
                        enumerate(value)]  # fmt: skip
        elif key in records and isinstance(value, dict):  # a record of its own (a body's inertia_tensor)
            out[key] = resolve_numbers(records[key], value, names, f"{where}.{key}")
    return out  # a key outside the model is left for the model to refuse


@functools.cache
def _field_kinds(model: type[BaseModel]) -> tuple[frozenset[str], dict[str, type[BaseModel]]]:
    """The model's number fields, and its fields that are lists of records with their record type."""
    fields = model.model_fields.items()
    numbers = frozenset(key for key, field in fields if is_number_annotation(field.annotation))
    records = {key: record for key, field in fields if (record := _record_type(field.annotation)) is not None}
    return numbers, records


def _record_type(annotation: Any) -> type[BaseModel] | None:
    """The record type of a ``list[Record]`` or a ``Record | None`` field, else None."""
    args = typing.get_args(annotation)
    origin = typing.get_origin(annotation)
    if origin is list and args and isinstance(args[0], type) and issubclass(args[0], BaseModel):
        return args[0]
    if origin in (typing.Union, types.UnionType) and len(records := [a for a in args if _is_record(a)]) == 1:
        return records[0]
    return None


def _is_record(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def _label(item: Any, index: int) -> str:
    """An item of a list as a dotted key names it: its name (a key ``set_dotted`` finds it by), else its index."""
    name = item.get("name") if isinstance(item, dict) else None
    return name if isinstance(name, str) and name and "." not in name else str(index)


def _numbers(value: Any, names: Mapping[str, float], where: str) -> Any:
    """An expression evaluated (a vector's entries each); anything else left for the model to check."""
    if isinstance(value, str):
        try:
            return evaluate(value, names)
        except ValueError as exc:
            raise ValueError(f"{where}: {exc}") from None
    if isinstance(value, list | tuple):
        return [_numbers(v, names, where) for v in value]
    return value


# --- the mirrored leg -------------------------------------------------------------------------------------------

LEG_PARTS = ("bodies", "point_masses", "joints", "feet")


def mirror_legs(description: dict[str, Any]) -> dict[str, Any]:
    """A description whose ``leg`` (its bodies, point masses, joints and feet, hip first) is written once, as two
    legs: each name suffixed ``_1`` and ``_2``, the two legs' parts in pairs (thigh_1, thigh_2, shank_1, ...), the
    second leg's hip body hinged to the first's at the hip (the joint ``hip``, or the mapping ``hip`` for its other
    fields; a ``lateral`` there is the hip width), the second leg the first's mirror image (its joints' and feet's
    ``lateral`` negated); the description's own bodies, point masses, joints and feet (a torso, the hip's mass)
    follow. A description without ``leg`` is returned as it is."""
    if not isinstance(description, dict) or "leg" not in description:
        return description
    leg, out = description["leg"], copy.deepcopy({k: v for k, v in description.items() if k not in ("leg", "hip")})
    if not isinstance(leg, dict) or not isinstance(leg.get("bodies"), list) or not leg["bodies"]:
        raise ValueError("leg: expected a mapping with the leg's bodies (hip first), joints and feet")
    if "legs" in out:
        raise ValueError("legs: follows from the mirrored leg (walker.description.leg), do not give it too")
    if unknown := sorted(set(leg) - set(LEG_PARTS)):
        raise ValueError(f"leg: unknown key {unknown[0]!r} (a leg has {', '.join(LEG_PARTS)})")
    for part in LEG_PARTS:
        if not isinstance(out.get(part, []), list):  # a key such as bodies.thigh_1.mass set on the written form
            raise ValueError(
                f"{part}: expected a list (of the parts off the mirrored leg); the leg's own are "
                f"walker.description.leg.{part}, named without their _1 or _2"
            )
    own = {str(item.get("name")) for part in LEG_PARTS for item in leg.get(part, []) if isinstance(item, dict)}
    copies = [_leg_copy(leg, own, f"_{k}") for k in (1, 2)]
    _mirror_lateral(copies[1])
    hip_body = f"{leg['bodies'][0].get('name')}"
    hip = {"name": "hip", **(description.get("hip") or {}), "parent": f"{hip_body}_1", "child": f"{hip_body}_2"}
    for part in LEG_PARTS:
        pairs = zip(copies[0].get(part, []), copies[1].get(part, []), strict=True)  # as hand-written: thigh_1, thigh_2
        out[part] = [*(item for pair in pairs for item in pair), *out.get(part, [])]
    out["joints"] = [hip, *out["joints"]]
    out["legs"] = [[b["name"] for b in c["bodies"]] for c in copies]
    return out


MIRRORED = {  # what the mirror across the sagittal plane (z' -> -z') negates: part -> (key, entries or None)
    "joints": (("lateral", None), ("axis", (0, 1))),  # an axis is a turn's: its in-plane components flip
    "feet": (("lateral", None), ("normal", (2,))),  # a plane's normal is a direction: its z' component flips
    "bodies": (("com_lateral", None),),
    "point_masses": (("lateral", None),),
}


def _mirror_lateral(leg: dict[str, Any]) -> None:
    """The second leg is the first's mirror image across its sagittal plane: its joints', feet's and point masses'
    ``lateral`` places, its bodies' ``com_lateral``, its feet's plane normals' z' component, its joints' axes (x' and y'
    components: z' -> -z' turns a rotation's sense) and its bodies' tensors' xz and yz products negated (numbers by now:
    the parameters are evaluated before the mirror)."""
    for part, keys in MIRRORED.items():
        for item in (i for i in leg.get(part, []) if isinstance(i, dict)):
            for key, entries in keys:
                value = item.get(key)
                if entries is None and isinstance(value, int | float):
                    item[key] = -value
                elif entries is not None and isinstance(value, list | tuple) and len(value) == 3:
                    item[key] = [-v if k in entries and isinstance(v, int | float) else v for k, v in enumerate(value)]
            tensor = item.get("inertia_tensor") if part == "bodies" else None
            if isinstance(tensor, dict):
                item["inertia_tensor"] = {**tensor, **{k: -tensor[k] for k in ("xz", "yz")
                                                       if isinstance(tensor.get(k), int | float)}}  # fmt: skip


def _leg_copy(leg: dict[str, Any], own: set[str], suffix: str) -> dict[str, Any]:
    """The leg with each of its own names (bodies, joints, feet, point masses and the bodies they name) suffixed."""
    renamed = copy.deepcopy(leg)
    for part in LEG_PARTS:
        for item in renamed.get(part, []):
            if isinstance(item, dict):
                for key in ("name", "body", "parent", "child"):
                    if isinstance(item.get(key), str) and item[key] in own:
                        item[key] += suffix
    return renamed


# --- what the user wrote of a resolved field -----------------------------------------------------------------------

WRITTEN_AS = "_written_as"  # a skeleton part's path as written (no schema has the key)


def written_field(description: Any, field: str, where: str = "walker.description") -> tuple[str, str]:
    """The dotted path the user wrote of ``field``, a field of the resolved ``description`` at ``where`` (its part
    by index or resolved name: ``walker.description.bodies.3.mass``), and a note naming the copy of the mirrored leg
    it is in ("" when in none): a part of the mirrored leg is its path in ``leg``, the hip joint ``hip``, any other
    part its name. ``description`` is what was written (plain data, expressions unevaluated); a field outside its
    parts, or one it cannot place, is returned as it is, so that an error message always names a field."""
    part, _, rest = field.removeprefix(f"{where}.").partition(".")
    label, dot, tail = rest.partition(".")
    if not field.startswith(f"{where}.") or part not in LEG_PARTS or not isinstance(description, dict):
        return field, ""
    try:
        resolved = mirror_legs(_skeleton(description)).get(part, [])
    except ValueError:  # a malformed leg: the error at hand is that
        return field, ""
    names = [item.get("name") for item in resolved]
    index = names.index(label) if label in names else int(label) if label.isdigit() else len(resolved)
    if index >= len(resolved):
        return field, ""
    path, name = resolved[index][WRITTEN_AS], resolved[index].get("name")
    copy_of = {"_1": "the leg as written", "_2": "the mirror image of the leg as written"}
    note = f" (in {name}, {copy_of[name[-2:]]})" if path.startswith("leg.") and isinstance(name, str) else ""
    return f"{where}.{path}{dot}{tail}", note


def _skeleton(description: dict[str, Any]) -> dict[str, Any]:
    """The description's parts reduced to their names and their paths as written, in the form :func:`mirror_legs`
    takes: mirrored as the description is, each resolved part says where it was written."""

    def parts(section: Any, prefix: str) -> dict[str, list[dict[str, Any]]]:
        lists = {part: items for part in LEG_PARTS if isinstance(items := section.get(part), list)}
        return {part: [{**({"name": item["name"]} if isinstance(item, dict) and "name" in item else {}),
                        WRITTEN_AS: f"{prefix}{part}.{_label(item, i)}"} for i, item in enumerate(items)]
                for part, items in lists.items()}  # fmt: skip

    out: dict[str, Any] = parts(description, "")
    if "leg" in description:
        leg, hip = description["leg"], description.get("hip")
        out["leg"] = parts(leg, "leg.") if isinstance(leg, dict) else leg
        out["hip"] = {**({"name": hip["name"]} if isinstance(hip, dict) and "name" in hip else {}), WRITTEN_AS: "hip"}
    return out
