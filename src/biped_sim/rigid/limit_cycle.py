"""Period-1 gaits of the rigid walkers: the step-to-step map, Newton on its fixed point, Floquet multipliers.

Poincare section: just after a heel strike. Its coordinates are the independent post-impact variables
(see each rigid walker's ``section_names``): the impact fixes the others (the swing angle is minus the
stance angle; for the simplest walker the swing rate is cos(2 theta) times the stance rate; the rimless
wheel's stance angle is pi/N), so their multipliers are exactly zero and are dropped by working in
section coordinates. The multipliers are the eigenvalues of the step map's Jacobian by central
differences with relative step ``FD_STEP`` (truncation ~ h^2 ~ 1e-10, integration noise ~ 1e-12 / h ~
1e-7 relative at worst; the validation compares them with the simplest walker's variational equations).

The Newton solver and the finite-difference Jacobian are generic (any step map on a section): the
compliant limit cycle (:mod:`biped_sim.studies.limit_cycle`) uses them too. A compliant run that starts
on ``simulation.initial: rigid_limit_cycle`` gets its state from :func:`rigid_limit_cycle_initial`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.rigid.build import initial_state, rigid_walker
from biped_sim.rigid.compiled import CompiledWalker, compile_walker, rigid_step
from biped_sim.rigid.step import RTOL, RigidStep
from biped_sim.rigid.tree import RigidWalker

RIGID_TOLERANCE = 1e-10
FD_STEP = 1e-6
MAX_NEWTON = 30
SETTLE_STEPS = 30
LINES_NOTE = (
    "lines: each leg's line from the hip to its foot (the point, or the arc's centre), its angle from the slope "
    "normal (+ foot downhill), and the inter-leg angle stance minus swing, at the fixed point and at touchdown"
)
STABILITY_MARGIN = 1e-9  # |lambda| < 1 - margin counts as stable
# the gait search's scan when the walk from the guess falls: step angles [rad] x stance rates [sqrt(g / l)]
SCAN_ANGLES = (0.1, 0.15, 0.2, 0.25, 0.3)
SCAN_RATES = (0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.7, 1.0)
SCAN_SWING_RATIO = 0.6


@dataclass
class LimitCycle:
    """A period-1 fixed point of the step map and its multipliers."""

    dynamics: str
    walker: str
    slope: float
    converged: bool
    iterations: int
    residual: float
    section_names: tuple[str, ...]
    section_point: np.ndarray
    fixed_point: dict[str, float]
    touchdown: dict[str, float]
    step_period: float
    step_length: float
    jacobian: np.ndarray
    multipliers: np.ndarray
    tolerance: float
    notes: list[str] = field(default_factory=list)
    start: str = ""  # which start the solver found the cycle from (empty: not recorded)
    tried: str = ""  # every start the search tried (the one line of a failed search)
    lines: dict[str, dict[str, float]] = field(default_factory=dict)  # the legs' hip-to-foot lines: see leg_lines

    @property
    def max_multiplier_modulus(self) -> float:
        return float(np.max(np.abs(self.multipliers))) if len(self.multipliers) else math.nan

    @property
    def stable(self) -> bool:
        return bool(self.converged and self.max_multiplier_modulus < 1.0 - STABILITY_MARGIN)

    @property
    def speed(self) -> float:
        return self.step_length / self.step_period if self.step_period > 0 else math.nan

    def failure(self) -> str:
        """The one line of a search that did not converge: its best residual and what it tried."""
        return (
            f"no {self.dynamics} limit cycle: Newton did not converge (best residual {self.residual:.1e}, tolerance "
            f"{self.tolerance:g}) from {self.tried}"
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON document of ``biped-sim limit-cycle --json``; a search that did not converge is its status, what
        it tried and its residual, without the point it stopped at (not a gait)."""
        status = {
            "status": "converged" if self.converged else "not_converged",
            "dynamics": self.dynamics,
            "walker": self.walker,
            "slope": self.slope,
            "converged": self.converged,
            "iterations": self.iterations,
            "residual": self.residual,
            "tolerance": self.tolerance,
            "tried": self.tried,
        }
        if not self.converged:
            return {**status, "error": self.failure()}
        order = np.argsort(-np.abs(self.multipliers))
        return {
            **status,
            "section": list(self.section_names),
            "fixed_point": self.fixed_point,
            "touchdown": self.touchdown,
            "lines": self.lines,
            "step_period": self.step_period,
            "step_length": self.step_length,
            "speed": self.speed,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers[order]],
            "max_multiplier_modulus": self.max_multiplier_modulus,
            "stable": self.stable,
            "start": self.start,
            "notes": self.notes,
        }


class StepFailedError(RuntimeError):
    """The walker fell or stalled during a step of the map."""


class SearchFellError(ConfigError):
    """The walker fell from every start of a gait search: a config's start is unusable (a run on
    ``rigid_limit_cycle``), and the limit-cycle command's search failed (exit 1)."""


# --- rigid ---------------------------------------------------------------------------------------------------


def rigid_map(
    walker: RigidWalker, z: np.ndarray, compiled: CompiledWalker | None = None
) -> tuple[np.ndarray, RigidStep]:
    """The step-to-step map on the section: post-impact coordinates -> the next ones (the compiled step map of
    :mod:`biped_sim.rigid.compiled`; ``compiled``: its buffers, reused)."""
    x_start = walker.from_section(np.asarray(z, dtype=float))
    step = rigid_step(walker, x_start, cw=compiled)
    if step.status != "strike" or step.x_plus is None:
        raise StepFailedError(f"the rigid {walker.name} {step.status} during the step")
    return walker.to_section(step.x_plus), step


def map_jacobian(func: Callable[[np.ndarray], np.ndarray], z: np.ndarray, step: float = FD_STEP) -> np.ndarray:
    """Central-difference Jacobian; each coordinate perturbed by step * max(1, |z_i|)."""
    n = len(z)
    jac = np.zeros((n, n))
    for i in range(n):
        h = step * max(1.0, abs(z[i]))
        dz = np.zeros(n)
        dz[i] = h
        jac[:, i] = (func(z + dz) - func(z - dz)) / (2.0 * h)
    return jac


def newton_fixed_point(
    func: Callable[[np.ndarray], np.ndarray],
    z0: np.ndarray,
    tolerance: float,
    max_iter: int = MAX_NEWTON,
    fd_step: float = FD_STEP,
) -> tuple[np.ndarray, bool, int, float]:
    """Newton on F(z) = P(z) - z with a finite-difference Jacobian (relative step ``fd_step``); damped when a
    full step fails.

    Returns (z, converged, iterations, residual |P(z) - z|_inf).
    """
    z = np.asarray(z0, dtype=float)
    residual = math.inf
    for iteration in range(1, max_iter + 1):
        f = func(z) - z
        residual = float(np.max(np.abs(f)))
        if residual <= tolerance:
            return z, True, iteration - 1, residual
        jac = map_jacobian(func, z, fd_step) - np.eye(len(z))
        delta = np.linalg.lstsq(jac, -f, rcond=None)[0]
        scale = 1.0
        while True:
            try:
                candidate = z + scale * delta
                new_residual = float(np.max(np.abs(func(candidate) - candidate)))
                if new_residual < residual or scale < 1e-3:
                    break
            except StepFailedError:
                pass
            scale *= 0.5
            if scale < 1e-3:
                return z, False, iteration, residual
        z = candidate
    residual = float(np.max(np.abs(func(z) - z)))
    return z, residual <= tolerance, max_iter, residual


def settle(step_map: Callable[[np.ndarray], np.ndarray], z: np.ndarray, steps: int) -> np.ndarray:
    """Iterate the map ``steps`` times from z (a walk toward a stable cycle); stop at the last good point."""
    for _ in range(steps):
        try:
            z_next = step_map(z)
        except StepFailedError:
            break
        if not np.all(np.isfinite(z_next)):
            break
        z = z_next
    return z


SearchResult = tuple[np.ndarray, bool, int, float]


def _solve_from(
    step_map: Callable[[np.ndarray], np.ndarray], tries: list[tuple[str, np.ndarray, int]]
) -> tuple[SearchResult, str] | None:
    """Newton from each try (label, section point, steps walked from it first); the first converged solve wins,
    else the last solve that did not fall (None if every try fell)."""
    best = None
    for label, z0, steps in tries:
        how = f"{label}, after {steps} settling steps" if steps else label
        try:
            found = newton_fixed_point(step_map, settle(step_map, z0, steps) if steps else z0, RIGID_TOLERANCE)
            step_map(found[0])
        except StepFailedError:
            continue
        best = (found, how)
        if found[1]:
            break
    return best


def scan_starts(walker: RigidWalker) -> list[tuple[str, np.ndarray]]:
    """A small scan of post-impact section points: step angle x speed (rates in units of sqrt(g / l)).

    The swing leg starts at 0.6 times the stance rate (typical of passive gaits just after a strike).
    """
    scale = math.sqrt(walker.gravity / walker.leg_length)
    points = []
    for k in SCAN_RATES:
        rate = -k * scale
        if walker.shift:  # a wheel: its section is the rate alone
            points.append((f"scan stance_rate {rate:.4g}", np.array([rate])))
            continue
        for angle in SCAN_ANGLES:
            label = f"scan stance_angle {angle:g}, stance_rate {rate:.4g}"
            points.append((label, walker.section_point(angle, rate, SCAN_SWING_RATIO * rate)))
    return points


def rigid_limit_cycle(
    config: Config,
    guess: dict[str, float] | None = None,
    settle_steps: int = SETTLE_STEPS,
) -> LimitCycle:
    """Period-1 fixed point of the rigid model of ``config.walker`` and its multipliers.

    The initial guess is ``guess`` (the walker's initial-state keys, or its section's: :meth:`RigidWalker.guess_state`),
    else the config's initial state, else (for the
    rigid_limit_cycle start) generic post-impact states. The guess first walks ``settle_steps`` steps, so
    that Newton starts near the stable cycle when there is one, then Newton starts from the guess itself;
    when neither converges (the walker falls from the guess), the same two tries run from each point of
    :func:`scan_starts` in turn. ``settle_steps = 0`` finds the cycle nearest the guess, stable or not (no
    scan: a continuation must not jump branch). The record's ``start`` says which start found the cycle.
    """
    rigid = config if config.dynamics == "rigid" else config.model_copy(update={"dynamics": "rigid"})
    walker = rigid_walker(rigid)
    if guess is not None:
        starts = [("the guess", walker.guess_state(guess))]
    elif config.simulation.initial == "rigid_limit_cycle":
        starts = [(f"generic start {i + 1}", start) for i, start in enumerate(_generic_starts(walker))]
    else:
        starts = [("the config's initial state", initial_state(rigid, walker))]

    compiled = compile_walker(walker)

    def step_map(z: np.ndarray) -> np.ndarray:
        return rigid_map(walker, z, compiled)[0]

    tries = []
    for label, x in starts:  # each start walked (toward a stable gait), then as it is
        z0 = walker.to_section(x)
        tries += [(label, z0, settle_steps), (label, z0, 0)] if settle_steps else [(label, z0, 0)]
    solved = _solve_from(step_map, tries)
    tried = _tried([label for label, _ in starts], settle_steps)
    if settle_steps and (solved is None or not solved[0][1]):
        # the scan: every point walked first (stable gaits), then every point as it is (any gait)
        scan = scan_starts(walker)
        tried += f", then the {len(scan)} points of a scan (each walked, then as it is)"
        scanned = _solve_from(
            step_map, [(label, z, settle_steps) for label, z in scan] + [(label, z, 0) for label, z in scan]
        )
        if scanned is not None and (solved is None or scanned[0][1]):
            solved = scanned
    if solved is None:
        raise SearchFellError("simulation.initial", f"no rigid limit cycle: the walker falls from {tried}")
    (z, converged, iterations, residual), how = solved
    _, step = rigid_map(walker, z, compiled)
    jac = map_jacobian(step_map, z)
    x_plus = walker.from_section(z)
    x_touchdown = walker.relabelled(step.x_minus)
    lines = {"fixed_point": walker.leg_lines(x_plus), "touchdown": walker.leg_lines(x_touchdown)}
    lines = lines if lines["fixed_point"] else {}
    return LimitCycle(
        dynamics="rigid",
        walker=walker.name,
        slope=walker.slope,
        converged=converged,
        iterations=iterations,
        residual=residual,
        section_names=walker.section_names,
        section_point=z,
        fixed_point=walker.legs_state(x_plus),
        touchdown=walker.legs_state(x_touchdown),
        step_period=step.period,
        step_length=step.length,
        jacobian=jac,
        multipliers=np.linalg.eigvals(jac),
        tolerance=RIGID_TOLERANCE,
        notes=[
            f"found by Newton from {how}",
            "section just after heel strike; coordinates " + ", ".join(walker.section_names),
            f"step map: {'compiled DOP853' if compiled is not None else 'scipy DOP853'} rtol {RTOL:g}",
            f"multipliers: central differences, relative step {FD_STEP:g}; the coordinates the impact fixes "
            "(zero multipliers) are not section coordinates",
            "touchdown: the state just before the strike, relabelled (stance = the leg touching down)",
            *([LINES_NOTE] if lines else []),
        ],
        start=how,
        tried=tried,
        lines=lines,
    )


def _tried(labels: list[str], settle_steps: int) -> str:
    """What a search started from, in a few words: 'the guess (walked 30 steps, then as it is)'."""
    what = labels[0] if len(labels) == 1 else f"the {len(labels)} generic starts"
    return what + (f" (walked {settle_steps} steps, then as it is)" if settle_steps else "")


def _generic_starts(walker: RigidWalker) -> list[np.ndarray]:
    """Post-impact states typical of passive gaits (rates scaled by sqrt(g / l)), tried when no guess is given."""
    scale = math.sqrt(walker.gravity / walker.leg_length)
    if walker.shift:  # a wheel: its section is the rate alone
        return [walker.from_section(np.array([-k * scale])) for k in (1.0, 0.5, 2.0)]
    starts = ((0.25, 0.36), (0.2, 0.2), (0.3, 0.5))
    if len(walker.section_names) >= 3:  # the legs just after a strike, as the walker's section places them
        return [walker.from_section(walker.section_point(angle, -k * scale, -0.4 * k * scale)) for angle, k in starts]
    return [np.array([angle, -angle, -k * scale, -0.4 * k * scale]) for angle, k in starts]


def rigid_limit_cycle_initial(config: Config) -> dict[str, float]:
    """The rigid model's period-1 fixed point as a run's initial state (the initial-state keys)."""
    cycle = rigid_limit_cycle(config)
    if not cycle.converged:
        raise ConfigError(
            "simulation.initial", f"rigid_limit_cycle: Newton did not converge (residual {cycle.residual:.1e})"
        )
    return cycle.fixed_point
