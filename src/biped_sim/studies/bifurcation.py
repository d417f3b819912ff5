"""Bifurcation diagram of a rigid walker against the slope: continuation plus brute-force steady states.

Continuation: the period-1 fixed point is followed slope by slope (Newton from the previous solution),
with its multipliers; the period-doubling slope is where the most negative real multiplier passes -1,
refined by bisection. Brute force: at each slope the walker walks ``BRUTE_STEPS`` steps from the
period-1 cycle of the previous slope, slightly perturbed, and the last ``RECORDED`` step periods are
recorded: one value for a period-1 gait, two for period 2, a cloud for chaos.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from biped_sim.config import Config, derive
from biped_sim.config.walker_registry import require_study
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.io.atomic import write_text_atomic
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import LimitCycle, rigid_limit_cycle
from biped_sim.simulate.budget import check_run_count
from biped_sim.studies.continuation import bisect_flip, continue_cycle, flip_margin

PARAMETER = "ground.slope"  # the one parameter the diagram varies
BRUTE_STEPS = 150
RECORDED = 16
PERTURBATION = 1e-4


@dataclass
class BifurcationDiagram:
    """Continuation rows and brute-force samples."""

    slopes: np.ndarray
    cycles: list[LimitCycle | None]
    brute: list[tuple[float, list[float]]]
    period_doubling_slope: float | None


def _brute_force(config: Config, slope: float, start: np.ndarray) -> list[float]:
    walker = rigid_walker(derive(config, {"ground.slope": slope}))
    x = walker.from_section(start + PERTURBATION)
    periods = []
    for _ in range(BRUTE_STEPS):
        step = rigid_step(walker, x)
        if step.status != "strike" or step.x_plus is None:
            return []
        periods.append(step.period)
        x = step.x_plus
    return periods[-RECORDED:]


def check_bifurcation(config: Config, start: float, stop: float, n: int, param: str = PARAMETER) -> None:
    """What :func:`bifurcation_diagram` refuses: another ``param`` than the slope, a compliant config, a slope
    ``start`` or ``stop`` the config cannot take, fewer than 2 or more than ``MAX_RUNS`` slopes ``n``."""
    if param != PARAMETER:
        raise ArgumentError("param", f"only {PARAMETER} is supported")
    require_study(config.walker.kind, "bifurcation", "bifurcation continues a rigid walker's period-1 cycle")
    if config.dynamics != "rigid":
        raise ConfigError("dynamics", "bifurcation runs the rigid model: set dynamics to rigid")
    for name, value in (("start", start), ("stop", stop)):
        try:
            derive(config, {PARAMETER: value})
        except ConfigError as exc:
            raise ArgumentError(name, f"slope {value}: {exc.reason}") from None
    if n < 2:
        raise ArgumentError("n", "at least 2 slopes")
    check_run_count(n, "n", "slopes")


def bifurcation_diagram(
    config: Config, start: float, stop: float, n: int, param: str = PARAMETER
) -> BifurcationDiagram:
    """Continuation and brute force over ``n`` slopes from ``start`` to ``stop`` (:func:`check_bifurcation`)."""
    check_bifurcation(config, start, stop, n, param)
    slopes = np.linspace(start, stop, n)
    cycle: LimitCycle | None = rigid_limit_cycle(derive(config, {"ground.slope": float(start)}))
    cycles: list[LimitCycle | None] = []
    brute = []
    flip_bracket: tuple[LimitCycle, LimitCycle] | None = None
    for slope in slopes:
        if cycle is not None:
            try:
                cycle = continue_cycle(config, float(slope), cycle.fixed_point)
            except ValueError:
                cycle = None
            if cycle is not None and not cycle.converged:
                cycle = None
        cycles.append(cycle)
        previous = cycles[-2] if len(cycles) > 1 else None
        if (
            cycle is not None
            and previous is not None
            and flip_bracket is None
            and flip_margin(previous) > 0 >= flip_margin(cycle)
        ):
            flip_bracket = (previous, cycle)
        seed = next((c.section_point for c in reversed(cycles) if c is not None), None)
        brute.append((float(slope), _brute_force(config, float(slope), seed) if seed is not None else []))
    flip = bisect_flip(config, *flip_bracket)[0] if flip_bracket is not None else None
    return BifurcationDiagram(slopes, cycles, brute, flip)


def write_bifurcation(diagram: BifurcationDiagram, out_dir) -> None:  # type: ignore[no-untyped-def]
    """bifurcation.csv (continuation) and brute_force.csv (steady periods); the figure is report.bifurcation's."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(
        [
            "slope",
            "converged",
            "stance_angle",
            "stance_rate",
            "swing_rate",
            "step_period",
            "max_multiplier",
            "stable",
            "multipliers",
        ]
    )
    for slope, cycle in zip(diagram.slopes, diagram.cycles, strict=True):
        if cycle is None:
            writer.writerow([repr(float(slope)), False, "", "", "", "", "", "", ""])
            continue
        # the section's coordinates (a kneed walker's hip bodies), else the fixed point's (the simplest's swing rate)
        point = {**cycle.fixed_point, **dict(zip(cycle.section_names, cycle.section_point, strict=True))}
        writer.writerow(
            [
                repr(float(slope)),
                cycle.converged,
                repr(float(point["stance_angle"])),
                repr(float(point["stance_rate"])),
                repr(float(point["swing_rate"])),
                repr(cycle.step_period),
                repr(cycle.max_multiplier_modulus),
                cycle.stable,
                " ".join(f"{m.real:.10g}{m.imag:+.10g}j" for m in cycle.multipliers),
            ]
        )
    write_text_atomic(out_dir / "bifurcation.csv", buffer.getvalue())
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["slope", "step_period"])
    for slope, periods in diagram.brute:
        for period in periods:
            writer.writerow([repr(slope), repr(period)])
    write_text_atomic(out_dir / "brute_force.csv", buffer.getvalue())


__all__ = ["BifurcationDiagram", "bifurcation_diagram", "write_bifurcation"]
