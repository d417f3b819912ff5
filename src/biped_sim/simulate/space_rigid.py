"""A rigid run of a walker in space (``Config.in_space``, ``dynamics: rigid``): its step map walked step
after step and measured, as a planar rigid run (:mod:`biped_sim.simulate.rigid`) is.

The run starts just after a strike, the left leg standing with its contact point at the origin, from
``simulation.initial``: the rigid gait's post-strike state (the keys of
:data:`~biped_sim.config.space_description.SPACE_STATE_KEYS`) or ``rigid_limit_cycle``, the walker's period-1 gait
found without a guess (:func:`~biped_sim.rigid.space_cycle.space_limit_cycle`). It steps until ``simulation.t_end``,
``simulation.max_steps`` strikes, a fall (status ``fell``: the hip near the ground or the bank past
``FALL_BANK``, or a stall: no strike within ``MAX_STEP_TIME`` natural periods) or the wall-time budget.
``simulation.pushes`` ([px, py, pz] on the hinge's midpoint, the spatial slope frame: x downhill, y the normal,
z right) act at their times (:mod:`biped_sim.rigid.space_walk`).

What it writes: the samples' state in the run's slope frame (the rigid model's: x downhill, y left, z the normal;
the stance leg's heading, bank and pitch, the hinge angle, the stance leg's angular velocity, the hinge rate, the
stance contact point; the stance leg alternates, left first: the step table's ``foot`` says which landed), the hip
(the hinge's midpoint, spatial frame), the energy terms, the strikes' states, and the step table with the spatial
runs' lateral columns (:mod:`biped_sim.measure.space_rigid`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from biped_sim.config import Config
from biped_sim.config.space_description import SPACE_TORSO_KEYS
from biped_sim.errors import ConfigError
from biped_sim.integrate.driver import TIMEOUT_REASON
from biped_sim.io.atomic import json_safe
from biped_sim.io.run_files import Channel, TrajectoryFile
from biped_sim.measure.rigid import RigidEnergy
from biped_sim.measure.space_rigid import SpaceSamples, SpaceTrace, leg_attitudes, space_samples, space_step_table
from biped_sim.measure.steps import StepTable
from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.space_cycle import space_limit_cycle, space_walker_model
from biped_sim.rigid.space_integration import FALL_BANK, MAX_ATTEMPTS, space_scratch
from biped_sim.rigid.space_kernels import space_params
from biped_sim.rigid.space_model import KNEE_NAMES, N_STATE, TORSO_NAMES, SpaceModel, pose
from biped_sim.rigid.space_step import SINGULAR, SINGULAR_REASON, SpaceStep, step_time_limit
from biped_sim.rigid.space_walk import Frame, walk_step
from biped_sim.rigid.step import MAX_STEP_TIME, RTOL
from biped_sim.simulate.budget import check_run_size
from biped_sim.simulate.result import RunResult, ordered_pushes, wall_deadline
from biped_sim.simulate.rigid import RIGID_ENERGY_TERMS, WalkEnd, summarize_rigid
from biped_sim.walkers.space_walker import BODY_NAMES, check_initial

INTEGRATOR = f"DOP853 rtol {RTOL:g} (rigid, in space)"
STATE_UNITS = "rad, rad/s, m (see state_names)"


@dataclass(frozen=True)
class SpaceStart:
    """A rigid run's start in space: the model and its post-strike state (the contact point at the origin)."""

    model: SpaceModel
    state: np.ndarray


def space_initial(config: Config) -> object:
    """``simulation.initial`` of a walker in space, ``rigid_limit_cycle`` resolved to the gait's post-strike state
    (ConfigError naming simulation.initial when Newton does not converge)."""
    initial = config.simulation.initial
    if initial != "rigid_limit_cycle":
        return initial
    cycle = space_limit_cycle(config)
    if not cycle.converged:
        raise ConfigError(
            "simulation.initial", f"rigid_limit_cycle: Newton did not converge (residual {cycle.residual:.1e})"
        )
    return cycle.fixed_point


def check_space_run_size(config: Config) -> None:
    """The run's samples within the memory budget (ConfigError naming the field otherwise): the state, the state in
    the run's frame, the hip and the energy terms per sample. Before its start is sought (the limit cycle's search
    compiles the step map on a cold cache), so that a run too large fails at once."""
    check_run_size(config, 2 * (N_STATE + len(KNEE_NAMES) + len(TORSO_NAMES)) + 8)


def space_start(config: Config) -> SpaceStart:
    """The model of ``config`` and its start (ConfigError naming simulation.initial when there is none)."""
    model = space_walker_model(config)
    keys = check_initial(space_initial(config), SPACE_TORSO_KEYS if model.torso else ())
    state = np.zeros(model.n_state)  # a swing knee starts straight and at rest, a torso's keys left out: 0
    for name, value in keys.items():
        state[model.state_names.index(name)] = value
    return SpaceStart(model, state)


@dataclass(repr=False)  # RunResult.__repr__: one line
class SpaceRunResult(RunResult):
    """A rigid run of a walker in space and what it measured (module docstring)."""

    config: Config
    start: SpaceStart
    status: str  # 'walking', 'fell', 'diverged' (singular equations) or 'timeout'
    status_reason: str | None
    stop_time: float | None
    t_final: float
    time: np.ndarray
    trace: SpaceTrace
    rhs_evals: int
    accepted_steps: int
    wall_time_s: float

    @cached_property
    def samples(self) -> SpaceSamples:
        """The samples' state, hip and energy terms in the run's frame (computed when first asked)."""
        return space_samples(self.start.model, self.trace, self.start.state, self.time, np.vstack(self.trace.states))

    @cached_property
    def steps(self) -> StepTable:  # type: ignore[override]
        """The step table (touchdown angles, the lateral columns)."""
        lateral = -self.samples.hip[:, 2]  # the rigid frame's y: left
        return space_step_table(self.start.model, self.trace, lateral)

    @property
    def state(self) -> np.ndarray:
        return self.samples.state

    @property
    def energy(self) -> RigidEnergy:
        return self.samples.energy

    @property
    def hip(self) -> np.ndarray:
        return self.samples.hip

    @property
    def pushes(self) -> list[tuple[float, float, float]]:
        return self.trace.pushes

    @property
    def energy_scale(self) -> float:
        """m g l: the whole mass, gravity and the leg length."""
        model = self.start.model
        return sum(part.mass for part in model.parts) * model.gravity * model.leg_length

    integrator = INTEGRATOR

    @cached_property
    def summary(self) -> dict[str, Any]:  # type: ignore[override]
        return json_safe(summarize_rigid(self))  # type: ignore[arg-type]

    def integrity_text(self) -> str:
        return f"impact losses {self.summary['energy_dissipated']['impact']:.4f} J"

    def energy_dissipated(self) -> dict[str, float]:
        """The strikes' kinetic energy losses; ``normal`` repeats it, ``friction`` is 0 (rolling without slip)."""
        impact = float(self.energy.dissipated_impact[-1]) if len(self.time) else 0.0
        return {"impact": impact, "normal": impact, "friction": 0.0}

    def peak_normal_force(self) -> float | None:
        """None: the rigid model's contact forces are impulses."""
        return None

    def _strike_states(self, states: list[np.ndarray], frame_offset: int) -> np.ndarray:
        """Strike states in the run's frame (each in its step's frame: the one before the strike for the
        pre-impact states, offset 0; after it for the post-impact ones, offset 1)."""
        frames = self.trace.frames
        n_state = self.start.model.n_state
        return np.array([frames[k + frame_offset].world(x) for k, x in enumerate(states)]).reshape(-1, n_state)

    def trajectory(self) -> TrajectoryFile:
        channels = [Channel(f"energy/{name}", getattr(self.energy, name), "J") for name in RIGID_ENERGY_TERMS]
        channels.append(Channel("hip", self.hip, "m"))
        stance = np.concatenate(self.trace.sample_step) % 2  # the left leg stands on even steps
        for name, values in leg_attitudes(self.state, stance).items():
            channels.append(Channel(f"attitude/{name}", values, "rad/s" if name == "pitch_rate" else "rad"))
        channels += [
            Channel(f"steps/{name}", getattr(self.steps, name), units, False) for name, units in self.steps.columns
        ]
        channels.append(Channel("strikes/time", np.array(self.trace.strike_time), "s", False))
        channels.append(
            Channel("strikes/pre_impact", self._strike_states(self.trace.strike_pre, 0), STATE_UNITS, False)
        )
        channels.append(
            Channel("strikes/post_impact", self._strike_states(self.trace.strike_post, 1), STATE_UNITS, False)
        )
        return TrajectoryFile(
            self.time, "s", self.state, list(self.start.model.state_names), STATE_UNITS, channels,
            root_attrs={"dynamics": "rigid"},
            group_attrs={"attitude": {"bodies": BODY_NAMES}},
        )  # fmt: skip


def fall_reason(model: SpaceModel, step: SpaceStep) -> str:
    """Which criterion ended a step that did not strike: the stall, or the fall limit its end state is nearest."""
    if step.status == "stalled":
        return f"no heel strike within {MAX_STEP_TIME:g} sqrt(l / g): the walker rocked back or stopped"
    if step.status == "stiff":
        return (
            f"{MAX_ATTEMPTS} integration steps tried in one phase: the equations of motion nearly singular, a motion "
            "almost no mass resists (a leg with little inertia about its axis?)"
        )
    if step.status == "tripped":
        return "the swing foot met the ground not ahead of the stance foot: the walker rocked back"
    hip = pose(model, step.x_minus).origin[2] / model.leg_length - FALL_HIP_FRACTION
    if hip < FALL_BANK - abs(step.x_minus[1]):
        return f"the hip within {FALL_HIP_FRACTION:g} leg lengths of the ground"
    return f"the bank past {FALL_BANK:g} rad: the walker toppled sideways"


def walk(config: Config, start: SpaceStart, progress: Callable[[float], None] | None) -> tuple[SpaceTrace, WalkEnd]:
    """Step from the start until t_end, max_steps, a fall or the wall-time budget."""
    model, params = start.model, space_params(start.model)
    t_end, max_steps, rate = config.simulation.t_end, config.simulation.max_steps, config.output.sample_rate
    deadline, pushes = wall_deadline(config), ordered_pushes(config)
    scratch = space_scratch(math.ceil(step_time_limit(model) * rate) + 1, model.n_state)
    trace = SpaceTrace(frames=[Frame(np.zeros(3), 1.0)])
    t0, x, evals, accepted = 0.0, start.state, 0, 0
    while True:
        index, frame = len(trace.strike_time), trace.frames[-1]
        finished = t0 >= t_end or (max_steps is not None and index >= max_steps)
        if finished or time.monotonic() > deadline:
            trace.add_samples(np.array([t0]), x, index)  # the state the run ends on, just after a strike
            status = "walking" if finished else "timeout"
            return trace, WalkEnd(
                status, None if finished else TIMEOUT_REASON, None if finished else t0, t0, evals, accepted
            )
        pending = [(at - t0, frame.impulse(impulse)) for at, impulse in pushes[len(trace.pushes) :]]
        try:
            walked = walk_step(model, params, scratch, x, rate, pending)
        except SINGULAR:
            trace.add_samples(np.array([t0]), x, index)  # the step's start: the last state integrated
            return trace, WalkEnd("diverged", SINGULAR_REASON, t0, t0, evals, accepted)
        trace.pushes += [(t0 + at, work, normal) for at, work, normal in walked.pushes]
        trace.stop_losses += [(t0 + at, loss) for at, loss in walked.knee_strikes if t0 + at <= t_end]
        evals, accepted = evals + walked.rhs_evals, accepted + walked.accepted_steps
        step, kept = walked.step, t0 + walked.samples_t <= t_end
        trace.add_samples(t0 + walked.samples_t[kept], walked.samples_x[kept], index)
        if t0 + step.period > t_end:
            return trace, WalkEnd("walking", None, None, t_end, evals, accepted)
        if step.x_plus is None:
            trace.add_samples(np.array([t0 + step.period]), step.x_minus, index)
            t_fell = t0 + step.period
            status = "diverged" if step.status == "stiff" else "fell"
            return trace, WalkEnd(status, fall_reason(model, step), t_fell, t_fell, evals, accepted)
        t0 = t0 + step.period
        trace.strike_time.append(t0)
        trace.strike_pre.append(step.x_minus)
        trace.frames.append(frame.after(step.x_plus))
        x = np.array(step.x_plus)
        x[8:10] = 0.0  # in the next step's frame
        trace.strike_post.append(x)
        trace.step_lengths.append(step.length)
        if progress is not None:
            progress(t0)


def simulate_space_rigid(
    config: Config, start: SpaceStart | None = None, progress: Callable[[float], None] | None = None
) -> SpaceRunResult:
    """Simulate ``config`` (a walker in space, rigid dynamics) and measure the gait; writes nothing."""
    start = start or space_start(config)
    clock = time.perf_counter()
    trace, end = walk(config, start, progress)
    return SpaceRunResult(
        config=config,
        start=start,
        status=end.status,
        status_reason=end.reason,
        stop_time=end.stop_time,
        t_final=end.t_final,
        time=np.concatenate(trace.times),
        trace=trace,
        rhs_evals=end.rhs_evals,
        accepted_steps=end.accepted_steps,
        wall_time_s=time.perf_counter() - clock,
    )
