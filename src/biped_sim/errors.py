"""Exceptions that the CLI turns into one-line messages with exit code 2, and the short quotes of input they hold."""

from __future__ import annotations

import reprlib
from typing import Any

FIELD_LIMIT = 400  # characters of a message's field: a dotted key, a file (and a sweep's run) or an argument
REASON_LIMIT = 600  # characters of its reason
QUOTE_LIMIT = 60  # characters of a quoted input value

_QUOTE = reprlib.Repr()  # Python 3.11: limits set as attributes
_QUOTE.maxlevel, _QUOTE.maxdict, _QUOTE.maxlist, _QUOTE.maxtuple, _QUOTE.maxset = 2, 4, 4, 4, 4
_QUOTE.maxstring = _QUOTE.maxother = QUOTE_LIMIT


def clipped(text: str, limit: int) -> str:
    """``text`` on one line (newlines shown as spaces) and at most ``limit`` characters, marked ``...`` if cut."""
    text = text.replace("\r", " ").replace("\n", " ")
    return text if len(text) <= limit else text[: limit - 3] + "..."


def quote(value: Any) -> str:
    """A short repr of an input value, read without expanding it (a YAML alias bomb is a few nested lists
    referenced billions of times: its full repr would not fit in memory)."""
    return clipped(_QUOTE.repr(value), QUOTE_LIMIT)


class ConfigError(ValueError):
    """Bad user input: names the field (dotted path, file or option) and the reason, on one bounded line."""

    def __init__(self, field: str, reason: str) -> None:
        self.field = clipped(field, FIELD_LIMIT)
        self.reason = clipped(reason, REASON_LIMIT)
        super().__init__(f"{self.field}: {self.reason}")


class ArgumentError(ConfigError):
    """Bad value of a function argument (``field`` is the argument's name): the CLI names its own option instead."""
