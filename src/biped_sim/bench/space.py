"""Benchmark rows of the walkers in space: the 3D rigid step map, the compliant 3D run, and MuJoCo on that walker.

* Rigid: the median wall time of one step of the compiled 3D step map (:class:`~biped_sim.rigid.space_cycle.SpaceMap`,
  its parameters built once, after a warm-up) from a walker's gait: Coleman's toy (ring feet) and the Kuo-type
  compass on spheres of radius 0.3; steps per second. The planar walkers' steps are :mod:`.rigid_map`'s rows.
* Compliant: the Kuo-type compass on spheres started on its rigid gait (``configs/space/kuo_compass_3d_compliant
  .yaml``: K = 1e7, dopri5 at rtol 1e-8, 3 s): the median wall time and real-time factor of its run, to read beside
  the four-legged walker's rows of the main table (the other spatial walker); and, when MuJoCo is installed, MuJoCo's
  run of the same walker (:func:`~biped_sim.bench.mujoco_space.side_by_side`: its real-time factor and the first
  steps' agreement).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.bench.rigid_map import median_time
from biped_sim.config import load_config
from biped_sim.rigid.space_cycle import SpaceMap, space_walker_model
from biped_sim.simulate import prepare_model, simulate

CONFIGS = Path(__file__).resolve().parents[3] / "configs" / "space"
# the Kuo-type compass's rigid gait on spheres of radius 0.3 (docs/guide/rigid.md), to 8 digits: laterally unstable
KUO_GAIT = {"heading": 0.33925448, "bank": -0.02289237, "pitch": -0.39046787, "swing_angle": 0.77225037,
            "omega_x": -0.3251506, "omega_y": 1.35243853, "omega_z": -0.20618886,
            "swing_rate": -0.94712293}  # fmt: skip
KUO_SPHERES = ("walker.parameters.foot_radius=0.3",)  # the foot's centre follows: its bottom stays 1 m below the hip
# Coleman et al.'s toy's fixed point (docs/guide/rigid.md), the section's order (swing angle not among them)
TINKERTOY_POINT = (0.09866766, -0.00924861, -0.16016583, -0.06623178, 0.46696908, -0.13656793, -0.39255917)
RIGID_CASES = {  # walker -> (config, overrides, section point)
    "tinkertoy": ("tinkertoy.yaml", (), TINKERTOY_POINT),
    "kuo_compass_spheres": (
        "kuo_compass_3d.yaml",
        KUO_SPHERES,
        tuple(v for k, v in KUO_GAIT.items() if k != "swing_angle"),
    ),
}


def rigid_space_steps(repeats: int = 20) -> dict[str, dict[str, float]]:
    """Per walker of :data:`RIGID_CASES`: the median wall time of one compiled step [us] and steps per second."""
    out = {}
    for name, (config_file, overrides, point) in RIGID_CASES.items():
        step_map = SpaceMap(space_walker_model(load_config(CONFIGS / config_file, list(overrides))))
        z = np.array(point)
        step_map(z)  # warm-up: loads the compiled code
        wall = median_time(lambda m=step_map, z=z: m(z), repeats)
        out[name] = {"step_us": wall * 1e6, "steps_per_s": 1.0 / wall}
    return out


def compliant_space_run(repeats: int) -> dict[str, Any]:
    """The compliant Kuo-type compass on spheres from its rigid gait: status, simulated time, median wall time and
    real-time factor (the model built once, outside the timing, as the main table's rows)."""
    config = load_config(CONFIGS / "kuo_compass_3d_compliant.yaml", ["simulation.initial=" + json.dumps(KUO_GAIT)])
    model = prepare_model(config)
    result = simulate(config, model=model)  # warm-up
    wall = median_time(lambda: simulate(config, model=model), repeats)
    return {"status": result.status, "t_final": result.t_final, "wall_s": wall, "rtf": result.t_final / wall}


def mujoco_space_run() -> dict[str, Any]:
    """MuJoCo's run of the same walker beside ours (:func:`~biped_sim.bench.mujoco_space.side_by_side`), or why it
    was not run."""
    try:
        from biped_sim.bench.mujoco_space import side_by_side  # optional extra (biped-sim[bench])
    except ImportError as exc:
        return {"available": False, "reason": f"{exc} (install with make setup-bench)"}
    config = load_config(CONFIGS / "kuo_compass_3d_compliant.yaml", ["simulation.initial=" + json.dumps(KUO_GAIT)])
    return {"available": True, **side_by_side(config, KUO_GAIT)}


def space_bench(repeats: int, mujoco: bool) -> dict[str, Any]:
    """The bench.json section ``space``: the rigid 3D steps, the compliant 3D run and (``mujoco``) MuJoCo's."""
    out: dict[str, Any] = {"rigid_step": rigid_space_steps(), "compliant_run": compliant_space_run(repeats)}
    if mujoco:
        out["mujoco"] = mujoco_space_run()
    return out
