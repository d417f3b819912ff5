"""The validation report's peer-engine check: a walker in space with sphere feet in MuJoCo and in this project.

Coleman et al.'s toy on spheres (``configs/space/tinkertoy_sphere_compliant.yaml``, a stable gait, largest
multiplier 0.92) from its rigid gait's state, five steps each side
(:func:`~biped_sim.bench.mujoco_space.side_by_side`): both walk, the steps' periods, lengths and widths agree
within 1 %, the hip's lateral sway within 4 %. ``biped-sim validate`` runs it when MuJoCo (the optional extra
``bench``) is installed and prints ``SKIP`` otherwise; docs/guide/formulations.md says what each engine's
contact assumes.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib.util import find_spec

import numpy as np

from biped_sim.bench.space import CONFIGS
from biped_sim.config import Config, load_config
from biped_sim.studies.checks import Check

TINKERTOY_SPHERE = CONFIGS / "tinkertoy_sphere_compliant.yaml"
# its rigid gait (biped-sim limit-cycle configs/space/tinkertoy_sphere.yaml, residual 4e-11), to 10 digits: stable
SPHERE_GAIT = {"heading": 0.0986990465, "bank": -0.009405176, "pitch": -0.1604358883, "swing_angle": 0.2943492893,
               "omega_x": -0.0664290886, "omega_y": 0.4672008356, "omega_z": -0.1369632665,
               "swing_rate": -0.393508172}  # fmt: skip
STEPS = 5
# largest relative difference over the steps (the hip's sway, from the first strike on: over four)
BOUNDS = {"period": 0.01, "length": 0.01, "width": 0.01, "sway": 0.04}
GROUP = "MuJoCo side by side (Coleman's toy on spheres, 5 steps)"
SKIP = "skip: MuJoCo side by side, a walker in space (MuJoCo, the optional extra 'bench', is not installed)"


def sphere_toy() -> Config:
    """The toy on spheres from its rigid gait, run long enough for ``STEPS`` steps."""
    initial = "simulation.initial=" + repr(SPHERE_GAIT).replace("'", '"')
    return load_config(TINKERTOY_SPHERE, [initial, "simulation.t_end=5.2"])


def mujoco_space_checks() -> list[Check]:
    """Both engines walk the toy's first steps; each quantity's largest relative difference within its bound."""
    from biped_sim.bench.mujoco_space import side_by_side  # imports mujoco

    compared = side_by_side(sphere_toy(), SPHERE_GAIT, n_steps=STEPS)
    statuses = f"ours {compared['ours']['status']}, MuJoCo {compared['mujoco']['status']}"
    rows = [Check(GROUP, "both walk", "walking", statuses, "-", statuses.count("walking") == 2)]
    for name, bound in BOUNDS.items():
        differences = np.abs(compared["quantities"][name]["relative_difference"])
        shown = ", ".join(f"{d:.2%}" for d in differences)
        passed = len(differences) >= STEPS - 1 and differences.max() < bound
        rows.append(Check(GROUP, f"step {name}s: relative difference", f"< {bound:.0%}", shown, f"{bound:g}", passed))
    return rows


def mujoco_stages() -> list[tuple[str, Callable[[], list[Check]]]]:
    """The validation stages that need MuJoCo: the comparison when it is installed, none otherwise."""
    if find_spec("mujoco") is None:
        return []
    return [("MuJoCo side by side: a walker in space on spheres", mujoco_space_checks)]
