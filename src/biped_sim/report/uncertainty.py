"""The figures of an uncertainty study: step-period bands against step number, histograms of the outputs, the
ranked Sobol indices(each PNG + SVG, house style)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from biped_sim.config.walker_registry import capabilities
from biped_sim.plots import COLUMN_WIDTH_IN, new_figure, save_figure, styled
from biped_sim.studies.uncertainty.mfpt import MfptCurve
from biped_sim.studies.uncertainty.sobol import SobolIndices, ranking
from biped_sim.studies.uncertainty.statistics import column, walking_mask
from biped_sim.studies.uncertainty.study import Uncertainty

HISTOGRAM_OUTPUTS = ("steady_period", "speed", "step_length", "energy_per_step")
UNITS = {"steady_period": "s", "speed": "m/s", "step_length": "m", "energy_per_step": "J", "slip": "m",
         "peak_normal_force": "N"}  # fmt: skip


def _unit(study: Uncertainty, name: str) -> str:
    nondimensional = capabilities(study.spec.config.walker.kind).nondimensional
    return "nondim." if nondimensional else UNITS.get(name, "")


@styled
def bands_figure(study: Uncertainty) -> Figure:
    """The median step period against step number with its 50 % and 90 % bands over the walking samples."""
    fig, (ax,) = new_figure()
    bands = study.bands
    step, q = bands["step"], bands["quantiles"]
    if step.size:
        ax.fill_between(step, q[0], q[4], color="C0", alpha=0.2, lw=0, label="90 %")
        ax.fill_between(step, q[1], q[3], color="C0", alpha=0.4, lw=0, label="50 %")
        ax.plot(step, q[2], color="C0", label="median")
        ax.legend(loc="best")
    ax.set_xlabel("step number")
    ax.set_ylabel(f"step period [{_unit(study, 'steady_period')}]")
    walking = study.stats["probability_walking"]["value"]
    ax.set_title(f"{len(study.values)} samples, {walking:.0%} walk")
    return fig


@styled
def histograms_figure(study: Uncertainty) -> Figure:
    """Histograms of the main outputs over the walking samples, one panel each."""
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.2), layout="constrained")
    axes = fig.subplots(2, 2).ravel()
    walks = walking_mask(study.outputs)
    for ax, name in zip(axes, HISTOGRAM_OUTPUTS, strict=True):
        values = column(study.outputs, name)[walks]
        values = values[np.isfinite(values)]
        if values.size:
            ax.hist(values, bins=min(30, max(5, values.size // 10)), color="C0")
        ax.set_xlabel(f"{name.replace('_', ' ')} [{_unit(study, name)}]", fontsize=7)
        ax.tick_params(labelsize=6)
    return fig


@styled
def sobol_figure(indices: SobolIndices) -> Figure:
    """First-order and total indices with their confidence intervals, keys ranked by total index, one panel
    per output that has indices."""
    shown = [o for o in indices.outputs if o.indices is not None]
    fig, axes = new_figure(rows=max(1, len(shown)), height=0.5 + (0.35 + 0.18 * len(indices.keys)) * max(1, len(shown)))
    for ax, out in zip(axes, shown, strict=False):
        order = [indices.keys.index(k) for k in ranking(out, indices.keys)]
        pos = np.arange(len(order))
        s = out.indices
        assert s is not None
        ax.barh(pos - 0.2, s["ST"][order], 0.4, xerr=s["ST_conf"][order], color="C0", label="total")
        ax.barh(pos + 0.2, s["S1"][order], 0.4, xerr=s["S1_conf"][order], color="C1", label="first order")
        ax.set_yticks(pos, [indices.keys[j] for j in order], fontsize=6)
        ax.invert_yaxis()
        ax.set_title(f"{out.output} ({out.blocks_used}/{out.blocks} blocks)")
        ax.grid(axis="y", visible=False)
    axes[0].legend(loc="lower right")
    axes[-1].set_xlabel("Sobol index")
    return fig


@styled
def mfpt_figure(curves: Sequence[MfptCurve]) -> Figure:
    """Mean first-passage time (steps) against roughness: the walks' estimates with their intervals, and the
    Markov chain's where there is one."""
    fig, (ax,) = new_figure()
    for i, curve in enumerate(curves):
        x = np.array(curve.roughness)
        mfpt = np.array([e.mfpt for e in curve.estimates])
        ci = np.array([e.ci for e in curve.estimates])
        fell = np.isfinite(mfpt)
        m, low, high = mfpt[fell], ci[fell, 0], ci[fell, 1]
        high = np.where(np.isfinite(high), high, m)  # an unbounded upper end: drawn to the estimate
        ax.errorbar(x[fell], m, yerr=[m - low, high - m], marker="o", ls="", color=f"C{i}", capsize=2,
                    label=f"{curve.ground} walks ({curve.seeds} seeds)")  # fmt: skip
        if not fell.all():  # no walk fell: only the interval's lower end is known
            ax.plot(x[~fell], ci[~fell, 0], marker="^", ls="", color=f"C{i}", label="no fall: MFPT above")
        if curve.chain is not None:
            ax.plot(x, curve.chain, color=f"C{i}", label="Markov chain")
    ax.set_yscale("log")
    ax.set_xlabel(curves[0].roughness_label if curves else "roughness")
    ax.set_ylabel("mean first-passage time [steps]")
    ax.legend(loc="best")
    return fig


def save_study_figures(study: Uncertainty, out_dir: Path) -> list[Path]:
    """bands, histograms and (with indices) sobol, each PNG + SVG."""
    paths = save_figure(bands_figure(study), out_dir, "bands") + save_figure(
        histograms_figure(study), out_dir, "histograms"
    )
    if study.indices is not None and any(o.indices is not None for o in study.indices.outputs):
        paths += save_figure(sobol_figure(study.indices), out_dir, "sobol")
    return paths
