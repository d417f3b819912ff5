"""Benchmark rows of the uncertainty study (full benchmark only), on a local pool of 2 workers (its start and the
workers' cache loading included), each sample written to a chunk file as ``biped-sim uncertainty`` does:

* ensemble: 1,024 samples (scrambled Sobol) of the default walker, 4 s each, in minimal coordinates (the study's
  choice for a planar compliant walker), over the four keys of :data:`DISTRIBUTIONS`. Target: 5 minutes;
* Sobol indices: the same four keys at N = 256 (Saltelli's design, 256 x 6 = 1,536 runs). Target: 10 minutes;
* MuJoCo: ``mujoco.rollout`` of the bench's MJCF walker (:mod:`.mujoco_walker`, RK4 at its timestep), 4 s from
  the same start, ``ROLLOUTS`` rollouts on 2 threads, as runs per second beside the ensemble's, and their ratio.
  A rollout runs open loop: the scuffing guard that the bench's MuJoCo walker applies between steps is not
  applied, so the rollouts time MuJoCo's stepping of the walker, not a walking gait.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import Config, derive, load_config
from biped_sim.studies.uncertainty.distributions import Distribution
from biped_sim.studies.uncertainty.study import UncertaintySpec, run_study
from biped_sim.sweep import study_executor

CONFIG = Path("configs/round_foot_walker.yaml")
T_END, WORKERS, ENSEMBLE, SOBOL_BASE = 4.0, 2, 1024, 256
ROLLOUTS, ROLLOUT_BATCH = 32, 8
DISTRIBUTIONS = (
    Distribution("ground.slope", "uniform", (0.016, 0.024)),
    Distribution("walker.leg_inertia", "uniform", (0.004, 0.006)),
    Distribution("contact.restitution", "uniform", (0.2, 0.4)),
    Distribution("walker.hip_mass", "uniform", (1.8, 2.2)),
)
TARGETS_S = {"ensemble": 300.0, "sobol": 600.0}


def _timed_study(config: Config, samples: int, method: str) -> dict[str, Any]:
    spec = UncertaintySpec(config, DISTRIBUTIONS, samples, method, seed=0)
    with tempfile.TemporaryDirectory(prefix="biped-sim-bench-uncertainty-") as tmp:
        clock = time.perf_counter()
        with study_executor("local", WORKERS) as pool:
            study = run_study(spec, Path(tmp), pool)
        wall = time.perf_counter() - clock
    doc = study.to_json()
    return {
        "runs": len(study.values), "wall_s": wall, "runs_per_s": len(study.values) / wall,
        "status_counts": doc["statistics"]["status_counts"], "sobol": doc["sobol"],
    }  # fmt: skip


def rollout_throughput(config: Config) -> dict[str, Any]:
    """``ROLLOUTS`` MuJoCo rollouts of ``T_END`` s on ``WORKERS`` threads: runs per second (or why not run)."""
    try:
        import mujoco
        from mujoco import rollout

        from biped_sim.bench.mujoco_walker import MujocoWalker  # optional extra (biped-sim[bench])
    except ImportError as exc:
        return {"available": False, "reason": f"{exc} (install with make setup-bench)"}
    walker = MujocoWalker(config)
    model, data = walker.model, walker.data
    data.qpos[:], data.qvel[:] = walker.qpos0, walker.qvel0
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.zeros(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    nstep = round(T_END / model.opt.timestep)
    datas = [mujoco.MjData(model) for _ in range(WORKERS)]
    starts = np.tile(state, (ROLLOUT_BATCH, 1))
    rollout.rollout(model, datas, starts[:1], nstep=10)  # warm-up
    clock = time.perf_counter()
    for _ in range(ROLLOUTS // ROLLOUT_BATCH):
        rollout.rollout(model, datas, starts, nstep=nstep)
    wall = time.perf_counter() - clock
    return {"available": True, "version": mujoco.__version__, "rollouts": ROLLOUTS, "threads": WORKERS,
            "timestep": model.opt.timestep, "wall_s": wall, "runs_per_s": ROLLOUTS / wall}  # fmt: skip


def uncertainty_bench() -> dict[str, Any]:
    """The bench.json section ``uncertainty``: the ensemble, the Sobol study and MuJoCo's rollouts."""
    config = derive(load_config(CONFIG), {"simulation.t_end": T_END})
    out: dict[str, Any] = {"t_end": T_END, "workers": WORKERS, "keys": [d.text() for d in DISTRIBUTIONS]}
    out["ensemble"] = {**_timed_study(config, ENSEMBLE, "sobol"), "target_s": TARGETS_S["ensemble"]}
    out["sobol"] = {**_timed_study(config, SOBOL_BASE, "saltelli"), "target_s": TARGETS_S["sobol"]}
    mujoco = rollout_throughput(config)
    if mujoco.get("available"):
        mujoco["ensemble_over_mujoco"] = out["ensemble"]["runs_per_s"] / mujoco["runs_per_s"]
    out["mujoco_rollout"] = mujoco
    return out
