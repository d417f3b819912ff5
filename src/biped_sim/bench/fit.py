"""Benchmark rows of calibration (full benchmark only): the global fit and the posterior, 2 workers each.

* Global fit: issue 20's case, the default walker's leg inertia and restitution against its own first seven
  step periods at 0.0049 kg m^2 and 0.42, rounded to 5 decimals (std 10 us given, so the fit is weighted):
  ``biped_sim.studies.fit.calibrate`` with the default global stage, the polish and the profile scans,
  on a local pool of 2 workers (its start and the workers' cache loading included). Target: 60 s.
* Recovery: the cost per fit of the slow tier's recovery check (``tests/test_fit_recovery.py``, issue 27),
  its first ``RECOVERY_CASES`` random cases of each parameter pair (``biped_sim.studies.fit.recovery``) on 2
  workers: evaluations and wall time per fit, and how many were recovered. The check runs 20 per pair. Target:
  15 s per fit of the default walker (40 fits in 10 minutes), 2 minutes per fit of the kneed walker (whose runs
  cost far more: docs/experiments.md, "Cost, profiled").
* Posterior: the same problem with 4,000 draws of emcee (16 walkers x 250 steps) from the fitted optimum,
  the fit's own evaluations reused through one checkpoint. Target: 10 minutes.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

from biped_sim.config import derive, load_config
from biped_sim.io.references import Reference, ReferenceSpec
from biped_sim.studies.fit import calibrate, fit_problems, synthetic_reference_data
from biped_sim.studies.fit.recovery import PAIRS, draw_cases, recover, start_config, summary
from biped_sim.sweep import study_executor

CONFIG = Path("configs/round_foot_walker.yaml")
HIDDEN = {"walker.leg_inertia": 0.0049, "contact.restitution": 0.42}
PARAMETERS = ["walker.leg_inertia=0.004:0.007", "contact.restitution=0.1:0.9"]
STEPS, STD_S, DRAWS, WORKERS = 7, 1e-5, 4000, 2
TARGETS_S = {"global_fit": 60.0, "posterior": 600.0, "recovery_per_fit": 15.0}  # recovery: 40 fits in 10 min
RECOVERY_TARGETS_S = {"kneed thigh mass+stiffness": 120.0}  # per fit, where not TARGETS_S["recovery_per_fit"]
RECOVERY_CASES, RECOVERY_SEED = 2, 27  # the check's seed: its first cases


def fit_problem() -> Any:
    """The global fit's problem: the default walker's two parameters against its own synthetic step periods."""
    base = load_config(CONFIG, ["simulation.t_end=3.5"])
    data = synthetic_reference_data(derive(base, HIDDEN), STEPS, 0.0, 0, decimals=5)
    data["std"] = [STD_S] * STEPS
    reference = Reference(Path("synthetic"), ReferenceSpec.model_validate(data))
    return fit_problems(base, reference, PARAMETERS)[0][1]


def fit_bench(posterior: bool = True) -> dict[str, Any]:
    """The bench.json section ``fit``: wall times, evaluations and what was recovered."""
    problem = fit_problem()
    out: dict[str, Any] = {"hidden": HIDDEN, "steps": STEPS, "workers": WORKERS}
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-fit-") as tmp:
        checkpoint = Path(tmp) / "fit.checkpoint.json"
        clock = time.perf_counter()
        with study_executor("local", WORKERS) as pool:
            fitted = calibrate(problem, pool, checkpoint=checkpoint).result
        out["global_fit"] = {
            "wall_s": time.perf_counter() - clock, "target_s": TARGETS_S["global_fit"],
            "evaluations": fitted.run.evaluations, "parameters": fitted.parameters,
            "standard_errors": {e.key: e.standard_error for e in fitted.estimates}, "converged": fitted.converged,
        }  # fmt: skip
        out["recovery"] = recovery_bench()
        if posterior:
            clock = time.perf_counter()
            with study_executor("local", WORKERS) as pool:
                sampled = calibrate(problem, pool, checkpoint=checkpoint, draws=DRAWS)
            assert sampled.posterior is not None
            out["posterior"] = {
                "wall_s": time.perf_counter() - clock, "target_s": TARGETS_S["posterior"], "draws": DRAWS,
                "evaluations": sampled.posterior.evaluations, "intervals_90": sampled.posterior.intervals,
                "autocorrelation_time": sampled.posterior.autocorrelation, "warnings": sampled.posterior.warnings,
            }  # fmt: skip
    return out


def recovery_bench() -> dict[str, object]:
    """Per parameter pair: the recovery check's first RECOVERY_CASES cases, their cost per fit and rate."""
    starts = {pair: start_config(pair) for pair in PAIRS}
    cases = {pair: draw_cases(starts[pair], pair, RECOVERY_CASES, RECOVERY_SEED)[0] for pair in PAIRS}
    with study_executor("local", WORKERS) as pool:
        recoveries = [recover(starts[pair], pair, hidden, pool) for pair in PAIRS for hidden in cases[pair]]
    rows = {pair: {k: v for k, v in row.items() if k != "misses"} for pair, row in summary(recoveries).items()}
    targets = {pair: RECOVERY_TARGETS_S.get(pair, TARGETS_S["recovery_per_fit"]) for pair in rows}
    return {pair: row | {"target_s_per_fit": targets[pair]} for pair, row in rows.items()}
