"""The figures of a fit: profile scans, the posterior's corner plot and predictive band, the contest's errors.

The corner plot is drawn with matplotlib, not the ``corner`` package: for the two to four parameters of a
gait calibration it is a grid of histograms and 2-D histograms, and drawing it here keeps the house style
(column width, 8 pt, PNG + SVG) and one fewer dependency.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from biped_sim.io.references import MEASURED_UNITS
from biped_sim.plots import COLUMN_WIDTH_IN, PANEL_HEIGHT_IN, log_positive, log_scale, style_of, styled
from biped_sim.studies.fit import Calibration, FitResult
from biped_sim.studies.fit.bayes import PosteriorRun

HIST_BINS = 30


@styled
def profile_figure(result: FitResult) -> Figure:
    """Cost (half the sum of squared weighted residuals) along each parameter's scan; the optimum marked."""
    profiles = result.profiles
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 1.6 * len(profiles) + 0.4), layout="constrained")
    axes = fig.subplots(len(profiles), 1, squeeze=False)[:, 0]
    for ax, profile, estimate in zip(axes, profiles, result.estimates, strict=True):
        ax.plot(profile.values, profile.costs, marker="o", color="C0")
        ax.axvline(estimate.value, color="C3", linewidth=0.8, label="optimum")
        ax.set_xlabel(profile.key)
        ax.set_ylabel("cost")
        ax.set_title("smooth" if profile.smooth else f"not smooth: {profile.jump}")
    axes[0].legend(frameon=False)
    return fig


@styled
def corner_figure(posterior: PosteriorRun, truth: dict[str, float] | None = None) -> Figure:
    """Marginal histograms (90 % interval dashed) and pairwise 2-D histograms of the retained draws."""
    p = len(posterior.keys)
    size = max(COLUMN_WIDTH_IN, 1.6 * p)
    fig = Figure(figsize=(size, size), layout="constrained")
    axes = fig.subplots(p, p, squeeze=False)
    for i in range(p):
        for j in range(p):
            ax = axes[i, j]
            if j > i:
                ax.set_axis_off()
                continue
            if i == j:
                ax.hist(posterior.samples[:, i], bins=HIST_BINS, color="C0", histtype="step")
                for q in (posterior.intervals[posterior.keys[i]][0], posterior.intervals[posterior.keys[i]][2]):
                    ax.axvline(q, color="C0", linestyle="--", linewidth=0.8)
                ax.set_yticks([])
            else:
                ax.hist2d(posterior.samples[:, j], posterior.samples[:, i], bins=HIST_BINS, cmap="Blues")
            if truth:
                ax.axvline(truth.get(posterior.keys[j], np.nan), color="C3", linewidth=0.8)
                if i != j:
                    ax.axhline(truth.get(posterior.keys[i], np.nan), color="C3", linewidth=0.8)
            if i == p - 1:
                ax.set_xlabel(posterior.keys[j])
            if j == 0 and i > 0:
                ax.set_ylabel(posterior.keys[i])
            ax.tick_params(labelsize=6)
    return fig


@styled
def predictive_figure(calibration: Calibration) -> Figure:
    """Per quantity: the measured means (+- 2 std errors), the posterior predictive and model bands (5-95 %)."""
    problem = calibration.result.run.problem
    assert calibration.band is not None
    quantities = problem.used_quantities
    fig = Figure(figsize=(COLUMN_WIDTH_IN, PANEL_HEIGHT_IN * len(quantities) + 0.4), layout="constrained")
    axes = fig.subplots(len(quantities), 1, squeeze=False, sharex=True)[:, 0]
    for ax, quantity in zip(axes, quantities, strict=True):
        idx = [i for i, t in enumerate(problem.targets) if t.quantity == quantity]
        steps = [problem.targets[i].step for i in idx]
        predictive, model = calibration.band["predictive"][:, idx], calibration.band["model"][:, idx]
        ax.fill_between(steps, predictive[0], predictive[2], color="C0", alpha=0.2, label="predictive 90 %")
        ax.fill_between(steps, model[0], model[2], color="C0", alpha=0.5, label="model 90 %")
        ax.plot(steps, model[1], color="C0", label="posterior median")
        means = [problem.targets[i].mean for i in idx]
        errors = [2 * problem.targets[i].sigma for i in idx]
        ax.errorbar(steps, means, yerr=errors, color="k", marker="s", linestyle="none", capsize=2, label="reference")
        ax.set_ylabel(f"{quantity} [{MEASURED_UNITS[quantity]}]")
    axes[0].legend(frameon=False, fontsize=6)
    axes[-1].set_xlabel(f"step ({problem.reference.spec.step_origin} numbering)")
    axes[-1].xaxis.get_major_locator().set_params(integer=True)
    return fig


@styled
def contest_errors_figure(fits: Sequence[tuple[str, FitResult]]) -> Figure:
    """Per-step relative period error of each law at its best fit, side by side; the running RMS below."""
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2 * PANEL_HEIGHT_IN + 0.4), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    width = 0.8 / max(len(fits), 1)
    for i, (label, result) in enumerate(fits):
        after = result.after
        if after is None:
            continue
        steps = np.asarray(after.steps, dtype=float)
        relative = np.asarray(after.relative_errors, dtype=float)
        top.bar(steps - 0.4 + width * (i + 0.5), log_positive(relative), width, label=label, color=style_of(i)["color"])
        errors = np.asarray(after.errors, dtype=float)
        running = np.sqrt(np.cumsum(errors**2) / np.arange(1, len(errors) + 1))
        bottom.plot(steps, log_positive(1e3 * running), marker="o", label=label, **style_of(i))
    top.set_yscale("log")  # laws that reach the data and laws that do not differ by orders of magnitude
    log_scale(bottom)
    top.set_ylabel("|error| [%]")
    bottom.set_ylabel("RMS error, steps 1..k [ms]")
    bottom.set_xlabel("step number k")
    top.legend(frameon=False, fontsize=6)
    bottom.xaxis.get_major_locator().set_params(integer=True)
    return fig
