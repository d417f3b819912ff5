r"""
Contact laws and the drop test
==============================

The feet of a compliant walker touch the ground through a penalty force law: the penetration
:math:`\delta` and its rate :math:`\dot\delta` give the normal force, with no impact map. The five laws of
``contact.model`` share one form,

.. math::

    F_N = \max\left(0,\; K \delta^n \left(1 + \chi \frac{\dot\delta}{\dot\delta^-}\right) + D \dot\delta\right),

where :math:`\dot\delta^-` is the approach velocity remembered at touchdown: ``hertz`` has
:math:`\chi = D = 0` (elastic); ``kelvin_voigt`` has :math:`n = 1`, :math:`\chi = 0` and a dashpot :math:`D`
matched to the restitution :math:`e` of a linear oscillator; ``hunt_crossley``
(:math:`\chi = 3(1-e)/2`), ``lankarani_nikravesh`` (:math:`\chi = 3(1-e^2)/4`) and ``flores``
(:math:`\chi = 8(1-e)/(5e)`) differ only in how :math:`\chi` follows from :math:`e`. The drop test measures
which restitution each law really gives: a 1 kg disc of radius 0.15 m meets the ground at 1 m/s without
gravity or friction, and the effective restitution is its separation speed over its approach speed.
"""

# %%
# The drop test, every law at four restitutions
# ---------------------------------------------
# ``biped-sim drop-test`` prints the same table; the test suite checks it.
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from biped_sim.studies.drop_test import drop_test_table

table = pd.DataFrame(drop_test_table())
table.pivot(index="model", columns="nominal_restitution", values="effective_restitution").round(4)

# %%
# Hertz is elastic; Flores tracks the nominal restitution over the whole range; Hunt-Crossley and
# Lankarani-Nikravesh were derived for :math:`e` near 1 and hold there only; Kelvin-Voigt loses less than
# nominal because its force, clipped at zero, lets the disc go early.
fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
for model, rows in table.groupby("model", sort=False):
    ax.plot(rows["nominal_restitution"], rows["effective_restitution"], "o-", label=model)
ax.plot([0.3, 0.9], [0.3, 0.9], "k:", label="effective = nominal")
ax.set_xlabel("nominal restitution e")
ax.set_ylabel("effective restitution")
ax.legend(fontsize=8)

# %%
# One impact, seen as a force-penetration loop
# --------------------------------------------
# The same disc, integrated by the compiled loop and sampled every microsecond; the force is the law's
# formula over the samples (the laws' parameters from :func:`~biped_sim.contact.normal.normal_parameters`,
# through :func:`~biped_sim.studies.drop_test.drop_system`). The area inside a loop is the energy the law
# dissipates.
from biped_sim.config import IntegratorConfig
from biped_sim.contact.normal import CHI, D, K, N
from biped_sim.integrate.driver import integrate_model
from biped_sim.studies.drop_test import APPROACH_SPEED, DISC_RADIUS, drop_system

fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
for model in ("hertz", "kelvin_voigt", "hunt_crossley", "lankarani_nikravesh", "flores"):
    system = drop_system(model, restitution=0.5)
    y0 = np.zeros(9)
    y0[1], y0[4] = DISC_RADIUS + 1e-5, -APPROACH_SPEED  # just above the ground, falling at 1 m/s
    modes0 = np.array([[1.0, 0.0, 0.0, 0.0]])
    method = IntegratorConfig(method="dopri5", rtol=1e-10, atol=1e-13, max_step=1e-6)
    drop = integrate_model(system, y0, modes0, method, t_end=2e-3, sample_rate=1e6)
    delta, rate = DISC_RADIUS - drop.y[:, 1], -drop.y[:, 4]
    p = system.normal_params
    touching = delta > 0
    force = p[K] * np.where(touching, delta, 0.0) ** p[N] * (1 + p[CHI] * rate / APPROACH_SPEED) + p[D] * rate
    force = np.where(touching, np.maximum(force, 0.0), 0.0)
    ax.plot(1e6 * delta[touching], force[touching] / 1e3, label=model)
ax.set_xlabel(r"penetration $\delta$ [$\mu$m]")
ax.set_ylabel("normal force [kN]")
ax.set_title("drop at 1 m/s, nominal e = 0.5", fontsize=9)
ax.legend(fontsize=8)

# %%
# The walker under each law
# -------------------------
# The default walker's first steps with each law at its config's restitution (0.3) and stiffness: the gait
# barely changes, the contact does. A full-size comparison is the bundled sweep
# ``configs/sweeps/contact_models.yaml`` (15 s per law; ``biped-sim sweep`` then ``biped-sim report``).
from pathlib import Path

from biped_sim import load_config, simulate

CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents) if (p / "configs").is_dir())
rows = []
for model in ("hertz", "kelvin_voigt", "hunt_crossley", "lankarani_nikravesh", "flores"):
    config = load_config(CONFIGS / "round_foot_walker.yaml", ["simulation.t_end=2.5", f"contact.model={model}"])
    result = simulate(config)
    rows.append(
        {
            "model": model,
            "status": result.status,
            "last period [s]": result.step_periods[-1],
            "max penetration [mm]": 1e3 * result.summary["max_penetration"],
            "dissipated by normal damping [J]": result.summary["energy_dissipated"]["normal"],
        }
    )
pd.DataFrame(rows).set_index("model")
