"""Warm-up: compile (or load from numba's on-disk cache) the kernels of a run before it is timed or awaited.

A compliant run needs the compiled code of its group only: its formulation's kernels and its
integrator family's loop (every explicit method shares one compiled loop, Radau and BDF share the
scipy driver's compiled right-hand side). Every contact law is part of each group's kernels (the laws
are dispatched at run time). :func:`warm_up` runs a config for a millisecond once per process and
group; ``biped-sim warmup`` (and ``make setup``) warms the default walker's group, ``--all`` every
formulation and integrator family of the package; a sweep's workers warm each group before its
first timed run, and a Dask worker can warm itself at start (:mod:`biped_sim.sweep.preload`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import get_args

from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config, FormulationConfig, config_from_dict
from biped_sim.integrate.driver import STIFF_METHODS
from biped_sim.simulate import simulate

WARM_UP_TIME = 0.001  # [s] simulated by a warm-up run
_WARMED: set[tuple[str, str]] = set()


@dataclass(frozen=True)
class WarmUp:
    """What warming one group took: the functions numba compiled (none: all came from the cache), wall time."""

    formulation: str
    family: str  # 'explicit' or 'stiff'
    method: str  # the integrator the group was warmed with
    compiled: tuple[str, ...]
    seconds: float

    def line(self) -> str:
        """One line for the terminal."""
        how = f"compiled {len(self.compiled)} functions" if self.compiled else "loaded from the cache"
        return f"{self.formulation} {self.family} ({self.method}): {how} in {self.seconds:.1f} s"


def integrator_family(method: str) -> str:
    """'stiff' (scipy's Radau/BDF over the compiled right-hand side) or 'explicit' (the compiled loop)."""
    return "stiff" if method in STIFF_METHODS else "explicit"


def warm_up(config: Config) -> WarmUp | None:
    """Run ``config`` for a millisecond, once per process and (formulation, integrator family).

    Returns what it took, or None when there was nothing to do: a rigid run (no compiled code) or a
    group already warmed in this process.
    """
    if config.dynamics == "rigid":
        return None
    group = (config.formulation.kind, integrator_family(config.integrator.method))
    if group in _WARMED:
        return None
    # at least one step and one sample after the start, so that the short run passes the run's own checks
    t_end = max(WARM_UP_TIME, config.integrator.dt)
    short = config_from_dict(
        config.model_dump(mode="json"), [f"simulation.t_end={t_end!r}", f"output.sample_rate={1 / t_end!r}"]
    )
    start = time.perf_counter()
    with recording_compilations() as compiled:
        simulate(short)
    _WARMED.add(group)
    return WarmUp(*group, config.integrator.method, tuple(compiled), time.perf_counter() - start)


def warm_up_configs(every_group: bool = False) -> list[Config]:
    """The default walker (the schema's defaults); with ``every_group``, it in every formulation x integrator family."""
    default = config_from_dict({})
    if not every_group:
        return [default]
    formulations = get_args(FormulationConfig.model_fields["kind"].annotation)
    methods = (default.integrator.method, STIFF_METHODS[0])
    return [
        config_from_dict({}, [f"formulation.kind={kind}", f"integrator.method={method}"])
        for kind in formulations
        for method in methods
    ]
