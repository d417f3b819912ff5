"""Shared pieces of the CLI: the typer app, the ``--set`` option and error reporting.

Exit codes: 0 done; 1 done with failed runs or failed checks, or the system failed while writing (no
space left, an I/O error) though the input was fine; 2 bad input or an unusable output location (no
permission, read-only, not a directory); 130 interrupted (Ctrl-C).
"""

from __future__ import annotations

import errno
import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from biped_sim.config import Config, load_config
from biped_sim.errors import ConfigError

app = typer.Typer(
    name="biped-sim",
    help="Passive dynamic walkers with compliant, dissipative foot-ground contact and friction.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

SetOption = Annotated[
    list[str] | None,
    typer.Option("--set", help="Override a config field: dotted KEY=VALUE, value parsed as YAML (repeatable)."),
]
ConfigArgument = Annotated[Path, typer.Argument(help="YAML config file.")]

F = TypeVar("F", bound=Callable[..., Any])

# File-system errors caused by where the user pointed a command (exit 2); any other is the system's (exit 1).
LOCATION_ERRNOS = frozenset(
    {errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOTDIR, errno.EISDIR, errno.ENOENT, errno.ENAMETOOLONG}
)


def fail(message: str, code: int = 2) -> None:
    """Print a one-line error to stderr and exit with ``code``."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def os_error_line(exc: OSError) -> str:
    """'path: No space left on device' (the path when the error names one)."""
    reason = exc.strerror or str(exc)
    return f"{exc.filename}: {reason}" if exc.filename else reason


def user_errors(func: F) -> F:
    """Decorator: ConfigError (bad input) -> one line on stderr, exit code 2; a file-system error -> one line,
    exit code 2 or 1 (:data:`LOCATION_ERRNOS`); Ctrl-C -> exit code 130. Never a traceback for these."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except ConfigError as exc:
            fail(str(exc))
        except OSError as exc:
            fail(os_error_line(exc), 2 if exc.errno in LOCATION_ERRNOS else 1)
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            sys.exit(130)

    return wrapper  # type: ignore[return-value]


def load(config_path: Path, overrides: list[str] | None) -> Config:
    """Load a config with ``--set`` overrides (ConfigError on bad input)."""
    return load_config(config_path, overrides or [])
