"""The ``biped-sim`` command line: a thin typer layer over the Python API.

Each command module registers its commands on :data:`app`; every command turns bad input
(:class:`~biped_sim.errors.ConfigError`) into a one-line message and exit code 2.
"""

from __future__ import annotations

from biped_sim.cli import (
    analysis_commands,  # noqa: F401
    basin_commands,  # noqa: F401
    bench_commands,  # noqa: F401
    experiment_commands,  # noqa: F401
    fit_commands,  # noqa: F401
    robustness_commands,  # noqa: F401
    run_commands,  # noqa: F401  (registers commands)
    uncertainty_commands,  # noqa: F401
)
from biped_sim.cli.common import app


def main() -> None:
    """Console-script entry point."""
    app()
