"""Runs that could never end or never fit, and sweeps or studies of too many runs, are refused before they start,
naming the field to change.

A run samples its state every ``1 / output.sample_rate`` seconds up to ``simulation.t_end``; the samples
and the channels measured from them live in memory until the run is written. A fixed-step method takes
``t_end / dt`` steps, an adaptive one at least ``t_end / max_step``. Either count past these budgets is a
typo (``t_end: 1e9``, ``max_step: 1e-300``), not a study: one line says which field to change.
"""

from __future__ import annotations

import math

from biped_sim.config import Config
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.integrate.driver import takes_fixed_steps

MAX_RUNS = 1_000_000  # runs of a sweep, cells of a basin, samples of a study: more is refused before it starts
MEMORY_BUDGET_BYTES = 4 * 2**30  # samples x channels x 8 bytes, with the copies measuring makes
MAX_INTEGRATION_STEPS = 1e9  # about 20 minutes of the fastest compiled loop
MEASURE_COPIES = 3  # the recorder, its trimmed copy and the measured channels


def check_run_count(count: float, field: str, what: str = "runs") -> None:
    """ArgumentError naming ``field`` when a sweep or study would make more than ``MAX_RUNS`` runs."""
    if not count <= MAX_RUNS:
        raise ArgumentError(field, f"{count:,.0f} {what}, more than the limit of {MAX_RUNS:,}")


def check_run_size(config: Config, values_per_sample: int) -> None:
    """ConfigError when the trajectory would not fit in memory or the integration needs too many steps."""
    if config.simulation.t_end * config.output.sample_rate < 1.0:
        raise ConfigError(
            "output.sample_rate",
            "no sample after the start (simulation.t_end x output.sample_rate < 1): the run's energy balance and "
            "constraints could not be measured",
        )
    samples = config.simulation.t_end * config.output.sample_rate + 2
    need = samples * values_per_sample * 8 * MEASURE_COPIES
    if need > MEMORY_BUDGET_BYTES:
        raise ConfigError(
            "output.sample_rate",
            f"{samples:.3g} samples of {values_per_sample} values (simulation.t_end x output.sample_rate) need "
            f"{need / 2**30:.3g} GiB, over the {MEMORY_BUDGET_BYTES / 2**30:.0f} GiB budget: lower either",
        )
    if config.dynamics == "rigid":
        return
    integ = config.integrator
    fixed = takes_fixed_steps(integ)
    field, step = ("integrator.dt", integ.dt) if fixed else ("integrator.max_step", integ.max_step)
    if fixed and integ.dt > config.simulation.t_end:
        raise ConfigError(
            "integrator.dt", f"{integ.dt:g} s is longer than simulation.t_end ({config.simulation.t_end:g} s)"
        )
    steps = config.simulation.t_end / step
    if not math.isfinite(steps) or steps > MAX_INTEGRATION_STEPS:
        raise ConfigError(
            field,
            f"simulation.t_end / {field.split('.')[1]} = {steps:.3g} steps, over the budget of "
            f"{MAX_INTEGRATION_STEPS:.0e}: a larger step or a shorter run",
        )
