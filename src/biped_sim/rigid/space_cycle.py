"""Period-1 gaits of the rigid walker in space: Newton on the step map's fixed point, Floquet multipliers.

Poincare section: just after a strike, mirrored so that the stance leg is the left leg (a symmetric gait is a
fixed point: the right leg's step is the left's mirror image). Its coordinates: heading (measured from the
downhill direction), bank, pitch, the stance leg's angular velocity (slope frame) and the hinge rate, and a torso's
angle and rate. The hinge
angle is not one: the strike puts the trailing foot on the ground, which fixes it (solved from the others, the
root near minus twice the pitch; its multiplier would be exactly zero). On a slope the heading is a state like the
others (gravity's downhill component turns the walker); on level ground the map is the same in every heading, so
the heading is left out of the section (the walker starts each step heading 0) and its multiplier, exactly 1, is
reported beside the others. Newton and the finite-difference Jacobian are the planar model's
(:mod:`biped_sim.rigid.limit_cycle`); the search without a guess walks a scan of sagittal starts first, as the
planar searches do.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.config import Config
from biped_sim.config.space_description import SPACE_STATE_KEYS, SPACE_TORSO_KEYS, SpaceDescription
from biped_sim.rigid.limit_cycle import (
    FD_STEP,
    RIGID_TOLERANCE,
    SCAN_ANGLES,
    SCAN_RATES,
    SETTLE_STEPS,
    LimitCycle,
    SearchFellError,
    SearchResult,
    StepFailedError,
    map_jacobian,
    newton_fixed_point,
    settle,
)
from biped_sim.rigid.space_integration import space_clearance, space_scratch
from biped_sim.rigid.space_kernels import space_params
from biped_sim.rigid.space_model import SpaceModel, space_model
from biped_sim.rigid.space_step import SINGULAR, SINGULAR_REASON, SpaceStep, space_step
from biped_sim.rigid.step import RTOL

CONTINUATION_STEP = 0.125  # the largest step of the homotopy's share (sagittal twin 0 -> walker 1)
MIN_CONTINUATION_STEP = 1.0 / 1024
SWING_RATE_RATIO = -0.6  # the hinge rate just after a strike, times the stance pitch rate (planar gaits' 0.4 - 1)
RATES = (4, 5, 6, 7)  # the section's rates: omega_x, omega_y, omega_z, swing_rate


class SpaceSection:
    """The section's coordinates of a walker in space (module docstring)."""

    def __init__(self, model: SpaceModel) -> None:
        self.model = model
        self.params = space_params(model)
        self.heading = model.slope != 0.0
        torso = (model.torso_angle, model.torso_angle + 1) if model.torso else ()
        self.indices = ((0,) if self.heading else ()) + (1, 2, *RATES, *torso)

    @property
    def names(self) -> tuple[str, ...]:
        """The coordinates' names."""
        return tuple(self.model.state_names[i] for i in self.indices)

    def to_section(self, x: np.ndarray) -> np.ndarray:
        """A post-strike state's section coordinates."""
        return np.array([x[i] for i in self.indices])

    def of_keys(self, keys: dict[str, float]) -> np.ndarray:
        """The section coordinates of a post-strike state given by its keys (those missing 0)."""
        return self.to_section(np.array([keys.get(name, 0.0) for name in self.model.state_names]))

    def from_section(self, z: np.ndarray) -> np.ndarray:
        """The post-strike state of section coordinates ``z``: the hinge angle that puts the trailing foot on the
        ground (secant iterations from minus twice the pitch)."""
        x = np.zeros(self.model.n_state)
        x[list(self.indices)] = z
        a, b = -2.0 * x[2], -1.9 * x[2]
        fa, fb = self._clearance(x, a), self._clearance(x, b)
        for _ in range(50):
            if fb == fa or abs(fb) < 1e-15:
                break
            a, b, fa = b, b - fb * (b - a) / (fb - fa), fb
            fb = self._clearance(x, b)
        x[3] = b
        return x

    def _clearance(self, x: np.ndarray, beta: float) -> float:
        x[3] = beta
        return space_clearance(self.params, x)


def space_state_keys(model: SpaceModel) -> tuple[str, ...]:
    """The keys of the walker's post-strike state (``simulation.initial``'s): the legs', a torso's."""
    return SPACE_STATE_KEYS + (SPACE_TORSO_KEYS if model.torso else ())


def space_walker_model(config: Config) -> SpaceModel:
    """The rigid model of a walker in space (``Config.in_space``)."""
    return space_model(config.walker.space, config.gravity, config.ground.slope)  # type: ignore[union-attr]


class SpaceMap:
    """The step map on the section, its compiled parameters built once."""

    def __init__(self, model: SpaceModel) -> None:
        self.model = model
        self.section = SpaceSection(model)
        self.params = self.section.params
        self.scratch = space_scratch(0, model.n_state)

    def step(self, z: np.ndarray) -> tuple[np.ndarray, SpaceStep]:
        """The next section point and the step."""
        start = self.section.from_section(np.asarray(z, dtype=float))
        try:
            step = space_step(self.model, start, self.params, self.scratch)
        except SINGULAR:
            raise StepFailedError(f"the rigid walker in space stopped: {SINGULAR_REASON}") from None
        if step.x_plus is None:
            raise StepFailedError(f"the rigid walker in space {step.status} during the step")
        return self.section.to_section(step.x_plus), step

    def __call__(self, z: np.ndarray) -> np.ndarray:
        return self.step(z)[0]


def scan(model: SpaceModel, section: SpaceSection) -> list[tuple[str, np.ndarray]]:
    """Sagittal post-strike starts (pitch back by the scan's angles, forward pitch rates in sqrt(g / l)); the
    lateral coordinates start at zero, a torso upright and at rest (as the planar scan's)."""
    scale = math.sqrt(model.gravity / model.leg_length)
    starts = []
    for k in SCAN_RATES:
        for angle in SCAN_ANGLES:
            x = np.zeros(model.n_state)
            x[2], x[5], x[7] = -0.5 * angle, k * scale, SWING_RATE_RATIO * k * scale
            if model.torso:  # its pitch and its rate about y zero: its angle and rate from the stance leg's opposite
                x[model.torso_angle], x[model.torso_angle + 1] = -x[2], -x[5]
            starts.append((f"scan pitch {-0.5 * angle:g}, omega_y {k * scale:.4g}", section.to_section(x)))
    return starts


def sagittal_twin(space: SpaceDescription, share: float) -> SpaceDescription:
    """The walker with its lateral geometry scaled by ``share``: hip width, the leg's lateral centre of mass and
    foot offsets, the products of inertia that couple y, and a ring's plane's tilt off the planes the mirror keeps
    (its normal's x and z components when its y outweighs its x, else its y: never a flat ring), a splayed leg's
    alike (0: its sagittal twin, a planar walker in space, whose gait the sagittal scan finds; 1: the walker
    itself); a knee's point, its shank's centre of mass and products alike."""
    leg, (nx, ny, nz) = space.leg, space.leg.foot.normal
    inertia = leg.inertia.model_copy(update={"xy": share * leg.inertia.xy, "yz": share * leg.inertia.yz})
    com = (leg.com[0], share * leg.com[1], leg.com[2])
    centre = (leg.foot.centre[0], share * leg.foot.centre[1], leg.foot.centre[2])
    normal = (share * nx, ny, share * nz) if abs(ny) >= abs(nx) else (nx, share * ny, nz)
    foot = leg.foot.model_copy(update={"centre": centre, "normal": normal})
    knee = leg.knee and leg.knee.model_copy(
        update={
            "at": (leg.knee.at[0], share * leg.knee.at[1], leg.knee.at[2]),
            "com": (leg.knee.com[0], share * leg.knee.com[1], leg.knee.com[2]),
            "inertia": leg.knee.inertia.model_copy(
                update={"xy": share * leg.knee.inertia.xy, "yz": share * leg.knee.inertia.yz}
            ),
        }
    )
    scaled = leg.model_copy(update={"com": com, "inertia": inertia, "foot": foot, "knee": knee})
    return space.model_copy(update={"hip_width": share * space.hip_width, "leg": scaled})


def _scan_solve(step_map: SpaceMap, settle_steps: int) -> tuple[SearchResult, str] | None:
    """Newton from each scan point walked ``settle_steps`` first (0: as it is): the first converged solve, else
    the last one that did not fall (None: it fell from every point)."""
    found = None
    for label, z0 in scan(step_map.model, step_map.section):
        try:
            solved = newton_fixed_point(step_map, settle(step_map, z0, settle_steps), RIGID_TOLERANCE)
        except StepFailedError:
            continue
        found = (solved, f"{label}, after {settle_steps} settling steps" if settle_steps else label)
        if solved[1]:
            break
    return found


def _continued(config: Config, z: np.ndarray) -> tuple[SearchResult, float]:
    """Newton along the homotopy from the sagittal twin's gait ``z`` (share 0) to the walker (share 1), the share
    stepped up while Newton converges from the last fixed point and halved when it does not; the last result and
    the share it reached."""
    share, step, solved = 0.0, CONTINUATION_STEP, (z, True, 0, 0.0)
    while share < 1.0 and step >= MIN_CONTINUATION_STEP:
        trial = min(1.0, share + step)
        twin = space_model(sagittal_twin(config.walker.space, trial), config.gravity, config.ground.slope)  # type: ignore[union-attr]
        try:
            result = newton_fixed_point(SpaceMap(twin), solved[0], RIGID_TOLERANCE)
        except StepFailedError:
            result = (solved[0], False, 0, math.inf)
        if result[1]:
            share, solved, step = trial, result, min(2.0 * step, CONTINUATION_STEP)
        else:
            step *= 0.5
    return (solved if share == 1.0 else (solved[0], False, solved[2], solved[3])), share


def space_limit_cycle(config: Config, settle_steps: int = SETTLE_STEPS) -> LimitCycle:
    """The period-1 gait of a walker in space, found without a guess, the first that converges of: Newton from
    each point of :func:`scan` walked ``settle_steps`` steps (a stable gait draws the walk in); the gait of its
    sagittal twin (:func:`sagittal_twin`, found so) continued to the walker; Newton from each scan point as it is
    (any gait). ``settle_steps = 0``: the last only."""
    model = space_walker_model(config)
    step_map = SpaceMap(model)
    found, tried = None, f"the {len(scan(model, step_map.section))} points of a scan"
    if settle_steps:
        found = _scan_solve(step_map, settle_steps)
        tried += f" (each walked {settle_steps} steps), the sagittal twin's gait continued, the scan as it is"
    if settle_steps and (found is None or not found[0][1]):
        space, g, slope = config.walker.space, config.gravity, config.ground.slope  # type: ignore[union-attr]
        twin_map = SpaceMap(space_model(sagittal_twin(space, 0.0), g, slope))
        twin = _scan_solve(twin_map, settle_steps)  # its lateral instability may topple the walks: then as it is
        twin = twin if twin is not None and twin[0][1] else _scan_solve(twin_map, 0)
        if twin is not None and twin[0][1]:
            continued, share = _continued(config, twin[0][0])
            found = (continued, f"the sagittal twin's gait ({twin[1]}) continued to share {share:.4g}")
    if found is None or not found[0][1]:
        found = _scan_solve(step_map, 0) or found
    if found is None:
        raise SearchFellError("walker", f"no rigid limit cycle: the walker falls from {tried}")
    (z, converged, iterations, residual), how = found
    return _cycle(step_map, z, converged, iterations, residual, how, tried, config.walker.kind)


def space_cycle_from(config: Config, keys: dict[str, float]) -> LimitCycle | None:
    """The period-1 gait by Newton from the post-strike state ``keys`` (a start near the gait: a second, where the
    search without a guess takes 10-20 CPU s); None when Newton does not converge or the walker falls on the way."""
    step_map = SpaceMap(space_walker_model(config))
    try:
        z, converged, iterations, residual = newton_fixed_point(
            step_map, step_map.section.of_keys(keys), RIGID_TOLERANCE
        )
    except StepFailedError:
        return None
    how = "the configured start"
    return _cycle(step_map, z, converged, iterations, residual, how, how, config.walker.kind) if converged else None


def space_branch(configs: list[Config], settle_steps: int = SETTLE_STEPS) -> list[LimitCycle]:
    """One branch of gaits through a series of walkers (e.g. a foot radius stepped up): the first walker's gait
    found by :func:`space_limit_cycle`, each next one by Newton from the last fixed point (small changes keep to
    the branch where a new search could land on another gait); the series stops at the first that does not
    converge (its record included)."""
    cycles = [space_limit_cycle(configs[0], settle_steps)]
    for config in configs[1:]:
        if not cycles[-1].converged:
            break
        step_map = SpaceMap(space_walker_model(config))
        try:
            z, converged, iterations, residual = newton_fixed_point(step_map, cycles[-1].section_point, RIGID_TOLERANCE)
        except StepFailedError:
            break
        how = "the previous walker's fixed point"
        cycles.append(_cycle(step_map, z, converged, iterations, residual, how, how, config.walker.kind))
    return cycles


def _cycle(
    step_map: SpaceMap,
    z: np.ndarray,
    converged: bool,
    iterations: int,
    residual: float,
    how: str,
    tried: str,
    walker: str,
) -> LimitCycle:
    """The limit-cycle record at section point ``z`` of a ``walker`` (its kind)."""
    section = step_map.section
    _, step = step_map.step(z)
    jac = map_jacobian(step_map, z)
    multipliers = np.linalg.eigvals(jac)
    if not section.heading:
        multipliers = np.append(multipliers, 1.0)
    x_plus = section.from_section(z)
    names, state = space_state_keys(step_map.model), step_map.model.state_names
    return LimitCycle(
        dynamics="rigid",
        walker=walker,
        slope=step_map.model.slope,
        converged=converged,
        iterations=iterations,
        residual=residual,
        section_names=section.names,
        section_point=z,
        fixed_point={name: float(x_plus[state.index(name)]) for name in names},
        touchdown={name: float(step.x_minus[state.index(name)]) for name in names},
        step_period=step.period,
        step_length=step.length,
        jacobian=jac,
        multipliers=multipliers,
        tolerance=RIGID_TOLERANCE,
        notes=[
            f"found by Newton from {how}",
            "section just after heel strike, mirrored to the left leg's stance; coordinates "
            + ", ".join(section.names),
            "the hinge angle is fixed by the trailing foot on the ground (not a coordinate)"
            + ("; the swing knee starts straight and at rest (not a coordinate)" if step_map.model.knee else "")
            + ("; the torso's angle is from the stance leg about the hinge axis" if step_map.model.torso else "")
            + ("" if section.heading else "; level ground: heading left out, its multiplier 1 appended"),
            f"step map: compiled DOP853, rtol {RTOL:g}",
            f"multipliers: central differences, relative step {FD_STEP:g}",
            "touchdown: the state just before the strike (not mirrored)",
        ],
        start=how,
        tried=tried,
    )
