"""Reading configs: YAML text (with a YAML-1.2 float resolver), ``--set key=value`` overrides, and pydantic's
errors turned into one-line :class:`~biped_sim.errors.ConfigError` messages naming the dotted field."""

from __future__ import annotations

import copy
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from biped_sim.config.parameters import written_field
from biped_sim.config.schema import Config
from biped_sim.errors import ArgumentError, ConfigError, quote

MAX_FILE_BYTES = 256 * 1024  # a config, sweep, reference or uncertainty file: the largest bundled one is 4 KiB


class _Loader(yaml.SafeLoader):
    """SafeLoader that reads ``1e7`` as a float (YAML 1.2) and ``on``/``off`` as strings."""


_FLOAT_RE = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |\.[0-9_]+(?:[eE][-+][0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.X,
)
_Loader.yaml_implicit_resolvers = {
    key: [(tag, rx) for tag, rx in resolvers if tag not in ("tag:yaml.org,2002:float", "tag:yaml.org,2002:bool")]
    for key, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_RE, list("-+0123456789."))
_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


def parse_yaml(text: str, source: str = "<string>") -> Any:
    """Parse YAML text with the project's loader; a syntax error becomes a one-line ConfigError."""
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(source, f"malformed YAML{where}: {problem}") from None


def apply_override(data: dict[str, Any], assignment: str) -> None:
    """Apply one ``dotted.key=value`` override (value parsed as YAML) to a raw config dict in place.

    A malformed one is an :class:`~biped_sim.errors.ArgumentError` of ``overrides`` (the CLI's ``--set``).
    """
    if "=" not in assignment:
        raise ArgumentError("overrides", f"expected KEY=VALUE, got {quote(assignment)}")
    key, _, raw_value = assignment.partition("=")
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise ArgumentError("overrides", f"invalid key {quote(key)}")
    try:
        value = parse_yaml(raw_value, source=key)
    except ConfigError as exc:
        raise ArgumentError("overrides", str(exc)) from None
    set_dotted(data, key, value)


def set_dotted(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``data[a][b][c] = value`` for ``key = 'a.b.c'``, creating sections as needed.

    A list of named items (a description's bodies, joints, feet) is entered by an item's name
    (``walker.description.bodies.thigh_1.mass``) or its index; an unknown name or an index out of range is a
    one-line ConfigError naming the list and its names. A key ending at a named parameter (an item with a
    ``value``: ``walker.parameters.thigh_mass``) sets its value.
    """
    parts = key.split(".")
    node: Any = data
    for depth, part in enumerate(parts[:-1]):
        if isinstance(node, list):
            node = node[_list_index(node, parts, depth)]
            continue
        child = node.get(part) if isinstance(node, dict) else None
        if not isinstance(child, dict | list):
            child = {}
            node[part] = child
        node = child
    slot = _list_index(node, parts, len(parts) - 1) if isinstance(node, list) else parts[-1]
    current = node[slot] if isinstance(node, list) else node.get(slot)
    if isinstance(current, dict) and "value" in current and not isinstance(value, dict):
        current["value"] = value  # a named parameter stands for its value
    else:
        node[slot] = value


def get_dotted(data: Any, key: str) -> Any:
    """The entry ``key`` (dotted, list items by name or index as :func:`set_dotted`; a named parameter's value)
    of plain config data; ConfigError naming the key when a section or field on the way is missing."""
    parts = key.split(".")
    node = data
    for depth, part in enumerate(parts):
        if isinstance(node, list):
            node = node[_list_index(node, parts, depth)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, dict) and part == "parameters" and depth + 1 < len(parts) and parts[depth + 1] in node:
            continue  # a preset's parameters are its fields: walker.parameters.leg_inertia is walker.leg_inertia
        else:
            raise ConfigError(key, "unknown config key")
    return node["value"] if isinstance(node, dict) and "value" in node else node  # a parameter: its value


def _list_index(items: list[Any], parts: list[str], depth: int) -> int:
    """The position in ``items`` (the list at ``parts[:depth]``) of the item ``parts[depth]`` names: an item's
    ``name`` or an index; ConfigError naming the list (and its names) when there is no such item."""
    part, where = parts[depth], ".".join(parts[:depth])
    names = [item.get("name") if isinstance(item, dict) else None for item in items]
    if part in names:
        return names.index(part)
    if part.lstrip("-").isdigit():
        if -len(items) <= int(part) < len(items):
            return int(part)
        raise ConfigError(where, f"no item {part} (the list has {len(items)})")
    listed = ", ".join(str(n) for n in names if n is not None)
    raise ConfigError(where, f"no item named {quote(part)}" + (f"; the names are {listed}" if listed else ""))


_UNION_TAG = re.compile(r"^([A-Z][A-Za-z]*|literal\[.*\]|tuple\[.*\])$")


def _format_validation_error(exc: ValidationError) -> ConfigError:
    """Turn pydantic's first error into one line: dotted field and reason."""
    err = exc.errors()[0]
    # a union (simulation.initial, a push's impulse) tags its members' errors with the member type: not part of the key
    loc = ".".join(str(part) for part in err["loc"] if not _UNION_TAG.match(str(part)))
    message = err["msg"]
    if message.startswith("Value error, "):
        message = message[len("Value error, ") :]
        # validators name their own field as "field: reason"
        field, sep, reason = message.partition(": ")
        if sep and "." not in field and loc:
            return ConfigError(f"{loc}.{field}", reason)
        if sep:
            return ConfigError(field, reason)
    if err["type"] == "extra_forbidden":
        message = "unknown key (not in the schema)"
    elif err["type"] == "literal_error":
        message = f"unknown name {quote(err.get('input'))}; {message[0].lower()}{message[1:]}"
    return ConfigError(loc or "config", message)


def config_from_dict(data: Any, overrides: list[str] | tuple[str, ...] = ()) -> Config:
    """Validate a raw dict (plus ``KEY=VALUE`` overrides) into a :class:`Config`."""
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError("config", "top level must be a mapping of sections")
    data = copy.deepcopy(data)
    for assignment in overrides:
        apply_override(data, assignment)
    try:
        return Config.model_validate(data)
    except ValidationError as exc:
        raise _as_written(_format_validation_error(exc), data) from None


def _as_written(error: ConfigError, data: dict[str, Any]) -> ConfigError:
    """``error`` naming its field as the user wrote it: a described walker's part by its name, or by its path in
    the leg written once (and which copy of it), not by its place in the resolved description."""
    walker = data.get("walker")
    if not isinstance(walker, dict) or walker.get("kind") != "description":
        return error
    field, note = written_field(walker.get("description"), error.field)
    return error if (field, note) == (error.field, "") else ConfigError(field, error.reason + note)


def derive(config: Config, values: Mapping[str, Any]) -> Config:
    """``config`` with the dotted keys of ``values`` set (``{"ground.slope": 0.01}``), validated again.

    The one way a study makes a variant of a config: the values are set on the canonical dict
    (``model_dump(mode="json")``) and the whole is validated, so a variant obeys every rule a loaded
    config does; an invalid value is a ConfigError naming its key.
    """
    data = config.model_dump(mode="json")
    for key, value in values.items():
        set_dotted(data, key, value)
    return config_from_dict(data)


def read_text_file(path: str | Path, what: str = "config file") -> str:
    """The text of a UTF-8 file; ConfigError naming the path when it is missing, a directory, not text or larger
    than :data:`MAX_FILE_BYTES` (a file that size is generated, and reading it would take minutes)."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(str(path), f"is a directory, not a {what}")
    if not path.is_file():
        raise ConfigError(str(path), f"no such {what}")
    try:
        if (size := path.stat().st_size) > MAX_FILE_BYTES:
            raise ConfigError(str(path), f"{size:,} bytes, larger than a {what} may be ({MAX_FILE_BYTES // 1024} KiB)")
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(str(path), f"not a UTF-8 text file (byte {exc.start}): is it a {what}?") from None
    except OSError as exc:
        raise ConfigError(str(path), f"cannot read: {exc.strerror}") from None


def load_config(path: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> Config:
    """Read and validate a YAML config file; raises ConfigError with a one-line reason."""
    text = read_text_file(path)
    return config_from_dict(parse_yaml(text, source=str(path)), overrides)


def default_output_dir(config: Config, config_path: str | Path | None) -> Path:
    """Run directory: ``output.dir`` if set, else results/runs/<config stem>."""
    if config.output.dir:
        return Path(config.output.dir)
    stem = Path(config_path).stem if config_path else "run"
    return Path("results") / "runs" / stem
