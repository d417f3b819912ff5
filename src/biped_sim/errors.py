"""Exceptions that the CLI turns into one-line messages with exit code 2."""

from __future__ import annotations


class ConfigError(ValueError):
    """Bad user input: names the field (dotted path, file or option) and the reason."""

    def __init__(self, field: str, reason: str) -> None:
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")
