"""Is the optimum a smooth minimum? A small profile scan per parameter, and the fit's honest verdict.

For each parameter, ``PROFILE_POINTS`` on each side of the optimum (the others held), spaced by
``PROFILE_WIDTH_SE`` of its conditional standard error (the others held: ``s / sqrt((J^T J)_jj)``, the
scale on which this scan's cost rises; in normalised units, clipped to ``PROFILE_SPACING``); all
``2 p PROFILE_POINTS`` runs are one batch. Along each scan every residual component should be smooth: a
jump (a rebound, a slip or a fall that appears) shows as one first difference off the line of its
neighbours (:func:`_jump`). The fit is called ``converged`` only when the optimizer met a tolerance, no parameter is on
a bound, the fitted walker reaches every target, the scans find nothing lower and see no jump; otherwise
the verdict lists why not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.optimize import MISFIT_P_VALUE, FitRun, misfit_p_value
from biped_sim.studies.fit.problem import FitProblem, Outcome, simulate_outcome

PROFILE_POINTS = 3
PROFILE_WIDTH_SE = 1.0  # spacing of the scan, in conditional standard errors
PROFILE_SPACING = (1e-3, 0.03)  # ... clipped to this, in normalised units
JUMP_RATIO = 0.5  # a first difference this far (relative) off its neighbours' line is a jump
NOISE_FLOOR = 1e-3  # residuals (in standard errors) that move less than this are not judged
AT_BOUND = 1e-6  # normalised distance from a bound that counts as on it
NUMBERING_RATIO = 0.25  # a shifted numbering this much better is flagged


@dataclass
class Profile:
    """One parameter's scan: values, costs, and whether (and where) the residuals jump."""

    key: str
    values: list[float]
    costs: list[float]
    smooth: bool
    jump: str | None  # "step 4 step_period between 0.31 and 0.312", or None
    lower: bool  # a point of the scan is lower than the optimum


def _jump(residuals: np.ndarray, values: np.ndarray, labels: list[str]) -> str | None:
    """Where a residual component jumps along a scan (rows: scan points), or None.

    Along a smooth scan the first differences change slowly: each is close to the linear interpolation (or,
    at the ends, extrapolation) of its neighbours, exactly so for a quadratic. A jump adds its size to one
    first difference only; one that departs from its neighbours' line by more than ``JUMP_RATIO`` of their
    size (and by more than ``NOISE_FLOOR``) is a jump.
    """
    d1 = np.diff(residuals, axis=0)
    n = d1.shape[0]
    if n < 3:
        return None
    for i, label in enumerate(labels):
        for k in range(n):
            if k == 0:
                line, near = 2 * d1[1, i] - d1[2, i], (d1[1, i], d1[2, i])
            elif k == n - 1:
                line, near = 2 * d1[n - 2, i] - d1[n - 3, i], (d1[n - 2, i], d1[n - 3, i])
            else:
                line, near = 0.5 * (d1[k - 1, i] + d1[k + 1, i]), (d1[k - 1, i], d1[k + 1, i])
            departure = abs(d1[k, i] - line)
            if departure > NOISE_FLOOR and departure > JUMP_RATIO * max(abs(near[0]), abs(near[1])):
                return f"{label} between {values[k]:.6g} and {values[k + 1]:.6g}"
    return None


def profile_scans(evaluator: Evaluator, run: FitRun, standard_errors_u: np.ndarray) -> list[Profile]:
    """The scans around ``run``'s optimum, spaced by the conditional standard errors of the normalised variables."""
    problem, u0 = run.problem, run.u
    offsets = np.arange(-PROFILE_POINTS, PROFILE_POINTS + 1)
    plans = []
    for j, se in enumerate(standard_errors_u):
        spacing = PROFILE_WIDTH_SE * se if np.isfinite(se) and se > 0 else PROFILE_SPACING[1]
        spacing = float(np.clip(spacing, *PROFILE_SPACING))
        along = u0[j] + spacing * offsets
        along = along[(along >= 0.0) & (along <= 1.0)]  # evenly spaced: a point beyond a bound is left out
        points = np.repeat(u0[None, :], len(along), axis=0)
        points[:, j] = along
        plans.append(points)
    evaluator.stage = "profile scans"
    outcomes = evaluator.outcomes([point for plan in plans for point in plan])
    labels = [f"step {t.step} {t.quantity}" for t in problem.targets]
    profiles, start = [], 0
    for j, plan in enumerate(plans):
        chunk = outcomes[start : start + len(plan)]
        start += len(plan)
        residuals = np.array([problem.residuals(o) for o in chunk])
        costs = [0.5 * float(r @ r) for r in residuals]
        values = np.array([problem.parameters[j].from_unit(u) for u in plan[:, j]])
        jump = _jump(residuals, values, labels)
        lower = min(costs) < run.cost * (1 - 1e-9) - 1e-15
        profiles.append(Profile(problem.parameters[j].key, values.tolist(), costs, jump is None, jump, lower))
    return profiles


def misfit(run: FitRun) -> str | None:
    """Whether the residuals are far larger than the reference's std at the optimum (weighted fits only)."""
    problem = run.problem
    n, p = len(run.residuals), len(problem.parameters)
    chi2 = float(run.residuals @ run.residuals)
    p_value = misfit_p_value(problem, 0.5 * chi2)
    if p_value is None or p_value >= MISFIT_P_VALUE:
        return None
    return (
        f"the fitted model misses the data: chi2 {chi2:.4g} for {n - p} degrees of freedom (p = {p_value:.1e}); "
        "another minimum, a model error or an underestimated std"
    )


def numbering_check(problem: FitProblem, start: np.ndarray) -> str | None:
    """Whether the reference's periods meet the start's model periods clearly better one step earlier or later
    (a reference built from a run's steps.csv but read as release-numbered is one step off): one simulation
    of the start, one strike further than the fit's."""
    data = problem.evaluation_data(start)
    data["simulation"]["max_steps"] += 1
    outcome = simulate_outcome(data)
    periods = [t for t in problem.targets if t.quantity == "step_period"]
    if len(periods) < 3:
        return None

    shifts = (-1, 0, 1)
    model = np.array([[outcome.value("step_period", t.model_step + s) for t in periods] for s in shifts])
    common = np.all(np.isfinite(model), axis=0)  # the steps every alignment has
    if common.sum() < 3:
        return None
    means = np.array([t.mean for t in periods])[common]
    errors = {s: float(np.sqrt(np.mean((model[i, common] - means) ** 2))) for i, s in enumerate(shifts)}

    def rms(shift: int) -> float:
        return errors[shift]

    declared = rms(0)
    better = [s for s in (-1, 1) if rms(s) < NUMBERING_RATIO * declared]
    if not better:
        return None
    origin = problem.reference.spec.step_origin
    return (
        f"the reference's periods meet the start's model steps {better[0]:+d} off better (RMS {rms(better[0]):.3g} s "
        f"against {declared:.3g} s): is step_origin ({origin}) or skip right?"
    )


def unreached_text(steps: list[int], outcome: Outcome) -> str | None:
    """Which reference steps the fitted walker never reached and how its run ended (None: it reached them all)."""
    if not steps:
        return None
    named = ", ".join(map(str, sorted(set(steps))[:10])) + (", ..." if len(set(steps)) > 10 else "")
    return (
        f"the fitted walker never reaches reference step {named} (its run ended {outcome.status} after "
        f"{outcome.strikes} model steps)"
    )


def verdict(run: FitRun, profiles: list[Profile], unreached: str | None) -> list[str]:
    """Why the fit is not converged (empty: it is); ``unreached``: :func:`unreached_text`."""
    reasons = []
    if not run.polish.success:
        reasons.append(f"the polish met no tolerance ({run.polish.message})")
    for parameter, u in zip(run.problem.parameters, run.u, strict=True):
        if u <= AT_BOUND or u >= 1 - AT_BOUND:
            reasons.append(f"{parameter.key} is on a bound")
    if unreached:
        reasons.append(unreached)
    for profile in profiles:
        if profile.jump is not None:
            reasons.append(f"the objective is not smooth along {profile.key} ({profile.jump})")
        if profile.lower:
            reasons.append(f"the profile of {profile.key} finds a lower cost than the optimum")
    return reasons
