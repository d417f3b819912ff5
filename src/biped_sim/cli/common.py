"""Shared pieces of the CLI: the typer app, the ``--set`` option and error reporting.

Exit codes: 0 done; 1 done with failed runs or failed checks, or the system failed while writing (no
space left, an I/O error) though the input was fine; 2 bad input (a bad option or argument, from typer or
from the API) or an unusable output location (no permission, read-only, not a directory); 130 interrupted
(Ctrl-C); 143 terminated (SIGTERM, as schedulers and Dask stop a job). Each is one line on stderr.
"""

from __future__ import annotations

import errno
import functools
import signal
import sys
import threading
import typing
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, NoReturn, TypeVar

import typer
from rich.markup import escape
from typer.core import TyperGroup
from typer.models import OptionInfo

from biped_sim.config import Config, load_config
from biped_sim.errors import ArgumentError, ConfigError, clipped

# `biped-sim --help` lists the commands in the order a user meets them: a run and what is made of runs, the
# studies, then the tools
COMMAND_ORDER = (
    "run", "sweep", "report", "plot", "animate", "compare", "fit",
    "limit-cycle", "bifurcation", "basin", "robustness", "uncertainty", "mfpt", "converge",
    "validate", "bench", "warmup", "drop-test",
)  # fmt: skip
ARGUMENT_FLAGS = {"overrides": "--set"}  # API arguments every command takes under another name
INTERRUPTED, TERMINATED = 130, 143  # 128 + SIGINT, 128 + SIGTERM


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C's KeyboardInterrupt so that a command stops the same way (workers ended,
    files consistent), then exits with 143."""


class Commands(TyperGroup):
    """The app's command group: commands in ``COMMAND_ORDER``, help shown as written (rich would take
    ``[s]`` or ``[default 1.0]`` for markup and drop it), and every usage error typer finds on one line."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        for command in self.commands.values():
            command.help = command.help and escape(command.help)
            for param in command.params:
                if getattr(param, "help", None):
                    param.help = escape(param.help)  # type: ignore[attr-defined]

    def list_commands(self, ctx: Any) -> list[str]:
        def rank(name: str) -> int:
            return COMMAND_ORDER.index(name) if name in COMMAND_ORDER else len(COMMAND_ORDER)

        return sorted(super().list_commands(ctx), key=rank)

    def main(self, *args: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        if not standalone_mode:
            return super().main(*args, standalone_mode=False, **kwargs)
        try:
            code = super().main(*args, standalone_mode=False, **kwargs)
        except typer.TyperException as exc:  # typer's usage errors (click's, vendored)
            if type(exc).__name__ == "NoArgsIsHelpError":  # `biped-sim` alone: the help, printed already
                sys.exit(exc.exit_code)
            context = getattr(exc, "ctx", None)
            hint = f" (see {context.command_path} --help)" if context is not None else ""
            typer.echo(f"error: {clipped(exc.format_message(), 300)}{hint}", err=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            typer.echo("error: aborted", err=True)
            sys.exit(1)
        sys.exit(code if isinstance(code, int) else 0)


app = typer.Typer(
    name="biped-sim",
    help="Passive dynamic walkers with compliant, dissipative foot-ground contact and friction.",
    cls=Commands,
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


def option_flags(command: Callable[..., Any]) -> dict[str, str]:
    """A command's option flags by parameter name (``steps`` -> ``--steps``), from its typer annotations."""
    flags = dict(ARGUMENT_FLAGS)
    for name, hint in typing.get_type_hints(command, include_extras=True).items():
        for info in getattr(hint, "__metadata__", ()):
            if not isinstance(info, OptionInfo):
                continue
            # typer.Option("--steps", "-s"): under Annotated the first declaration is read as the default
            first = [info.default] if isinstance(info.default, str) and info.default.startswith("-") else []
            declared = [*first, *(info.param_decls or ())]
            if declared:
                flags[name] = next((flag for flag in declared if flag.startswith("--")), declared[0])
    return flags


def _terminate(signum: int, frame: object) -> None:
    raise Terminated


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Inside the block SIGTERM raises :class:`Terminated` (in the main thread, where signals are delivered)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        if signal.getsignal(signal.SIGTERM) is _terminate:  # not ignored by end_interrupted meanwhile
            signal.signal(signal.SIGTERM, previous)


def end_interrupted(exc: KeyboardInterrupt, message: str | None = None) -> NoReturn:
    """Exit after Ctrl-C (130) or SIGTERM (143) with one line (``message`` after 'interrupted: ' or 'terminated: ').

    Later Ctrl-C's and SIGTERMs are ignored from here on: the command has stopped its work already, and a
    second Ctrl-C during the exit must not end the process by the signal instead of the exit code.
    """
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_IGN)
    how = "terminated" if isinstance(exc, Terminated) else "interrupted"
    typer.echo(f"{how}: {message}" if message else how, err=True)
    sys.exit(TERMINATED if isinstance(exc, Terminated) else INTERRUPTED)


def user_errors(func: F) -> F:
    """Decorator of a command: bad input (ConfigError) -> one line on stderr, exit code 2, an API argument's
    error named by the command's option (``steps`` -> ``--steps``); a file-system error -> one line, exit code
    2 or 1 (:data:`LOCATION_ERRNOS`); Ctrl-C -> 130, SIGTERM -> 143. Never a traceback for these."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            with sigterm_as_interrupt():
                return func(*args, **kwargs)
        except ArgumentError as exc:
            fail(f"{option_flags(func).get(exc.field, exc.field)}: {exc.reason}")
        except ConfigError as exc:
            fail(str(exc))
        except OSError as exc:
            fail(os_error_line(exc), 2 if exc.errno in LOCATION_ERRNOS else 1)
        except KeyboardInterrupt as exc:
            end_interrupted(exc)

    return wrapper  # type: ignore[return-value]


def load(config_path: Path, overrides: list[str] | None) -> Config:
    """Load a config with ``--set`` overrides (ConfigError on bad input)."""
    return load_config(config_path, overrides or [])
