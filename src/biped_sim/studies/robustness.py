"""How much a walker's gait survives: step down and up, pushes, rough ground, and its gait sensitivity norm.

The walker is started on its gait, then disturbed once, one step ahead, and survives when it walks
``SURVIVAL_STEPS`` further heel strikes without falling (or diverging):

* rigid dynamics: from the rigid limit cycle's post-impact state
  (:func:`~biped_sim.rigid.limit_cycle.rigid_limit_cycle`); the disturbed step is the second (step 1, from the
  first heel strike);
* compliant dynamics: from the config's initial state after ``SETTLE_STEPS`` heel strikes of settling; the
  disturbed step is the one that begins at the last of them.

An undisturbed reference run gives the disturbed step's start t_d and end t_d+1 (heel strikes), and the hip's
x at t_d+1: where the disturbances are put. A step (``ground.profile`` steps) has its riser at that x, halfway
between the feet at the touchdown that ends the disturbed step, so that the landing foot meets the new level;
a push (``simulation.pushes``, along the slope) acts at mid-stance (t_d + t_d+1) / 2; rough ground
(``random`` profile, heights every ``RANDOM_SPACING`` leg lengths) begins at that x.

A walker in space (``Config.in_space``) is pushed across the slope too ('lateral': right and left, on the hinge's
midpoint), in its own dynamics (its other takes settings of its own: :func:`robustness_configs`); its rigid model
walks flat ground only, so its rigid study has pushes alone (no steps, rough ground or GSN).

Largest disturbance survived: the size is doubled from a first guess until the walker falls, then bisected to
``STEP_TOLERANCE`` leg lengths (steps) or ``PUSH_TOLERANCE`` relative (pushes). The result is the largest size
seen to survive; a walker that survives some larger sizes too (survival need not be monotonic) is not searched
beyond the first failure bracketed. Sizes beyond ``MAX_STEP`` / ``MAX_PUSH`` are not tried.

Gait sensitivity norm (Hobbelen and Wisse, IEEE Trans. Robotics 23 (2007) 1213-1224): after a step down of
e = ``GSN_STEP`` leg lengths (rigid 1e-6: Garcia's walker responds nonlinearly already at 1e-4; compliant 1e-4,
well above the integration noise), the gait indicators g = (step period / sqrt(l / g), step length / l) of the
disturbed step and the ``GSN_STEPS`` after it, minus the undisturbed gait's, give
GSN = sqrt(sum_k sum_i dg_ik^2) / (e / l): a finite difference of a linear response (the tests halve e).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from biped_sim.config import Config, derive
from biped_sim.config.walker_registry import require_study
from biped_sim.errors import ArgumentError, ConfigError, quote
from biped_sim.io.tables import Column, Table
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.space_cycle import space_limit_cycle, space_walker_model
from biped_sim.simulate import RunResult, simulate
from biped_sim.simulate.budget import check_run_count
from biped_sim.simulate.rigid import RigidRunResult
from biped_sim.simulate.space_rigid import SpaceRunResult

SURVIVAL_STEPS = 10
SETTLE_STEPS = 10
STEP_TOLERANCE = 1e-4  # [leg lengths]
PUSH_TOLERANCE = 1e-2  # relative
FIRST_STEP = 0.01  # [leg lengths] first size tried
FIRST_PUSH = 0.05  # [m_total sqrt(g l)]
MAX_STEP = 0.5  # [leg lengths]
MAX_PUSH = 2.0  # [m_total sqrt(g l)]
ROUGHNESS = (0.001, 0.002, 0.005, 0.01)  # [leg lengths] standard deviation of the random heights
SEEDS = 20
RANDOM_SPACING = 0.1  # [leg lengths]
GSN_STEP = {"rigid": 1e-6, "compliant": 1e-4}  # [leg lengths] small enough for a linear response
GSN_STEPS = 30
SAMPLE_RATE = 50.0  # samples per sqrt(l / g) (the runs' steps are read, and the hip at one time)
DYNAMICS = ("rigid", "compliant")


@dataclass(frozen=True)
class Gait:
    """A walker started on its gait, and where and when its disturbed step happens."""

    config: Config  # the undisturbed run (initial state resolved, flat ground, no pushes, unlimited steps)
    disturbed_step: int  # d: the step from heel strike d (0 = the start) to d + 1
    step_start: float  # t_d
    step_end: float  # t_d+1
    riser_x: float  # the hip's x at t_d+1 (slope frame)
    period: np.ndarray  # reference step periods of steps d, d + 1, ... (GSN_STEPS + 1 of them)
    length: np.ndarray  # and their lengths
    leg_length: float
    time_scale: float  # sqrt(l / g)
    push_scale: float  # m_total sqrt(g l)


@dataclass(frozen=True)
class Trial:
    """One disturbed run: did it survive, and the gait indicators of its steps from the disturbed one on."""

    survived: bool
    period: np.ndarray
    length: np.ndarray


def _with(
    config: Config,
    *,
    steps: int,
    ground: dict[str, Any] | None = None,
    push: tuple[float, float] | None = None,
    t: float = 0.0,
) -> Config:
    """The config of a run of ``steps`` heel strikes, with a ground profile and a push at t (along the slope,
    lateral: to the right, a walker in space's)."""
    values: dict[str, Any] = {"simulation.max_steps": steps}
    if ground is not None:
        values["ground.profile"] = ground
    if push is not None:
        impulse = [push[0], 0.0, push[1]] if config.in_space else [push[0], 0.0]
        values["simulation.pushes"] = [{"time": t, "impulse": impulse}]
    return derive(config, values)


def robustness_configs(config: Config, dynamics: str = "both") -> list[Config]:
    """``config`` under each dynamics asked for: 'rigid', 'compliant', or 'both' (those the walker has; a walker
    in space's own: its other dynamics takes settings of its own, its compliant runs many times the rigid one's
    cost); ArgumentError naming ``dynamics`` for another name, or a single dynamics the walker has no model for."""
    if dynamics not in (*DYNAMICS, "both"):
        raise ArgumentError("dynamics", f"unknown dynamics {quote(dynamics)}; expected rigid, compliant or both")
    if dynamics == "both" and config.in_space:
        return [config]
    configs = []
    for kind in DYNAMICS if dynamics == "both" else (dynamics,):
        try:
            configs.append(_under(config, kind))
        except ConfigError:
            if dynamics != "both":
                raise ArgumentError("dynamics", f"the {config.walker.kind} walker has no {kind} model") from None
    return configs


def _under(config: Config, dynamics: str) -> Config:
    """``config`` in ``dynamics``: a walker in space's other dynamics with its formulation (compliant: spatial;
    rigid: the planar default, without spin friction), not a walker in space then (ConfigError)."""
    values: dict[str, Any] = {"dynamics": dynamics}
    if config.in_space and dynamics != config.dynamics:
        space = {"formulation.kind": "spatial"} if dynamics == "compliant" else {"formulation.kind": "planar"}
        values |= space | ({"friction.spin_radius": 0.0} if dynamics == "rigid" else {})
    derived = derive(config, values)
    if config.in_space and not derived.in_space:
        raise ConfigError("dynamics", f"the walker in space has no {dynamics} model from this config's start")
    return derived


def _strike_times(result: RunResult) -> np.ndarray:
    """Heel-strike times with t = 0 first (strike k ends step k - 1)."""
    return np.concatenate([[0.0], result.steps.strike_time])


def _hip_x(result: RunResult, t: float) -> float:
    """The hip's x along the slope at time t (interpolated between samples)."""
    rigid = isinstance(result, RigidRunResult | SpaceRunResult)
    times = result.time if rigid else result.run.t  # type: ignore[attr-defined]
    return float(np.interp(t, times, result.hip[:, 0]))  # type: ignore[attr-defined]


def _scales(config: Config) -> tuple[float, float, float]:
    """(leg length, gravity, mass) of the walker's rigid model, either dynamics: the units of the disturbances
    (the simplest walker's are 1; the mass per kg of hub for the rimless wheel's)."""
    if config.in_space:
        model = space_walker_model(config)
        return model.leg_length, model.gravity, sum(part.mass for part in model.parts)
    walker = rigid_walker(config)
    return walker.leg_length, walker.gravity, walker.reference_mass


def flat_only(config: Config) -> bool:
    """Whether the walker walks flat ground only (a walker in space in rigid dynamics): no steps, rough ground or
    GSN then."""
    return config.in_space and config.dynamics == "rigid"


def gait_start(config: Config) -> Gait:
    """Start the walker of ``config`` on its gait (rigid limit cycle, or settled) and run the reference."""
    require_study(config.walker.kind, "robustness", "robustness pushes a planar walker and steps its ground")
    leg, gravity, mass = _scales(config)
    time_scale = math.sqrt(leg / gravity)
    undisturbed: dict[str, Any] = {
        "ground.profile": {"kind": "flat"}, "simulation.pushes": [], "simulation.max_steps": None,
        "simulation.t_end": 20.0 * (SETTLE_STEPS + GSN_STEPS) * time_scale,
        "output.sample_rate": SAMPLE_RATE / time_scale,
    }  # fmt: skip
    d = 1 if config.dynamics == "rigid" else SETTLE_STEPS
    if config.dynamics == "rigid" or config.simulation.initial == "rigid_limit_cycle":  # resolved once for all runs
        search = space_limit_cycle if config.in_space else rigid_limit_cycle
        undisturbed["simulation.initial"] = search(config).fixed_point
    base = derive(config, undisturbed)
    reference = simulate(_with(base, steps=d + GSN_STEPS + 2))
    strikes = _strike_times(reference)
    if reference.status != "walking" or len(strikes) < d + GSN_STEPS + 3:
        raise ConfigError(
            "simulation.initial", f"the undisturbed {config.dynamics} walker does not walk ({reference.status})"
        )
    return Gait(
        config=base,
        disturbed_step=d,
        step_start=float(strikes[d]),
        step_end=float(strikes[d + 1]),
        riser_x=_hip_x(reference, float(strikes[d + 1])),
        period=reference.steps.period[d - 1 : d + GSN_STEPS],  # row k: the step from heel strike k + 1
        length=reference.steps.length[d - 1 : d + GSN_STEPS],
        leg_length=leg,
        time_scale=time_scale,
        push_scale=mass * math.sqrt(gravity * leg),
    )


def trial(gait: Gait, kind: str, size: float, seed: int = 0, steps: int = SURVIVAL_STEPS) -> Trial:
    """Run the gait disturbed once: ``kind`` 'step' (height [leg lengths], < 0 down), 'push' (impulse along the
    slope [m_total sqrt(g l)], > 0 forward), 'lateral' (a walker in space's push across the slope, > 0 to the
    right) or 'random' (roughness [leg lengths], ``seed``); then ``steps`` heel strikes after the disturbed step."""
    d, l = gait.disturbed_step, gait.leg_length
    strikes = d + 1 + steps
    if kind == "step":
        ground = {"kind": "steps", "steps": [{"at": gait.riser_x, "height": size * l}]}
        config = _with(gait.config, steps=strikes, ground=ground)
    elif kind in ("push", "lateral"):
        t_push, impulse = 0.5 * (gait.step_start + gait.step_end), size * gait.push_scale
        push = (impulse, 0.0) if kind == "push" else (0.0, impulse)
        config = _with(gait.config, steps=strikes, push=push, t=t_push)
    else:
        length = 3.0 * (steps + 2) * float(np.max(gait.length))
        ground = {
            "kind": "random", "spacing": RANDOM_SPACING * l, "roughness": size * l, "seed": seed,
            "start": gait.riser_x, "length": length,
        }  # fmt: skip
        config = _with(gait.config, steps=strikes, ground=ground)
    result = simulate(config)
    survived = result.status == "walking" and len(result.steps.strike_time) >= strikes
    return Trial(survived, result.steps.period[d - 1 :], result.steps.length[d - 1 :])


def largest_survived(
    survives: Callable[[float], bool], first: float, cap: float, tolerance: float, relative: bool
) -> tuple[float, float | None]:
    """(largest size seen to survive, smallest seen to fail or None when even ``cap`` survived).

    Doubling from ``first`` brackets the first failure, bisection narrows the bracket to ``tolerance``
    (times the failing size when ``relative``). Size 0 (the undisturbed gait) is taken to survive.
    """
    good, bad = 0.0, first
    while survives(bad):
        good = bad
        if bad >= cap:
            return good, None
        bad = min(2.0 * bad, cap)
    while bad - good > (tolerance * bad if relative else tolerance):
        middle = 0.5 * (good + bad)
        if survives(middle):
            good = middle
        else:
            bad = middle
    return good, bad


def gait_sensitivity(gait: Gait, e: float) -> float:
    """GSN for a step down of ``e`` leg lengths (module docstring): nondimensional, per leg length; nan when the
    walker falls (its gait has no response to linearise)."""
    run = trial(gait, "step", -e, steps=GSN_STEPS)
    if not run.survived:
        return math.nan
    n = GSN_STEPS + 1
    d_period = (run.period[:n] - gait.period[:n]) / gait.time_scale
    d_length = (run.length[:n] - gait.length[:n]) / gait.leg_length
    return float(math.sqrt(np.sum(d_period**2) + np.sum(d_length**2)) / e)


@dataclass
class Robustness:
    """What one dynamics of a walker survives (sizes in leg lengths and m_total sqrt(g l), as in :func:`trial`);
    None, nan or empty: not run (a walker on flat ground only has no steps, rough ground or GSN; a planar walker no
    lateral pushes)."""

    dynamics: str
    walker: str
    step_down: tuple[float, float | None] | None  # (largest survived, smallest failed or None: survived MAX_STEP)
    step_up: tuple[float, float | None] | None
    push_forward: tuple[float, float | None]
    push_backward: tuple[float, float | None]
    rough_survival: dict[float, float]  # roughness -> fraction of the seeds survived
    gsn: float
    leg_length: float
    push_scale: float  # m_total sqrt(g l) in N s (nondimensional for the simplest walker)
    notes: list[str] = field(default_factory=list)
    push_right: tuple[float, float | None] | None = None  # a walker in space's, across the slope
    push_left: tuple[float, float | None] | None = None

    def to_json(self) -> dict[str, Any]:
        doc = asdict(self)
        doc["rough_survival"] = [{"roughness": r, "survival": f} for r, f in self.rough_survival.items()]
        return doc


def largest_disturbance(
    gait: Gait, kind: str, sign: float, step_tolerance: float = STEP_TOLERANCE
) -> tuple[float, float | None]:
    """The largest step (``kind`` 'step', sign -1 down, +1 up; to ``step_tolerance`` leg lengths) or push
    ('push', +1 forward, -1 backward; 'lateral', +1 right, -1 left) survived, with the smallest seen to fail
    (:func:`largest_survived`)."""
    if kind == "step":
        return largest_survived(
            lambda h: trial(gait, "step", sign * h).survived, FIRST_STEP, MAX_STEP, step_tolerance, False
        )
    return largest_survived(lambda p: trial(gait, kind, sign * p).survived, FIRST_PUSH, MAX_PUSH, PUSH_TOLERANCE, True)


def _task(gait: Gait, task: tuple[str, float, int]) -> Any:
    """One independent piece of the study (a worker's job): a search, a rough-ground run or the GSN."""
    kind, value, seed = task
    if kind == "random":
        return trial(gait, "random", value, seed).survived
    if kind == "gsn":
        return gait_sensitivity(gait, value)
    return largest_disturbance(gait, kind, value)


def robustness(
    config: Config,
    executor: Executor | None = None,
    roughness: tuple[float, ...] = ROUGHNESS,
    seeds: int = SEEDS,
) -> Robustness:
    """The robustness of the walker of ``config`` with its own dynamics (module docstring); ``executor`` runs
    the searches, the rough-ground runs and the GSN in parallel (else one after the other)."""
    if seeds < 1:
        raise ArgumentError("seeds", "must be at least 1")
    check_run_count(len(roughness) * seeds, "seeds", "rough-ground runs (roughness levels times seeds)")
    gait, flat = gait_start(config), flat_only(config)
    searches = [("push", 1.0), ("push", -1.0)] + ([] if flat else [("step", -1.0), ("step", 1.0)])
    searches += [("lateral", 1.0), ("lateral", -1.0)] if config.in_space else []
    tasks = [(kind, sign, 0) for kind, sign in searches]
    if not flat:
        tasks += [("gsn", GSN_STEP[config.dynamics], 0)]
        tasks += [("random", level, seed) for level in roughness for seed in range(seeds)]
    if executor is None:
        results = [_task(gait, task) for task in tasks]
    else:
        results = list(executor.map(_task, [gait] * len(tasks), tasks))
    found = dict(zip(searches, results, strict=False))
    survived = results[len(searches) + 1 :]
    levels = () if flat else roughness
    rough = {level: float(np.mean(survived[i * seeds : (i + 1) * seeds])) for i, level in enumerate(levels)}
    return Robustness(
        dynamics=config.dynamics,
        walker=config.walker.kind,
        step_down=found.get(("step", -1.0)),
        step_up=found.get(("step", 1.0)),
        push_forward=found[("push", 1.0)],
        push_backward=found[("push", -1.0)],
        rough_survival=rough,
        gsn=math.nan if flat else results[len(searches)],
        leg_length=gait.leg_length,
        push_scale=gait.push_scale,
        push_right=found.get(("lateral", 1.0)),
        push_left=found.get(("lateral", -1.0)),
        notes=_notes(config, seeds),
    )


def _notes(config: Config, seeds: int) -> list[str]:
    """What the study ran and how (:class:`Robustness`'s notes)."""
    rigid = config.dynamics == "rigid"
    start = "the rigid limit cycle" if rigid else f"the config's start after {SETTLE_STEPS} steps"
    notes = [
        f"started on {start}; disturbed once, one step ahead; survived = {SURVIVAL_STEPS} more heel strikes",
        f"pushes on the hip along the slope at mid-stance to {PUSH_TOLERANCE:.0%}; none tried beyond "
        f"{MAX_PUSH:g} m_total sqrt(g l)",
    ]
    if config.in_space:  # the left leg stands on even steps
        leg = "right" if (1 if rigid else SETTLE_STEPS) % 2 else "left"
        notes.append(f"push right, left: across the slope on the hinge's midpoint, the {leg} leg standing")
    if flat_only(config):
        return [*notes, "rigid in space: flat ground only (no steps, rough ground or GSN)"]
    return [
        *notes,
        f"steps to {STEP_TOLERANCE:g} leg lengths (riser halfway between the feet at the disturbed step's end), "
        f"none tried beyond {MAX_STEP:g} leg lengths",
        f"rough h [l]: the fraction of {seeds} seeds of random ground of roughness h survived (heights every "
        f"{RANDOM_SPACING:g} leg lengths from the riser's x on)",
        f"GSN: step down of {GSN_STEP[config.dynamics]:g} leg lengths, (period / sqrt(l/g), length / l) over "
        f"{GSN_STEPS + 1} steps, per leg length (Hobbelen and Wisse 2007)",
    ]


ROBUSTNESS_COLUMNS = [
    Column("walker", "walker"),
    Column("dynamics", "dynamics"),
    Column("step_down", "step down", "l", ".4f"),
    Column("step_up", "step up", "l", ".4f"),
    Column("push_forward", "push forward", "m sqrt(g l)", ".3f"),
    Column("push_backward", "push backward", "m sqrt(g l)", ".3f"),
    Column("gsn", "GSN", "1/l", ".3g"),
]
LATERAL_COLUMNS = [
    Column("push_right", "push right", "m sqrt(g l)", ".3f"),
    Column("push_left", "push left", "m sqrt(g l)", ".3f"),
]
SEARCHES = ("step_down", "step_up", "push_forward", "push_backward", "push_right", "push_left")


def robustness_table(results: list[Robustness]) -> Table:
    """The robustness table (largest disturbances survived, rough-ground survival, GSN) of some walkers; a walker
    in space's lateral pushes; blank: not run."""
    levels = sorted({level for r in results for level in r.rough_survival})
    lateral = LATERAL_COLUMNS if any(r.push_right is not None for r in results) else []
    columns = ROBUSTNESS_COLUMNS[:6] + lateral + ROBUSTNESS_COLUMNS[6:]
    columns += [Column(f"rough_{level:g}", f"rough {level:g}", "l", ".2f") for level in levels]
    rows = []
    for r in results:
        row: dict[str, Any] = {"walker": r.walker, "dynamics": r.dynamics, "gsn": r.gsn}
        for key in SEARCHES:
            if getattr(r, key) is None:
                continue
            good, bad = getattr(r, key)
            row[key] = good if bad is not None else f">= {good:g}"  # survived the largest size tried
        row.update({f"rough_{level:g}": fraction for level, fraction in r.rough_survival.items()})
        rows.append(row)
    notes = results[0].notes if results else []
    return Table("robustness", "Robustness: largest disturbance survived", columns, rows, notes)
