"""The Python API: build a walker from a config, simulate it, measure it, write its files.

    from biped_sim import load_config, simulate
    result = simulate(load_config("configs/round_foot_walker.yaml"))
    print(result.status, result.step_periods)

:func:`run` does the same and writes ``trajectory.h5``, ``summary.json`` and ``steps.csv``. A config with
``dynamics: rigid`` is simulated by the rigid model (:mod:`biped_sim.rigid.run`) and gives a
:class:`~biped_sim.rigid.run.RigidRunResult` with the same ``status``, ``summary``, ``steps``,
``step_periods`` and ``heel_strike_states``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.analysis.gait import (
    EnergyAudit,
    StepAccess,
    StepTable,
    constraint_drift,
    energy_audit,
    lateral_summary,
    step_table,
    violation_names,
)
from biped_sim.config import Config
from biped_sim.integrate.driver import Integration, integrate_model
from biped_sim.rigid.run import RigidRunResult, RigidStart, rigid_start, simulate_rigid
from biped_sim.walkers import BuiltModel, build_model


@dataclass
class RunResult(StepAccess):
    """A simulation and what it measured."""

    config: Config
    model: BuiltModel
    run: Integration
    steps: StepTable
    energy: EnergyAudit
    violation: np.ndarray  # (ns, 2) ||Phi||, ||Phidot|| (spatial: (ns, 3), + ||p.p - 1||)
    wall_time_s: float
    summary: dict[str, Any] = field(default_factory=dict)

    @property
    def status(self) -> str:
        return self.run.status

    def unit(self, si_unit: str) -> str:
        """This run's unit for an SI unit: compliant runs are SI throughout."""
        return si_unit


def summarize(result: RunResult) -> dict[str, Any]:
    """The summary.json content."""
    from biped_sim.io.provenance import package_version

    run, config = result.run, result.config
    scale = result.model.total_mass * config.gravity * result.model.leg_length
    return {
        "status": run.status,
        "stop_time": run.stop_time,
        "t_end": run.t_final,
        **result.step_summary(),
        "energy_dissipated": {
            "normal": float(result.energy.dissipated_normal[-1] - result.energy.dissipated_normal[0]),
            "friction": float(result.energy.dissipated_friction[-1] - result.energy.dissipated_friction[0]),
        },
        "energy_residual_max": float(np.max(np.abs(result.energy.residual))),
        "energy_residual_max_relative": float(np.max(np.abs(result.energy.residual)) / scale),
        "constraint_violation_max": {
            name: float(np.max(result.violation[:, k])) for k, name in enumerate(violation_names(result.model))
        },
        **lateral_summary(result.model, run),
        "rhs_evals": run.rhs_evals,
        "accepted_steps": run.accepted_steps,
        "rejected_steps": run.rejected_steps,
        "events": run.events,
        "wall_time_s": result.wall_time_s,
        "integrator": config.integrator.method,
        "config_hash": config.hash(),
        "version": package_version(),
    }


def prepare_model(config: Config) -> BuiltModel | RigidStart:
    """Build and validate what :func:`simulate` needs (ConfigError naming the field): the compliant model, or
    for ``dynamics: rigid`` the rigid walker and its resolved initial state."""
    return rigid_start(config) if config.dynamics == "rigid" else build_model(config)


def simulate(
    config: Config,
    *,
    model: BuiltModel | RigidStart | None = None,
    progress: Callable[[float], None] | None = None,
) -> RunResult | RigidRunResult:
    """Simulate ``config`` and measure the gait; writes nothing.

    ``model`` is :func:`prepare_model`'s result when the caller has built it already; ``progress(t)`` reports
    the simulated time.
    """
    if config.dynamics == "rigid":
        if model is not None and not isinstance(model, RigidStart):
            raise TypeError("simulate: a rigid config takes the RigidStart of prepare_model, not a compliant model")
        return simulate_rigid(config, model, progress)
    if isinstance(model, RigidStart):
        raise TypeError("simulate: a compliant config takes the BuiltModel of prepare_model, not a RigidStart")
    model = model or build_model(config)
    start = time.perf_counter()
    run = integrate_model(
        model.system,
        model.y0,
        model.modes0,
        config.integrator,
        config.simulation.t_end,
        config.output.sample_rate,
        max_strikes=config.simulation.max_steps,
        progress=progress,
    )
    wall = time.perf_counter() - start
    result = RunResult(
        config=config,
        model=model,
        run=run,
        steps=step_table(model, run),
        energy=energy_audit(model, run),
        violation=constraint_drift(model, run),
        wall_time_s=wall,
    )
    result.summary = summarize(result)
    return result


def run(
    config: Config, out_dir: str | Path, *, progress: Callable[[float], None] | None = None
) -> RunResult | RigidRunResult:
    """Simulate and write ``trajectory.h5``, ``summary.json``, ``steps.csv`` and ``config.yaml`` into ``out_dir``
    (atomically)."""
    from biped_sim.io.results import write_run

    result = simulate(config, progress=progress)
    write_run(result, Path(out_dir))
    return result
