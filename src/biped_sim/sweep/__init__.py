"""Parameter sweeps: a sweep file expands into runs that execute on local processes or a Dask cluster.

from biped_sim.sweep import load_sweep, local_executor, run_sweep
sweep = load_sweep("configs/sweeps/slopes_integrators.yaml")
with local_executor(jobs=2) as executor:
    outcome = run_sweep(sweep, sweep.default_output_dir(), executor)
"""

from __future__ import annotations

from biped_sim.sweep.executors import (
    SchedulerLostError,
    check_executor,
    dask_executor,
    default_jobs,
    local_executor,
    make_executor,
    study_executor,
    workers_for,
)
from biped_sim.sweep.rows import read_sweep
from biped_sim.sweep.runner import SweepOutcome, SweepProgress, execute_run, pending_runs, run_sweep
from biped_sim.sweep.spec import RangeSpec, RunSpec, Sweep, SweepSpec, check_buildable, expand, load_sweep

__all__ = [
    "RangeSpec",
    "RunSpec",
    "SchedulerLostError",
    "Sweep",
    "SweepOutcome",
    "SweepProgress",
    "SweepSpec",
    "check_buildable",
    "check_executor",
    "dask_executor",
    "default_jobs",
    "execute_run",
    "expand",
    "load_sweep",
    "local_executor",
    "make_executor",
    "pending_runs",
    "read_sweep",
    "run_sweep",
    "study_executor",
    "workers_for",
]
