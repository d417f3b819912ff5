"""Figures of single runs and of sweeps: PNG at 200 dpi and SVG, sized to be read at column width.

Every figure is 3.5 in wide (one journal column) with 8 pt text, so that printed at column
width its labels are 8 pt; nothing is saved as JPEG (the paper's reviewers asked for sharp
figures). Figures are built on :class:`matplotlib.figure.Figure` directly (Agg canvas, no pyplot
state), so plotting works headless and in worker processes.

The figure functions take a list of ``(label, RunData)`` series: one series for ``biped-sim
plot RUN_DIR``, several overlaid for a sweep report.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Literal, TypeVar

import matplotlib as mpl
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from biped_sim.io.atomic import write_with
from biped_sim.io.output import OutputKind, staged_directory
from biped_sim.io.trajectory import RunData
from biped_sim.measure.pose import run_poses
from biped_sim.picture import WalkerPicture, draw_ground, draw_space_walker
from biped_sim.studies.compare import Comparison

COLUMN_WIDTH_IN = 3.5
PANEL_HEIGHT_IN = 2.1
PNG_DPI = 200
LEGEND_INSIDE_MAX = 3
STRIKE_WINDOW = (0.02, 0.12)  # fractions of the step period shown before and after a heel strike
WALKER_POSES = 6  # poses of the walker figure, over one step

STYLE = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 6.5,
    "lines.linewidth": 1.0,
    "lines.markersize": 3,
    "axes.grid": True,
    "grid.linewidth": 0.4,
    "grid.alpha": 0.5,
    "svg.fonttype": "none",  # text stays text in the SVG
    "svg.hashsalt": "biped-sim",  # reproducible SVG ids
}
LINESTYLES = ("-", "--", "-.", ":")

Series = Sequence[tuple[str, RunData]]
F = TypeVar("F", bound=Callable[..., Any])


@contextmanager
def figure_style() -> Iterator[None]:
    """The house style for every figure of the package (text sizes apply when artists are made)."""
    with mpl.rc_context(STYLE):
        yield


def styled(func: F) -> F:
    """Decorator: build the figure inside :func:`figure_style`."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with figure_style():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def new_figure(rows: int = 1, height: float | None = None, sharex: bool = True) -> tuple[Figure, list[Axes]]:
    """A column-width figure with ``rows`` stacked panels."""
    fig = Figure(figsize=(COLUMN_WIDTH_IN, height or PANEL_HEIGHT_IN * rows + 0.4), layout="constrained")
    axes = fig.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]
    return fig, list(axes)


def save_figure(fig: Figure, out_dir: Path, name: str) -> list[Path]:
    """Write ``name.png`` (200 dpi) and ``name.svg`` atomically; returns both paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    with figure_style():
        for fmt in ("png", "svg"):
            path = out_dir / f"{name}.{fmt}"
            # no creation date or software stamp: the same figure gives the same file
            metadata = {"Date": None} if fmt == "svg" else {"Software": None}

            def draw(tmp: Path, fmt: str = fmt, metadata: dict[str, None] = metadata) -> None:
                fig.savefig(tmp, format=fmt, dpi=PNG_DPI, metadata=metadata)

            write_with(path, draw)
            paths.append(path)
    return paths


def style_of(index: int) -> dict[str, object]:
    """Colour and line style of the ``index``-th series (10 colours, then dashed, ...)."""
    return {"color": f"C{index % 10}", "linestyle": LINESTYLES[(index // 10) % len(LINESTYLES)]}


def add_legend(fig: Figure, ax: Axes, count: int) -> None:
    """A legend inside the axes for a few series, below the figure for many."""
    handles, labels = ax.get_legend_handles_labels()
    if count <= 1 or not handles:  # nothing drawn: e.g. a run that fell or diverged before its first heel strike
        return
    if count <= LEGEND_INSIDE_MAX:
        ax.legend(handles, labels, frameon=False)
    else:
        fig.legend(handles, labels, loc="outside lower center", ncol=2, frameon=False)


def log_positive(values: np.ndarray) -> np.ndarray:
    """Values for a log axis: zeros and negatives become gaps."""
    values = np.asarray(values, dtype=float)
    return np.where(values > 0, values, np.nan)


def log_scale(ax: Axes, axis: Literal["x", "y"] = "y") -> None:
    """A log scale on ``axis`` when the data drawn on it have a positive value; else it stays linear, with a note.

    matplotlib cannot place log ticks without one, and fails only when the figure is saved: a run whose
    constraint violations are all zero or NaN (one that diverged at once) would stop every figure after it.
    """
    data = [np.asarray(line.get_ydata() if axis == "y" else line.get_xdata(), dtype=float) for line in ax.get_lines()]
    if any(np.any(np.isfinite(values) & (values > 0)) for values in data):
        if axis == "y":
            ax.set_yscale("log")
        else:
            ax.set_xscale("log")
        return
    ax.text(0.5, 0.5, "no positive values to draw", transform=ax.transAxes, ha="center", va="center", color="0.4")


def completed_periods(run: RunData) -> np.ndarray:
    """Periods of the completed steps (the last strike begins a step that did not finish)."""
    return run.steps["period"][:-1] if len(run.steps["period"]) else np.array([])


def completed_slips(run: RunData) -> np.ndarray:
    """Stance-foot slip of the completed steps [m]."""
    return run.steps["slip"][:-1] if len(run.steps["slip"]) else np.array([])


def per_step_figure(series: Series, per_step: Callable[[RunData], np.ndarray], y_label: str) -> tuple[Figure, Axes]:
    """A quantity of each completed step against step number, one line per run."""
    fig, (ax,) = new_figure()
    for i, (label, run) in enumerate(series):
        values = per_step(run)
        ax.plot(np.arange(1, len(values) + 1), values, marker="o", label=label, **style_of(i))
    ax.set_xlabel("step number")
    ax.set_ylabel(y_label)
    add_legend(fig, ax, len(series))
    return fig, ax


@styled
def step_period_figure(series: Series) -> Figure:
    """Step period against step number."""
    return per_step_figure(series, completed_periods, "step period [s]")[0]


@styled
def constraint_violation_figure(series: Series) -> Figure:
    """Position and velocity constraint violation ||Phi||, ||Phidot|| against time (log scale)."""
    fig, (top, bottom) = new_figure(2)
    for i, (label, run) in enumerate(series):
        top.plot(run.time, log_positive(run.violation_position), label=label, **style_of(i))
        bottom.plot(run.time, log_positive(run.violation_velocity), label=label, **style_of(i))
    log_scale(top)
    log_scale(bottom)
    top.set_ylabel(r"$\|\Phi\|$ [m]")
    bottom.set_ylabel(r"$\|\dot\Phi\|$ [m/s]")
    bottom.set_xlabel("time [s]")
    add_legend(fig, top, len(series))
    return fig


def middle_strike(run: RunData) -> int | None:
    """Index of a heel strike in the middle of the walk with a finished step after it (None if no step)."""
    n = len(run.steps["strike_time"])
    if n == 0:
        return None
    return min(n // 2, max(n - 2, 0))


@styled
def contact_forces_figure(series: Series) -> Figure:
    """Normal and friction force against time around a heel strike in the middle of each run.

    The window (2 % of the step before, 12 % after) shows the impact, the bounce and the start
    of single support; the samples are those of ``output.sample_rate``. One run: both feet (the
    striking foot solid, the trailing foot dashed: double support and lift-off). Several runs:
    the striking foot of each.
    """
    fig, (top, bottom) = new_figure(2)
    single = len(series) == 1
    for i, (label, run) in enumerate(series):
        k = middle_strike(run)
        if k is None:
            continue
        t_strike = run.steps["strike_time"][k]
        period = run.steps["period"][k]
        span = period if math.isfinite(period) else 0.5
        window = (run.time >= t_strike - STRIKE_WINDOW[0] * span) & (run.time <= t_strike + STRIKE_WINDOW[1] * span)
        t_ms = (run.time[window] - t_strike) * 1e3
        foot = int(run.steps["foot"][k])
        feet = [(foot, "-", "striking foot"), (1 - foot, "--", "trailing foot")] if single else [(foot, "-", label)]
        for f, linestyle, name in feet:
            style = {**style_of(0 if single else i), "linestyle": linestyle}
            top.plot(t_ms, run.normal_force[window, f], label=name, **style)
            bottom.plot(t_ms, run.friction_force[window, f], label=name, **style)
    top.set_ylabel("normal force [N]")
    bottom.set_ylabel("friction force [N]")
    bottom.set_xlabel("time from heel strike [ms]")
    add_legend(fig, top, 2 if single else len(series))
    return fig


ENERGY_TERMS = (
    ("kinetic", "kinetic"),
    ("potential", "potential"),
    ("elastic", "elastic (contact)"),
    ("dissipated_normal", "dissipated, normal"),
    ("dissipated_friction", "dissipated, friction"),
    ("dissipated_impact", "dissipated, impacts"),  # a rigid run's
    ("dissipated_elements", "dissipated, joint elements"),
)


@styled
def energy_terms_figure(run: RunData) -> Figure:
    """One run: energy terms against time (changes from t = 0), and the balance residual below."""
    fig, (top, bottom) = new_figure(2)
    e = run.energy
    for i, (name, label) in enumerate((name, label) for name, label in ENERGY_TERMS if name in e):
        top.plot(run.time, e[name] - e[name][0], label=label, **style_of(i))
    bottom.plot(run.time, e["residual"], **style_of(0))
    unit = run.summary.get("units", {}).get("energy", "J")  # a rigid run's may be per kg or nondimensional
    top.set_ylabel(f"energy change [{unit}]")
    bottom.set_ylabel(rf"$E - E_0 + W_\mathrm{{diss}}$ [{unit}]")
    bottom.set_xlabel("time [s]")
    handles, labels = top.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=2, frameon=False)
    return fig


@styled
def energy_balance_figure(series: Series) -> Figure:
    """Several runs: energy dissipated by normal damping and by friction, and |residual| (log), against time."""
    fig, axes = new_figure(3)
    for i, (label, run) in enumerate(series):
        e = run.energy
        axes[0].plot(run.time, e["dissipated_normal"] - e["dissipated_normal"][0], label=label, **style_of(i))
        axes[1].plot(run.time, e["dissipated_friction"] - e["dissipated_friction"][0], label=label, **style_of(i))
        axes[2].plot(run.time, log_positive(np.abs(e["residual"])), label=label, **style_of(i))
    axes[0].set_ylabel("normal damping [J]")
    axes[1].set_ylabel("friction [J]")
    axes[2].set_ylabel("|energy residual| [J]")
    log_scale(axes[2])
    axes[2].set_xlabel("time [s]")
    add_legend(fig, axes[0], len(series))
    return fig


@styled
def slip_figure(series: Series) -> Figure:
    """Stance-foot slip per step [mm] against step number."""
    fig, ax = per_step_figure(series, lambda run: completed_slips(run) * 1e3, "stance-foot slip [mm]")
    ax.axhline(0.0, color="0.5", linewidth=0.6)
    return fig


@styled
def phase_portrait_figure(series: Series) -> Figure:
    """Leg angle against leg angular rate. One run: both legs; several runs: the first leg of each."""
    fig, (ax,) = new_figure(height=3.0, sharex=False)
    single = len(series) == 1
    for i, (label, run) in enumerate(series):
        bodies = run.body_names if single else run.body_names[:1]
        angles, rates = run.leg_angles(), run.leg_rates()
        for j, body in enumerate(bodies):
            name = body if single else label
            ax.plot(angles[:, j], rates[:, j], label=name, **style_of(j if single else i))
    ax.set_xlabel(r"leg angle $\theta$ [rad]")
    ax.set_ylabel(r"leg rate $\dot\theta$ [rad/s]")
    add_legend(fig, ax, 2 if single else len(series))
    return fig


@styled
def walker_figure(run: RunData) -> Figure:
    """The walker at :data:`WALKER_POSES` instants of a step in the middle of the run (the earlier paler) over its
    ground (the whole run if it has no complete step), drawn from its description (:mod:`biped_sim.picture`)."""
    strikes, k = run.steps["strike_time"], middle_strike(run)
    t0, t1 = (strikes[k], strikes[k + 1]) if k is not None and k + 1 < len(strikes) else (run.time[0], run.time[-1])
    samples = np.unique(np.searchsorted(run.time, np.linspace(t0, t1, WALKER_POSES)).clip(0, len(run.time) - 1))
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 2.2), layout="constrained")
    if run.config.in_space:  # a walker in space: its sagittal and 3D views
        draw_space_walker(fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2, projection="3d"), run, samples)
        return fig
    poses = run_poses(run)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.axis("off")
    for i, alpha in zip(samples, np.linspace(0.3, 1.0, len(samples)), strict=True):
        WalkerPicture(ax, poses.skeleton, run.config.ground.slope, float(alpha), 1.2).place(poses.at(int(i)))
    reach = max(float(np.max(poses.hip[samples, 1])), 1e-3)
    x = poses.hip[samples, 0]
    draw_ground(ax, run.config, float(x.min()) - 0.6 * reach, float(x.max()) + 0.6 * reach, 0.15 * reach)
    ax.relim()  # the walker's lines were placed after they were made
    ax.autoscale_view()
    return fig


RUN_FIGURES = ("step_period", "constraint_violation", "contact_forces", "energy", "slip", "phase_portrait", "walker")
RIGID_RUN_FIGURES = ("step_period", "energy", "phase_portrait", "walker")  # no contact, slip or constraint drift
PLOT_OUTPUT = OutputKind("plot", tuple(f"{name}.{fmt}" for name in RUN_FIGURES for fmt in ("png", "svg")))
FIGURES: dict[str, Callable[[RunData], Figure]] = {
    "step_period": lambda run: step_period_figure([(run.label, run)]),
    "constraint_violation": lambda run: constraint_violation_figure([(run.label, run)]),
    "contact_forces": lambda run: contact_forces_figure([(run.label, run)]),
    "energy": energy_terms_figure,
    "slip": lambda run: slip_figure([(run.label, run)]),
    "phase_portrait": lambda run: phase_portrait_figure([(run.label, run)]),
    "walker": walker_figure,
}


def plot_run(run: RunData, out_dir: Path) -> list[Path]:
    """Every single-run figure of ``run`` (a rigid run's :data:`RIGID_RUN_FIGURES`) into ``out_dir`` (PNG + SVG
    each), which is replaced as a whole once all are drawn: a failure leaves the old figures as they were, and no
    old figure stays beside new ones."""
    names = RIGID_RUN_FIGURES if run.dynamics == "rigid" else RUN_FIGURES
    with staged_directory(out_dir, PLOT_OUTPUT) as stage:
        paths = [path for name in names for path in save_figure(FIGURES[name](run), stage, name)]
    return [out_dir / path.name for path in paths]


@styled
def parameter_lines_figure(
    x_label: str, y_label: str, lines: Sequence[tuple[str, Sequence[float], Sequence[float]]], log_y: bool = False
) -> Figure:
    """A quantity against a swept parameter, one line per ``(label, x, y)``."""
    fig, (ax,) = new_figure()
    for i, (label, x, y) in enumerate(lines):
        ax.plot(x, log_positive(np.asarray(y, dtype=float)) if log_y else y, marker="o", label=label, **style_of(i))
    if log_y:
        log_scale(ax)
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
    add_legend(fig, ax, len(lines))
    return fig


@styled
def bar_figure(labels: Sequence[str], values: Sequence[float | None], x_label: str) -> Figure:
    """One horizontal bar per run (sweeps without a numeric axis); a run without the value (None) has no bar."""
    fig, (ax,) = new_figure(height=0.8 + 0.2 * len(labels))
    positions = np.arange(len(labels))
    ax.barh(positions, [math.nan if value is None else value for value in values], color="C0")
    ax.set_yticks(positions, labels)
    ax.invert_yaxis()
    ax.grid(axis="y", visible=False)
    ax.set_xlabel(x_label)
    return fig


@styled
def accuracy_cost_figure(series: Sequence[tuple[str, Sequence[float], Sequence[float]]]) -> Figure:
    """Integrators: step-period deviation from the reference run against wall time (log-log), one marker set each."""
    fig, (ax,) = new_figure()
    for i, (label, wall, deviation) in enumerate(series):
        ax.plot(wall, log_positive(np.asarray(deviation, dtype=float)), marker="os^vD<>"[i % 7], linestyle="none",
                label=label, color=f"C{i % 10}")  # fmt: skip
    log_scale(ax, "x")
    log_scale(ax, "y")
    ax.set_xlabel("integration wall time [s]")
    ax.set_ylabel("max |step period - reference| [s]")
    add_legend(fig, ax, len(series))
    return fig


@styled
def comparison_figure(
    steps: Sequence[int],
    reference: Sequence[float],
    reference_std: Sequence[float] | None,
    reference_label: str,
    series: Sequence[tuple[str, Sequence[float], Sequence[float]]],
    published: dict[str, Sequence[float]],
) -> Figure:
    """Reference and model step periods against step number; relative error against step number below.

    ``series``: (label, model periods, relative errors [%]) on the reference's steps;
    ``published``: another model's published errors [%] on the same steps (grey, for comparison).
    """
    fig, (top, bottom) = new_figure(2)
    top.errorbar(
        steps, reference, yerr=reference_std, color="k", marker="s", linestyle="none", capsize=2, label=reference_label
    )
    for i, (label, model, relative) in enumerate(series):
        top.plot(steps, model, marker="o", label=label, **style_of(i))
        bottom.plot(steps, relative, marker="o", label=label, **style_of(i))
    for j, (name, values) in enumerate(published.items()):
        bottom.plot(
            steps, values, marker="^", color=f"{0.35 + 0.2 * j:.2f}", linestyle=":", label=f"{name} (published)"
        )
    top.set_ylabel("step period [s]")
    bottom.set_ylabel("relative error [%]")
    bottom.set_xlabel("step number")
    bottom.set_ylim(bottom=0)
    top.xaxis.get_major_locator().set_params(integer=True)
    add_legend(fig, top, len(series) + 1)
    if published:
        bottom.legend(frameon=False)
    return fig


def comparisons_figure(comparisons: Sequence[Comparison]) -> Figure:
    """:func:`comparison_figure` of model period series against their (shared) reference and its published errors."""
    reference = comparisons[0].reference
    return comparison_figure(
        reference.steps,
        reference.values,
        reference.std,
        reference.short_name,
        [(c.label, c.model_periods, c.relative_errors) for c in comparisons],
        comparisons[0].published,
    )
