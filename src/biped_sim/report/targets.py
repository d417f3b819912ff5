"""What ``biped-sim compare`` compares: the step periods of a config (simulated), a run directory or a sweep."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from biped_sim.config import load_config
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.io.trajectory import load_summary
from biped_sim.report.view import SweepView
from biped_sim.simulate import simulate
from biped_sim.studies.compare import model_step_periods


def compare_targets(
    target: Path, overrides: Sequence[str] = (), skip: int = 0
) -> tuple[list[tuple[str, list[float]]], str | None]:
    """(label, model step periods) of each run of ``target``, and a line on a sweep's runs without results.

    ``target`` is a config file (simulated with ``overrides``; nothing is written), a run directory or a sweep
    directory (read from disk; ``overrides`` do not apply). ``skip`` drops the first model steps.
    """
    if not target.exists():
        raise ConfigError(str(target), "no such config file, run directory or sweep directory")
    if skip < 0:
        raise ArgumentError("skip", "must be >= 0")
    if not target.is_dir():
        result = simulate(load_config(target, list(overrides)))
        label = target.stem + (f" ({', '.join(overrides)})" if overrides else "")
        return [(label, model_step_periods(result.summary["step_times"], skip))], None
    if overrides:
        raise ArgumentError("overrides", "only applies when comparing a config file, not a run or sweep directory")
    if not (target / "sweep.json").is_file():
        return [(target.name, model_step_periods(load_summary(target)["step_times"], skip))], None
    view = SweepView.load(target)
    series = [
        (view.label(row), model_step_periods(load_summary(target / "runs" / row["run"])["step_times"], skip))
        for row in view.finished
    ]
    if not series:
        raise ConfigError(str(target), "no finished run in this sweep")
    return series, view.missing_note("compared")
