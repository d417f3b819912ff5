"""The contest of laws (or of any config value) at their best fits, ranked by evidence.

One fit per value of a key (``contact.model=hertz,flores,...``), each with the same parameters, bounds and
settings. Ranked by the small-sample corrected Akaike information criterion

    AICc = chi2 + 2 k + 2 k (k + 1) / (n - k - 1)      (k: fitted parameters the data resolve, n: targets)

with chi2 the sum of squared weighted residuals (-2 log L up to a constant when the reference gives std;
without it, n log(RSS / n) in its place, the unknown-variance form). Why AICc and not BIC: with the few
steps of a gait trial (n ~ 7) BIC's charge k ln n is smaller than AIC's 2 k (ln 7 < 2), so it would charge
less for a parameter exactly where over-fitting is easiest; AICc is the criterion recommended for n / k
< 40 (Burnham and Anderson 2002, Model Selection and Multimodel Inference, 2nd ed., sec. 2.4). BIC is
reported beside it. k counts the parameters the Jacobian resolves (a law that ignores the restitution,
such as undamped Hertz, is not charged for it). The RMS error of the periods ranks beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from biped_sim.io.tables import Column, Table
from biped_sim.studies.fit.stats import FitResult


@dataclass(frozen=True)
class Evidence:
    """A fit's information criteria: AICc (the ranking), AIC, BIC, with n, k and chi2."""

    n: int
    k: int
    chi_square: float
    aic: float
    aicc: float
    bic: float


def evidence(result: FitResult) -> Evidence:
    """The information criteria of one fit (see the module docstring)."""
    problem = result.run.problem
    n, k = len(problem.targets), result.identifiability.rank
    chi2 = result.chi_square
    fit_term = chi2 if problem.weighted else n * math.log(max(chi2, 1e-300) / n)
    aic = fit_term + 2 * k
    aicc = aic + (2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else math.inf)
    return Evidence(n, k, chi2, aic, aicc, fit_term + k * math.log(n))


def ranked(fits: list[tuple[str, FitResult]]) -> list[tuple[str, FitResult, Evidence]]:
    """The fits with their evidence, best (lowest AICc; then lowest RMS error) first."""
    scored = [(label, result, evidence(result)) for label, result in fits]

    def order(item: tuple[str, FitResult, Evidence]) -> tuple[float, float]:
        rms = item[1].after.stats.rms_abs if item[1].after is not None else math.nan
        return (item[2].aicc if math.isfinite(item[2].aicc) else math.inf, rms if math.isfinite(rms) else math.inf)

    return sorted(scored, key=order)


def ranking_table(key: str, fits: list[tuple[str, FitResult]], name: str = "ranking") -> Table:
    """The contest: one row per value of ``key``, best first, with its evidence and the period errors."""
    columns = [
        Column("rank", "rank"),
        Column("value", key),
        Column("parameters", "fitted parameters"),
        Column("rms_abs", "RMS error", "s", ".5f"),
        Column("max_abs", "max |error|", "s", ".5f"),
        Column("k", "k"),
        Column("chi_square", "chi2", fmt=".4g"),
        Column("aicc", "AICc", fmt=".4g"),
        Column("delta", "dAICc", fmt=".3g"),
        Column("bic", "BIC", fmt=".4g"),
        Column("evaluations", "evaluations"),
        Column("converged", "converged"),
    ]
    order = ranked(fits)
    best = order[0][2].aicc if order else math.nan
    rows = []
    for rank, (value, result, ev) in enumerate(order, start=1):
        stats = result.after.stats if result.after is not None else None
        text = "; ".join(
            f"{e.key}={e.value:.4g}" + (f" ± {e.standard_error:.2g}" if e.standard_error is not None else "")
            for e in result.estimates
        )
        rows.append(
            {
                "rank": rank, "value": value, "parameters": text, "rms_abs": stats.rms_abs if stats else math.nan,
                "max_abs": stats.max_abs if stats else math.nan, "k": ev.k, "chi_square": ev.chi_square,
                "aicc": ev.aicc, "delta": ev.aicc - best, "bic": ev.bic,
                "evaluations": result.simulations + result.replayed, "converged": "yes" if result.converged else "no",
            }
        )  # fmt: skip
    notes = [
        "Each row is a separate fit of the same parameters and bounds at that value (its best parameters).",
        "Ranked by AICc = chi2 + 2k + 2k(k+1)/(n-k-1), k the parameters the data resolve; dAICc > 2: less support, "
        "> 10: essentially none (Burnham and Anderson 2002).",
    ]
    return Table(name, f"Contest of {key} at each one's fitted parameters", columns, rows, notes)
