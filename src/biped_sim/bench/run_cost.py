"""Benchmark rows of a run's price against its own integration (issue 30), every ratio measured in this process.

* ``simulate`` against its integration (:func:`~biped_sim.simulate.compliant.integrate_config`, the call that
  ``simulate`` makes) for the default walker in each compliant formulation, and for its rigid model (the walk
  of the compiled step map, :func:`~biped_sim.simulate.rigid.walk`). A run measures its channels when asked,
  so each row also times ``simulate`` followed by every measure ``biped-sim run`` writes (the summary and the
  trajectory file's channels, not the file itself);
* one ``fit`` evaluation (:func:`~biped_sim.studies.fit.problem.simulate_outcome` on the bench fit's problem,
  at the middle of its parameter box) and one ``uncertainty`` sample
  (:func:`~biped_sim.studies.uncertainty.samples.run_sample`, the bench ensemble's walker), each against the
  integration of the run it makes, also per simulated second.

The timings are CPU times of this process (every call is single-process), alternated (integration, then the call)
``repeats`` times after one warm-up of each, each side keeping its best: other processes' load moves wall times of
runs as short as 0.5 ms a hundredfold (a rigid run measured 104x its integration at load 16), CPU times barely, and
the ratio of best to best is the least disturbed. Target: 1.2x.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from biped_sim.bench.fit import fit_problem
from biped_sim.bench.uncertainty import CONFIG as UNCERTAINTY_CONFIG
from biped_sim.bench.uncertainty import T_END as UNCERTAINTY_T_END
from biped_sim.config import Config, derive, load_config
from biped_sim.simulate import prepare_model, simulate, study_formulation
from biped_sim.simulate.compliant import integrate_config
from biped_sim.simulate.rigid import walk
from biped_sim.studies.fit.problem import simulate_outcome
from biped_sim.studies.uncertainty.samples import run_sample
from biped_sim.walkers import BuiltModel

FORMULATIONS = ("planar", "minimal", "spatial")
TARGET = 1.2  # a run, a fit evaluation or an uncertainty sample at most this many times its integration


def _best_pair(integration: Callable[[], Any], call: Callable[[], Any], repeats: int) -> tuple[float, float]:
    """(best CPU time of ``integration``, of ``call``) [s], alternating after one warm-up of each."""
    integration(), call()
    spent: tuple[list[float], list[float]] = ([], [])
    for _ in range(repeats):
        for timed, function in zip(spent, (integration, call), strict=True):
            clock = time.process_time()
            function()
            timed.append(time.process_time() - clock)
    return min(spent[0]), min(spent[1])


def _row(label: str, integration: Callable[[], Any], calls: dict[str, Callable[[], Any]], repeats: int,
         simulated_s: float) -> dict[str, Any]:  # fmt: skip
    """One row: the integration's best CPU time and, for each call, its best and its ratio to the integration."""
    row: dict[str, Any] = {"label": label, "simulated_s": simulated_s, "target": TARGET}
    for name, call in calls.items():
        base, best = _best_pair(integration, call, repeats)
        row["integration_s"] = min(base, row.get("integration_s", np.inf))
        row[f"{name}_s"], row[f"{name}_ratio"] = best, best / base
    row["met"] = all(row[f"{name}_ratio"] <= TARGET for name in calls if name != "with_measures")
    return row


def _every_measure(config: Config, model: BuiltModel | Any) -> None:
    """``simulate`` and every measure ``biped-sim run`` writes: the summary and the trajectory file's channels."""
    result = simulate(config, model=model)
    _ = result.summary
    result.trajectory()


def simulate_rows(base: Config, t_end: float, repeats: int) -> list[dict[str, Any]]:
    """``simulate`` against its integration in each compliant formulation and for the rigid model."""
    rows = []
    for kind in FORMULATIONS:
        config = derive(base, {"formulation.kind": kind, "simulation.t_end": t_end})
        model = prepare_model(config)
        assert isinstance(model, BuiltModel)
        calls = {"simulate": lambda c=config, m=model: simulate(c, model=m),
                 "with_measures": lambda c=config, m=model: _every_measure(c, m)}  # fmt: skip
        rows.append(_row(f"simulate, {kind}", lambda c=config, m=model: integrate_config(c, m), calls, repeats, t_end))
    config = derive(base, {"dynamics": "rigid", "simulation.t_end": t_end})
    start = prepare_model(config)
    calls = {"simulate": lambda: simulate(config, model=start), "with_measures": lambda: _every_measure(config, start)}
    rows.append(_row("simulate, rigid", lambda: walk(config, start, None), calls, repeats, t_end))  # type: ignore[arg-type]
    return rows


def _integration_of(config: Config) -> Callable[[], Any]:
    model = prepare_model(config)
    assert isinstance(model, BuiltModel)
    return lambda: integrate_config(config, model)


def study_rows(repeats: int) -> list[dict[str, Any]]:
    """One fit evaluation and one uncertainty sample against the integration of their runs."""
    problem = fit_problem()
    data = problem.evaluation_data(np.full(len(problem.parameters), 0.5))
    fit_config = Config.model_validate(data)
    fit_run = simulate(fit_config)
    rows = [_row("fit evaluation", _integration_of(fit_config), {"call": lambda: simulate_outcome(data)}, repeats,
                 fit_run.t_final)]  # fmt: skip
    sample = derive(load_config(UNCERTAINTY_CONFIG), {"simulation.t_end": UNCERTAINTY_T_END})
    run_config = derive(sample, {"formulation.kind": study_formulation(sample)})
    calls = {"call": lambda: run_sample(sample, (), np.zeros(0))}
    rows.append(_row("uncertainty sample", _integration_of(run_config), calls, repeats, UNCERTAINTY_T_END))
    for row in rows:
        row["integration_s_per_simulated_s"] = row["integration_s"] / row["simulated_s"]
        row["call_s_per_simulated_s"] = row["call_s"] / row["simulated_s"]
    return rows


def run_cost_bench(base: Config, t_end: float, repeats: int) -> dict[str, Any]:
    """The bench.json section ``run_cost``: the rows of :func:`simulate_rows` and :func:`study_rows`."""
    return {"t_end": t_end, "repeats": repeats, "rows": simulate_rows(base, t_end, repeats) + study_rows(repeats)}
