"""The contest of laws (or of any config value) at their best fits: one entry per physics, ranked by evidence.

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

By physics, not by name: normal laws of one force family (``NormalLaw.family`` in the contact registry:
Hunt-Crossley, Lankarani-Nikravesh and Flores are all F = K delta^n (1 + chi deltadot / deltadot^-),
differing only in how the restitution maps to chi) are, with the restitution fitted, reparametrisations
of one law: the contest ranks the family once (by its best member) and reports each member's implied chi;
a member that cannot reach the family's best chi within the restitution's bounds is said to, not ranked
as a worse law. Entries within ``TIE_BAND`` of AICc are indistinguishable by the data.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from biped_sim.contact.normal import NORMAL_LAWS
from biped_sim.io.tables import Column, Table
from biped_sim.studies.fit.stats import FitResult

TIE_BAND = 2.0  # dAICc at most this: indistinguishable (Burnham and Anderson 2002: < 2 is substantial support)
NO_SUPPORT = 10.0  # dAICc above this: essentially no support
NORMAL_LAW_KEY, RESTITUTION_KEY = "contact.model", "contact.restitution"


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


@dataclass(frozen=True)
class Entry:
    """One contest value: its force family (the value itself when it has none), the family parameter it implies
    at its fit (``chi``, NaN without one) and the range that parameter spans over the fitted bounds."""

    label: str
    family: str
    chi: float
    chi_range: tuple[float, float]
    result: FitResult
    evidence: Evidence

    @property
    def score(self) -> tuple[float, float]:
        """The ranking key: AICc, then the RMS period error."""
        rms = self.result.after.stats.rms_abs if self.result.after is not None else math.nan
        return (
            self.evidence.aicc if math.isfinite(self.evidence.aicc) else math.inf,
            rms if math.isfinite(rms) else math.inf,
        )


def entry(key: str, label: str, result: FitResult) -> Entry:
    """The contest entry of ``result``: a normal law's family when the key is the law and the restitution is
    fitted (the family's members are then one law), else a family of its own."""
    law = NORMAL_LAWS.get(result.fitted_config.contact.model) if key == NORMAL_LAW_KEY else None
    fitted = {e.key: e for e in result.estimates}
    if law is None or RESTITUTION_KEY not in fitted:
        return Entry(label, label, math.nan, (math.nan, math.nan), result, evidence(result))
    if law.chi is None:
        return Entry(label, law.family, math.nan, (math.nan, math.nan), result, evidence(result))
    e = fitted[RESTITUTION_KEY]
    ends = sorted((law.chi(e.low), law.chi(e.high)))
    return Entry(label, law.family, law.chi(e.value), (ends[0], ends[1]), result, evidence(result))


def ranked(key: str, fits: list[tuple[str, FitResult]]) -> list[Entry]:
    """The entries, families in order of their best member (AICc, then RMS error), members best first."""
    entries = sorted((entry(key, label, result) for label, result in fits), key=lambda e: e.score)
    families = list(dict.fromkeys(e.family for e in entries))
    return [e for family in families for e in entries if e.family == family]


def verdicts(entries: list[Entry]) -> dict[str, str]:
    """Per entry (by label): what the data say of it against the best family and within its own family."""
    if not entries:
        return {}
    best = entries[0].evidence.aicc
    leaders = {e.family: e for e in reversed(entries)}  # each family's best member (entries are ranked)
    out = {}
    for e in entries:
        leader = leaders[e.family]
        if e is not leader and e.evidence.aicc - leader.evidence.aicc > TIE_BAND:
            low, high = e.chi_range
            out[e.label] = (
                f"{e.family} family: cannot reach its best chi {leader.chi:.3g} (spans {low:.3g}-{high:.3g} "
                "over the restitution's bounds)"
            )
            continue
        within = "" if e is leader and sum(x.family == e.family for x in entries) == 1 else f"{e.family} family, "
        delta = leader.evidence.aicc - best
        if leader is entries[0]:
            rivals = [x.family for x in leaders.values() if x is not leader and x.evidence.aicc - best <= TIE_BAND]
            out[e.label] = within + ("best" if not rivals else "indistinguishable from " + ", ".join(rivals))
        elif delta <= TIE_BAND:
            out[e.label] = within + f"indistinguishable from {entries[0].family}"
        else:
            out[e.label] = within + ("less support" if delta <= NO_SUPPORT else "essentially no support")
    return out


def summary(key: str, entries: list[Entry]) -> str:
    """One sentence: which physics the data pick, or which they cannot tell apart (with the implied chi)."""
    if not entries:
        return f"No fits of {key}."
    best = entries[0].evidence.aicc
    tied = [e for e in entries if e.evidence.aicc - best <= TIE_BAND]
    families = list(dict.fromkeys(e.family for e in tied))

    def members(family: str) -> str:
        inside = [e for e in tied if e.family == family]
        if len(inside) == 1 and inside[0].label == family:
            return family
        chis = ", ".join(f"{e.label} chi {e.chi:.3g}" if math.isfinite(e.chi) else e.label for e in inside)
        return f"the {family} family ({chis})"

    if len(families) == 1:
        return f"The data pick {members(families[0])}; every other entry is more than {TIE_BAND:g} in AICc behind."
    return (
        "Indistinguishable by the data (within " + f"{TIE_BAND:g} in AICc): " + "; ".join(map(members, families)) + "."
    )


def ranking_table(key: str, fits: list[tuple[str, FitResult]], name: str = "ranking") -> Table:
    """The contest: one row per value of ``key``, grouped by family, best first, with evidence and verdicts."""
    columns = [
        Column("rank", "rank"),
        Column("value", key),
        Column("family", "family"),
        Column("chi", "implied chi", fmt=".4g"),
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
        Column("verdict", "verdict"),
    ]
    order = ranked(key, fits)
    said = verdicts(order)
    families = list(dict.fromkeys(e.family for e in order))
    best = order[0].evidence.aicc if order else math.nan
    rows = []
    for e in order:
        result, ev = e.result, e.evidence
        stats = result.after.stats if result.after is not None else None
        text = "; ".join(
            f"{x.key}={x.value:.4g}" + (f" ± {x.standard_error:.2g}" if x.standard_error is not None else "")
            for x in result.estimates
        )
        rows.append(
            {
                "rank": families.index(e.family) + 1, "value": e.label, "family": e.family, "chi": e.chi,
                "parameters": text, "rms_abs": stats.rms_abs if stats else math.nan,
                "max_abs": stats.max_abs if stats else math.nan, "k": ev.k, "chi_square": ev.chi_square,
                "aicc": ev.aicc, "delta": ev.aicc - best, "bic": ev.bic,
                "evaluations": result.simulations + result.replayed, "converged": "yes" if result.converged else "no",
                "verdict": said[e.label],
            }
        )  # fmt: skip
    notes = [
        summary(key, order),
        "Each row is a separate fit of the same parameters and bounds at that value (its best parameters); laws of "
        "one force family (the contact registry's) are one law under a fitted restitution and share a rank.",
        "Ranked by AICc = chi2 + 2k + 2k(k+1)/(n-k-1), k the parameters the data resolve; dAICc <= "
        f"{TIE_BAND:g}: indistinguishable, > {NO_SUPPORT:g}: essentially no support (Burnham and Anderson 2002).",
    ]
    return Table(name, f"Contest of {key} at each one's fitted parameters", columns, rows, notes)
