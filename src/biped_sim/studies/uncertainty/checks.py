"""Checks of the uncertainty study against known answers (``biped-sim validate`` and the slow tier).

* The Ishigami function (a = 7, b = 0.1; Ishigami and Homma 1990; analytic indices in Saltelli et al., Global
  Sensitivity Analysis: The Primer, 2008): S1 = 0.3139, S2 = 0.4424, S3 = 0, ST1 = 0.5576, ST3 = 0.2437, through
  the design and estimator code that walker runs use (:func:`.sampling.unit_design`, :func:`.sobol.saltelli_indices`).
* Garcia's simplest walker depends on the slope alone: over slope and the contact restitution (unused by the rigid
  model), the slope's total index is 1 and the restitution's 0.
* The mean steady period over a uniform slope distribution equals the average of the limit-cycle periods over it
  (Gauss-Legendre quadrature of Newton's cycles), within the sampling error.
* The rimless wheel's MFPT on random slopes from simulated walks against its Markov chain at two roughness levels.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import derive, load_config
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.studies.checks import CONFIGS, Check, simplest_config
from biped_sim.studies.uncertainty.distributions import Distribution
from biped_sim.studies.uncertainty.mfpt import mfpt_curve
from biped_sim.studies.uncertainty.sampling import unit_design
from biped_sim.studies.uncertainty.sobol import saltelli_indices
from biped_sim.studies.uncertainty.study import UncertaintySpec, run_study

ISHIGAMI = {"S1": (0.3139, 0.4424, 0.0), "ST": (0.5576, 0.4424, 0.2437)}  # Saltelli et al. 2008, a = 7, b = 0.1
ISHIGAMI_SAMPLES = 4096
INDEX_TOLERANCE = 0.02
SLOPES = (0.006, 0.012)  # the simplest walker's stable period-1 range holds these (Garcia 1998)
WALKER_SAMPLES = 32
SLOPE_TOTAL_TOLERANCE = 0.1  # Jansen's estimator of an index of 1 at N = 32 (its bootstrap CI is wider)
QUADRATURE_NODES = 8
MEAN_SIGMAS = 3.0
WHEEL_ROUGHNESS = (0.03, 0.04)  # [rad] slope sd per step: MFPT of tens of steps
WHEEL_SEEDS = 1000


def ishigami(x: np.ndarray, a: float = 7.0, b: float = 0.1) -> np.ndarray:
    """f = sin x1 + a sin^2 x2 + b x3^4 sin x1, x_i uniform on [-pi, pi]."""
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_checks() -> list[Check]:
    unit = unit_design(ISHIGAMI_SAMPLES, 3, "saltelli", seed=0)
    found = saltelli_indices(ishigami(-math.pi + 2.0 * math.pi * unit), 3, seed=0)
    group = f"Ishigami function, Sobol indices (SALib, N = {ISHIGAMI_SAMPLES})"
    checks = []
    for name, values in ISHIGAMI.items():
        for j, expected in enumerate(values):
            if name == "ST" and j == 1:
                continue  # ST2 = S2: no second-order term of x2
            got, ci = float(found[name][j]), float(found[f"{name}_conf"][j])
            checks.append(Check(group, f"{name} x{j + 1} (95 % CI +-{ci:.3f})", f"{expected:.4f}", f"{got:.4f}",
                                f"{INDEX_TOLERANCE:g}", abs(got - expected) <= INDEX_TOLERANCE))  # fmt: skip
    return checks


def _simplest(t_end: float = 40.0):
    return derive(simplest_config(0.009), {"simulation.initial": "rigid_limit_cycle", "simulation.t_end": t_end})


def simplest_index_checks() -> list[Check]:
    """Slope and the contact restitution, unused by the rigid model: total indices 1 and 0."""
    spec = UncertaintySpec(
        _simplest(),
        (Distribution("ground.slope", "uniform", SLOPES), Distribution("contact.restitution", "uniform", (0.2, 0.9))),
        WALKER_SAMPLES, "saltelli", seed=1,
    )  # fmt: skip
    study = run_study(spec, None)
    assert study.indices is not None
    period = study.indices.outputs[0]
    s = period.indices if period.indices is not None else {"ST": [math.nan] * 2, "ST_conf": [math.nan] * 2}
    group = f"Simplest walker, Sobol indices of the steady period ({WALKER_SAMPLES} x 4 runs)"
    slope_total, slope_ci = float(s["ST"][0]), float(s["ST_conf"][0])
    return [
        Check(
            group,
            f"ST slope (95 % bootstrap CI +-{slope_ci:.2f})",
            "1",
            f"{slope_total:.3f}",
            f"{SLOPE_TOTAL_TOLERANCE:g}",
            abs(slope_total - 1.0) <= SLOPE_TOTAL_TOLERANCE,
        ),
        Check(
            group,
            "ST contact restitution (unused by the model)",
            "0",
            f"{float(s['ST'][1]):.2e}",
            "1e-12",
            abs(float(s["ST"][1])) <= 1e-12,
        ),
    ]


def mean_period_checks() -> list[Check]:
    """The study's mean steady period against the quadrature of limit-cycle periods over the slope."""
    config = _simplest()
    spec = UncertaintySpec(config, (Distribution("ground.slope", "uniform", SLOPES),), WALKER_SAMPLES, "sobol", 2)
    stats = run_study(spec, None).stats["outputs"]["steady_period"]
    nodes, weights = np.polynomial.legendre.leggauss(QUADRATURE_NODES)
    lo, hi = SLOPES
    slopes = lo + (hi - lo) * (nodes + 1.0) / 2.0
    periods = [rigid_limit_cycle(derive(config, {"ground.slope": float(g)})).step_period for g in slopes]
    expected = float(np.dot(weights, periods) / 2.0)
    tolerance = MEAN_SIGMAS * stats["mean_se"]
    group = f"Simplest walker, mean period over slope U{SLOPES} ({WALKER_SAMPLES} samples)"
    return [Check(group, f"mean steady period against {QUADRATURE_NODES}-node quadrature of the limit cycles",
                  f"{expected:.8f}", f"{stats['mean']:.8f}", f"{tolerance:.1e} (3 standard errors)",
                  abs(stats["mean"] - expected) <= tolerance)]  # fmt: skip


def wheel_mfpt_checks() -> list[Check]:
    """The rimless wheel's walks on random slopes against its Markov chain."""
    curve = mfpt_curve(load_config(CONFIGS / "rimless_wheel.yaml"), "slope", WHEEL_ROUGHNESS, WHEEL_SEEDS, 20_000)
    assert curve.chain is not None
    group = f"Rimless wheel MFPT on random slopes ({WHEEL_SEEDS} walks per level)"
    return [
        Check(
            group,
            f"chain MFPT within the walks' 95 % CI, slope sd {h:g} rad [steps]",
            f"{chain:.3f}",
            f"{e.mfpt:.3f} [{e.ci[0]:.3f}, {e.ci[1]:.3f}]",
            "CI",
            e.ci[0] <= chain <= e.ci[1],
        )
        for h, e, chain in zip(curve.roughness, curve.estimates, curve.chain, strict=True)
    ]


def uncertainty_checks() -> list[Check]:
    """Every check of this module."""
    return ishigami_checks() + simplest_index_checks() + mean_period_checks() + wheel_mfpt_checks()
