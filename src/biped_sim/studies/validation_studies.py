"""Validation checks of the studies built on runs: compliant-to-rigid convergence and largest step down as the
contact stiffens, the simplest walker's basin of attraction, and the recovery of known parameters by a fit."""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import derive, load_config
from biped_sim.io.references import Reference, ReferenceSpec
from biped_sim.studies.basin import CONVERGED, FELL, BasinSpec, GridAxis, map_basin
from biped_sim.studies.checks import CONFIGS, Check, close, simplest_config
from biped_sim.studies.convergence import converge
from biped_sim.studies.fit import calibrate, fit_problems, synthetic_reference_data
from biped_sim.studies.robustness import gait_start, largest_disturbance
from biped_sim.walkers.model import contact_stiffness


def convergence_checks() -> tuple[list[Check], list[dict[str, Any]]]:
    """Compliant gait -> rigid gait of the default walker as the contact stiffens (and the table)."""

    config = load_config(CONFIGS / "round_foot_walker.yaml")
    _, rows = converge(config)
    table = [asdict(r) for r in rows]
    diffs = [r.touchdown_difference for r in rows]
    periods = [abs(r.period_difference) for r in rows]
    group = "Compliant -> rigid (round_foot_walker)"
    finite = all(math.isfinite(d) for d in diffs)
    return [
        Check(
            group,
            "touchdown-state difference shrinks (first -> last level)",
            "-> 0, last < first / 20",
            " -> ".join(f"{d:.1e}" for d in diffs),
            "-",
            finite and diffs[-1] < diffs[0] / 20,
        ),
        Check(
            group,
            "|step period difference| shrinks (first -> last level) [s]",
            "-> 0, last < first / 10",
            " -> ".join(f"{d:.1e}" for d in periods),
            "-",
            finite and periods[-1] < periods[0] / 10,
        ),
    ], table


STEP_DOWN_LEVELS = 3
STEP_DOWN_TOLERANCE = 1e-3  # [leg lengths] of the searches here (the command's is 1e-4)
# relative: the stiffest compliant walker's largest step down against the rigid one's (searches to 1e-3 l; the
# report lists each level's)
STEP_DOWN_AGREEMENT = 0.05


def step_down_checks() -> tuple[list[Check], list[dict[str, Any]]]:
    """The largest step down the default walker survives, compliant -> rigid as the contact stiffens (and the table).

    Both started on the rigid limit cycle; level k: contact stiffness 10^k times the config's, restitution
    0.3 / sqrt(10)^k (as ``converge``; the config's Ambrosio friction, LuGre not being available on profiles).
    The compliant walker settles for 10 steps first (:func:`~biped_sim.studies.robustness.gait_start`).
    """
    config = load_config(CONFIGS / "round_foot_walker.yaml", ["simulation.initial=rigid_limit_cycle"])
    rigid_config = derive(config, {"dynamics": "rigid"})
    rigid = largest_disturbance(gait_start(rigid_config), "step", -1.0, STEP_DOWN_TOLERANCE)[0]
    table = []
    for k in range(STEP_DOWN_LEVELS):
        stiffness = contact_stiffness(config) * 10.0**k
        restitution = 0.3 / math.sqrt(10.0) ** k
        level = {"contact.stiffness": stiffness, "contact.materials": None, "contact.restitution": restitution}
        largest = largest_disturbance(gait_start(derive(config, level)), "step", -1.0, STEP_DOWN_TOLERANCE)[0]
        table.append({"stiffness": stiffness, "compliant": largest, "rigid": rigid})
    gaps = [abs(row["compliant"] - rigid) / rigid for row in table]
    group = "Compliant -> rigid largest step down (round_foot_walker)"
    return [
        Check(
            group,
            "relative difference from the rigid walker's does not grow (first -> last level)",
            "last <= first",
            " -> ".join(f"{gap:.3f}" for gap in gaps),
            f"{STEP_DOWN_TOLERANCE:g} l searches",
            gaps[-1] <= gaps[0],
        ),
        Check(
            group,
            "stiffest compliant against rigid [leg lengths]",
            f"{rigid:.4f}",
            f"{table[-1]['compliant']:.4f}",
            f"{STEP_DOWN_AGREEMENT:.0%}",
            gaps[-1] <= STEP_DOWN_AGREEMENT,
        ),
    ], table


def basin_checks() -> list[Check]:
    """Schwab & Wisse's basin of the simplest walker at slope 0.009, qualitatively: it holds the fixed point, is a
    small fraction of the post-impact plane, and is a thin band (principal axes of its cells) along a falling
    diagonal (faster starts need larger stance angles). No number is taken from the paper."""
    config = simplest_config(0.009)
    spec = BasinSpec(config, GridAxis("stance_angle", 0.1, 0.4, 61), GridAxis("stance_rate", -0.45, -0.05, 81), 30)
    basin = map_basin(spec, None)
    group = "Schwab & Wisse 2001, simplest walker's basin (slope 0.009, 61 x 81 cells, 30 steps)"
    fixed = basin.fixed_point or {"stance_angle": math.nan, "stance_rate": math.nan}
    i = int(np.argmin(np.abs(spec.x.values - fixed["stance_angle"])))
    j = int(np.argmin(np.abs(spec.y.values - fixed["stance_rate"])))
    rows, cols = np.nonzero(basin.outcome != FELL)
    points = np.vstack([spec.x.values[cols], spec.y.values[rows]])
    fraction = len(cols) / basin.outcome.size
    if len(cols) > 2:
        values, vectors = np.linalg.eigh(np.cov(points))
        aspect, direction = math.sqrt(values[1] / max(values[0], 1e-300)), vectors[:, 1]
    else:
        aspect, direction = math.nan, np.array([1.0, 1.0])
    falling = float(direction[0] * direction[1])
    return [
        Check(
            group,
            "the cell at the fixed point converges",
            "converged",
            str(basin.outcome[j, i] == CONVERGED),
            "-",
            basin.outcome[j, i] == CONVERGED,
        ),
        Check(group, "fraction of the plane that walks", "in (0, 0.05)", f"{fraction:.4f}", "-", 0 < fraction < 0.05),
        Check(group, "thin: length / width of the band", ">= 5", f"{aspect:.1f}", "-", aspect >= 5),
        Check(group, "the band falls: rate decreases as angle grows", "< 0", f"{falling:.3f}", "-", falling < 0),
    ]


# (hidden values, the start's other changes, fitted KEY=LO:HI): each fitted to the default walker's first seven
# periods at the hidden values, rounded to 5 decimals (the stiffness case starts at the default materials' Hertz value)
RECOVERIES: tuple[tuple[dict[str, Any], dict[str, Any], tuple[str, ...]], ...] = (
    ({"walker.leg_inertia": 0.0049, "contact.restitution": 0.42}, {},
     ("walker.leg_inertia=0.004:0.007", "contact.restitution=0.1:0.9")),
    ({"contact.stiffness": 2.2e7}, {"contact.materials": None, "contact.stiffness": 3.24e7},
     ("contact.stiffness=1e7:1e8",)),
    ({"friction.mu_kinetic": 0.5}, {}, ("friction.mu_kinetic=0.3:0.9",)),
)  # fmt: skip
ROUNDING_RMS_S = 5e-6  # 5 decimals: the rounding's RMS is 1e-5 / sqrt(12) = 2.9 us


def fit_recovery_checks() -> list[Check]:
    """``biped-sim fit`` recovers hidden values (issue 20's restitution and leg inertia, a stiffness, a friction
    coefficient) from the default walker's own first seven periods rounded to 5 decimals: each within three
    standard errors (from the residual variance), the RMS error at the rounding, the verdict converged."""
    base = load_config(CONFIGS / "round_foot_walker.yaml", ["simulation.t_end=3.5"])
    checks = []
    for hidden, changes, texts in RECOVERIES:
        start = derive(base, changes)
        spec = ReferenceSpec.model_validate(synthetic_reference_data(derive(start, hidden), 7, 0.0, 0, decimals=5))
        [(_, problem)] = fit_problems(start, Reference(Path("synthetic"), spec), list(texts))
        result = calibrate(problem).result
        group = "Fit recovery: " + ", ".join(p.key for p in problem.parameters)
        verdict = result.verdict
        checks.append(Check(group, "verdict", "converged", verdict, "-", result.converged))
        rms = result.after.stats.rms_abs if result.after is not None else math.nan
        checks.append(
            Check(group, "RMS period error [s]", f"< {ROUNDING_RMS_S:g}", f"{rms:.2e}", "-", rms < ROUNDING_RMS_S)
        )
        for e in result.estimates:
            se = e.standard_error if e.standard_error is not None else math.nan
            checks.append(close(group, f"{e.key} (3 standard errors)", hidden[e.key], e.value, 3 * se))
    return checks
