"""Shared pieces of the CLI: the typer app, the ``--set`` option and error reporting."""

from __future__ import annotations

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


def fail(message: str, code: int = 2) -> None:
    """Print a one-line error to stderr and exit with ``code``."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def user_errors(func: F) -> F:
    """Decorator: ConfigError (bad input) -> one line on stderr, exit code 2, no traceback."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except ConfigError as exc:
            fail(str(exc))
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            sys.exit(130)

    return wrapper  # type: ignore[return-value]


def load(config_path: Path, overrides: list[str] | None) -> Config:
    """Load a config with ``--set`` overrides (ConfigError on bad input)."""
    return load_config(config_path, overrides or [])
