"""
Your own walker in YAML
=======================

A walker is data: bodies (mass, inertia, centre of mass), point masses, revolute joints with one-sided stops
(a knee that cannot hyperextend), feet (arcs or points) and the bodies of each leg. Written once, the same
description runs rigid (plastic strikes, limit cycles, basins) and compliant (contact laws at the feet, the
stops as compliant contacts), with no code.

Here Hsu Chen's point-foot kneed walker (M.Eng. thesis, MIT 2007), written with named parameters and one leg
mirrored into two, then changed: a heavier thigh.
"""

# %%
# The description
# ---------------
# Numbers may be arithmetic on the named parameters (read from the syntax tree, never evaluated as Python); a
# ``leg`` is mirrored into ``_1`` and ``_2`` with the ``hip`` joint between them.
from tempfile import mkdtemp

import numpy as np
import pandas as pd
import yaml

from biped_sim import config_from_dict, simulate

WALKER = """
dynamics: rigid
gravity: 9.81
ground: {slope: 0.0504}
walker:
  kind: description
  parameters:
    - {name: thigh_mass, value: 0.5, unit: kg}
    - {name: shank_mass, value: 0.05, unit: kg}
    - {name: hip_mass, value: 0.5, unit: kg}
    - {name: thigh_length, value: 0.5, unit: m}
    - {name: shank_length, value: 0.5, unit: m}
  description:
    leg:
      bodies:
        - {name: thigh, mass: thigh_mass, inertia: 0.0, com: [0.0, -0.65 * thigh_length]}
        - {name: shank, mass: shank_mass, inertia: 0.0, com: [0.0, -shank_length / 4]}
      joints:
        - {name: knee, parent: thigh, child: shank, at: [0.0, -thigh_length], stops: [{side: upper, angle: 0.0}]}
      feet:
        - {name: foot, body: shank, centre: [0.0, -shank_length], radius: 0.0}
    point_masses:
      - {name: hip, body: thigh_1, at: [0.0, 0.0], mass: hip_mass}
simulation:
  t_end: 3.0
  initial: rigid_limit_cycle
"""
config = config_from_dict(yaml.safe_load(WALKER))
config.initial_keys()

# %%
# ``initial: rigid_limit_cycle`` starts the run on the gait, found by Newton on the step map. Each step: the
# swing knee bends, strikes its stop (a plastic knee strike), the straight leg swings on, and the heel strikes.
result = simulate(config)
result

# %%
result.to_pandas()[["strike_time", "period", "length", "stance_angle", "swing_angle"]]

# %%
# The walker over one step, as ``biped-sim plot`` draws it (the earlier poses paler; a knee at its stop is a
# filled square, a bent one hollow).
from pathlib import Path

from biped_sim.io.trajectory import load_run
from biped_sim.plots import walker_figure

out = Path(mkdtemp()) / "kneed"
result.write(out)
step_figure = walker_figure(load_run(out))

# %%
# The gait and its stability
# --------------------------
from biped_sim.studies.limit_cycle import limit_cycle

cycle = limit_cycle(config)
print("period", round(cycle.step_period, 4), "s; speed", round(cycle.speed, 3), "m/s")
print("multipliers", np.round(cycle.multipliers, 3), "largest modulus", round(cycle.max_multiplier_modulus, 3))

# %%
# A change: heavier thighs
# ------------------------
# A parameter is one dotted key, in ``--set``, sweep axes, ``fit --param`` and ``uncertainty --param`` alike:
# every number that uses it follows.
from biped_sim.config import derive

rows = []
for mass in (0.4, 0.5, 0.6, 0.7):
    variant = derive(config, {"walker.parameters.thigh_mass": mass})
    gait = limit_cycle(variant)
    rows.append(
        {
            "thigh mass [kg]": mass,
            "period [s]": gait.step_period,
            "speed [m/s]": gait.speed,
            "largest |multiplier|": gait.max_multiplier_modulus,
            "stable": gait.stable,
        }
    )
pd.DataFrame(rows).round(4)

# %%
# The same description runs compliant with feet of some radius on a contact law, and its knee stops become
# compliant contacts that latch: ``configs/kneed_walker_compliant.yaml``.
