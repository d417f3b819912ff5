"""A rigid run: the classical impulsive model of a walker config, walked step after step and measured.

``dynamics: rigid`` simulates the config's walker (``compass`` with round or point feet, Garcia's
``simplest`` walker, the ``rimless_wheel``, a described walker) with the models of :mod:`biped_sim.rigid.tree`:
the stance foot rolls without slip, the swing leg swings freely (mid-stance scuffing ignored) and each heel strike
is an instantaneous, perfectly plastic impact located to about 1e-12 by the compiled step map
(:func:`~biped_sim.rigid.compiled.rigid_step`).

The run starts just after a heel strike, from ``simulation.initial`` (or the rigid limit cycle), with the
stance contact point at x = 0, and steps until ``simulation.t_end``, ``simulation.max_steps`` heel strikes,
or a fall. A step that ends in a fall (a leg past ``simulation.fall_leg_angle``, the hip on the ground) or a
stall (no heel strike within ``MAX_STEP_TIME`` natural periods: the walker rocked back or stopped)
ends the run with status ``fell`` and ``stop_time`` at the end of that step: a stall counts as a fall.

What it measures, and how it relates to a compliant run:

* Samples every ``1 / output.sample_rate`` on each step's own clock: the grid restarts at each heel strike,
  whose post-impact state is therefore always a sample (time runs on across steps). A fall's last state
  is the run's last sample.
* Heel strikes: time, foot (0 is the initial stance foot, so strikes alternate 1, 0, 1, ...; for the rimless
  wheel the spoke, 1, 2, ..., N - 1, 0, ...), the pre-impact state and the post-impact state (the walker's
  state order; the post-impact one relabelled, its stance leg the one that just landed).
* The step table (:class:`~biped_sim.measure.steps.StepTable`, one row per strike, the step it begins) holds
  the *touchdown* (pre-impact) angles and rates, with 'stance' the leg touching down and 'swing' the one about
  to leave the ground, as the compliant model records them (its impact takes time); the post-impact states
  are in ``strike_post``. Slip is zero by construction (rolling without slip).
* Energy at the samples in one frame for the whole run (the potential of every step measured from the same
  slope origin): kinetic, potential, the energy dissipated by the impacts up to the sample (each strike's
  kinetic-energy loss, booked at its time), and the balance residual E(t) - E(0) + W(t), zero up to the
  integration error.
* The hip position: x along the slope continuous across steps (the stance contact point advances by R dtheta
  as the foot rolls and by each step's length at a strike), y along the slope normal.

On a ground profile (``ground.profile`` other than flat) each heel strike is sought against the profile's
height at the swing foot (:mod:`biped_sim.rigid.ground`: the stance foot keeps a flat local ground at the
level of its contact point); the potential energy and the hip include the stance level, so a step down of h
adds m_total g h cos(gamma) to the energy budget (h along the slope normal). A riser hit is a fall.

The reduced coordinates satisfy the rolling and joint constraints exactly, so the constraint violation is 0
by construction. Units are SI except for the simplest walker, which is nondimensional (g = l = 1, hip mass
1), and the rimless wheel, whose energies are per kg of hub mass.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np

from biped_sim.config import Config
from biped_sim.contact.response import LEG_TOO_FAR
from biped_sim.integrate.driver import TIMEOUT_REASON
from biped_sim.integrate.recorder import FALL_REASONS, body_fall_reason
from biped_sim.io.atomic import json_safe
from biped_sim.io.provenance import package_version
from biped_sim.io.run_files import Channel, TrajectoryFile
from biped_sim.measure.rigid import RigidEnergy, RigidTrace, rigid_energy_and_hip, rigid_step_table
from biped_sim.measure.steps import StepTable
from biped_sim.rigid.compiled import compile_walker, rigid_step
from biped_sim.rigid.ground import Footing, ProfileStrike, rigid_ground
from biped_sim.rigid.kernels import FALL_HIP_FRACTION
from biped_sim.rigid.start import INTEGRATOR, NONDIMENSIONAL, RigidStart, rigid_start, rigid_units
from biped_sim.rigid.step import MAX_STEP_TIME, RigidStep
from biped_sim.rigid.tree import RigidWalker
from biped_sim.simulate.result import RunResult, ordered_pushes, push_summary, wall_deadline

RIGID_ENERGY_TERMS = ("kinetic", "potential", "dissipated_impact", "dissipated_elements", "push_work", "residual")


@dataclass(repr=False)  # RunResult.__repr__: one line, not every array
class RigidRunResult(RunResult):
    """A rigid simulation and what it measured."""

    config: Config
    walker: RigidWalker
    status: str  # 'walking', 'fell' (a stall counts as a fall) or 'timeout' (simulation.max_wall_time)
    status_reason: str | None  # why it fell (the criterion) or timed out
    stop_time: float | None  # end of the step that fell or stalled
    t_final: float  # last simulated time: t_end, the last strike (max_steps), or the fall
    time: np.ndarray  # (ns,)
    state: np.ndarray  # (ns, ny), the walker's reduced state, relabelled at each strike
    strike_time: np.ndarray  # (n,)
    strike_pre: np.ndarray  # (n, ny) just before each strike
    strike_post: np.ndarray  # (n, ny) just after, new stance leg first
    pushes: list[tuple[float, float, float]]  # applied: (time, work, ground normal impulse)
    steps: StepTable
    rhs_evals: int
    accepted_steps: int
    wall_time_s: float
    start: RigidStart  # with the trace, what the energy terms and the hip are computed from when asked
    trace: RigidTrace

    @cached_property
    def _energy_and_hip(self) -> tuple[RigidEnergy, np.ndarray]:
        return rigid_energy_and_hip(self.walker, self.start, self.trace, self.time, self.state)

    @property
    def energy(self) -> RigidEnergy:
        """The energy terms at the samples (computed the first time something asks)."""
        return self._energy_and_hip[0]

    @property
    def hip(self) -> np.ndarray:
        """(ns, 2) the hip's position in the run's slope frame (computed the first time something asks)."""
        return self._energy_and_hip[1]

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The summary.json content (plain JSON data), computed when asked."""
        return json_safe(summarize_rigid(self))

    @property
    def units(self) -> dict[str, str]:
        return rigid_units(self.walker)

    @property
    def energy_scale(self) -> float:
        """m g l: the reference mass, gravity and the leg length (the energy residual's scale)."""
        return self.walker.reference_mass * self.walker.gravity * self.walker.leg_length

    integrator = INTEGRATOR

    def unit(self, si_unit: str) -> str:
        """This run's unit for an SI unit ('s' is '1 (g = l = 1)' for the simplest walker)."""
        return self.units[si_unit]

    def integrity_text(self) -> str:
        return f"impact losses {self.summary['energy_dissipated']['impact']:.4f}" + (
            "" if self.unit("J") == NONDIMENSIONAL else f" {self.unit('J')}"
        )

    def trajectory(self) -> TrajectoryFile:
        angles, rates = self.unit("rad"), self.unit("rad/s")
        state_units = f"{angles}, {rates} (see state_names)"
        energy_units = self.unit("J")
        channels = [Channel(f"energy/{name}", getattr(self.energy, name), energy_units) for name in RIGID_ENERGY_TERMS]
        channels.append(Channel("hip", self.hip, self.unit("m")))
        channels += [
            Channel(f"steps/{name}", getattr(self.steps, name), self.unit(units), False)
            for name, units in self.steps.columns
        ]
        channels.append(Channel("strikes/time", self.strike_time, self.unit("s"), False))
        channels.append(Channel("strikes/pre_impact", self.strike_pre, state_units, False))
        channels.append(Channel("strikes/post_impact", self.strike_post, state_units, False))
        return TrajectoryFile(
            self.time,
            self.unit("s"),
            self.state,
            self.walker.state_names,
            state_units,
            channels,
            root_attrs={"dynamics": "rigid"},
        )

    def energy_dissipated(self) -> dict[str, float]:
        """The impacts' kinetic energy losses over the run; ``normal`` repeats it, ``friction`` is 0 (no slip)."""
        impact = float(self.energy.dissipated_impact[-1]) if len(self.time) else 0.0
        return {"impact": impact, "normal": impact, "friction": 0.0}

    def peak_normal_force(self) -> float | None:
        """None: the rigid model's contact forces are impulses."""
        return None

    @property
    def post_impact_states(self) -> list[dict[str, float]]:
        """Leg angles and rates just after each strike (the Poincaré section of the rigid limit cycle)."""
        return [self.walker.legs_state(x) for x in self.strike_post]


class WalkEnd(NamedTuple):
    """How a rigid walk ended."""

    status: str  # 'walking', 'fell' or 'timeout'
    reason: str | None  # why it fell or timed out
    stop_time: float | None
    t_final: float
    rhs_evals: int
    accepted_steps: int


def fall_reason(walker: RigidWalker, step: RigidStep) -> str:
    """Which criterion ended a step that did not strike: the stall, the trip, or the fall limit its end state is
    nearest to (the fall events stop the flow on one of them)."""
    if step.status == "stalled":
        return f"no heel strike within {MAX_STEP_TIME:g} sqrt(l / g): the walker rocked back or stopped"
    if step.status == "tripped":
        return "the swing foot met the ground profile short of a heel strike (a riser, or below it)"
    x = step.x_minus
    legs = [k for k in range(walker.n_q) if k not in walker.off_legs]
    margins = {FALL_REASONS[LEG_TOO_FAR]: walker.fall_leg_angle - float(np.max(np.abs(x[legs])))}
    for k in walker.off_legs:  # a torso, against its own fall angle
        margins[body_fall_reason(walker.state_names[k].removesuffix("_angle"))] = walker.fall_angles[k] - abs(x[k])
    margins[f"the hip within {FALL_HIP_FRACTION:g} leg lengths of the ground"] = (
        walker.hip_height(x) / walker.leg_length - FALL_HIP_FRACTION
    )
    return min(margins, key=lambda reason: margins[reason])


def walk(config: Config, start: RigidStart, progress: Callable[[float], None] | None) -> tuple[RigidTrace, WalkEnd]:
    """Step from the start until t_end, max_steps, a fall or the wall-time budget."""
    walker = start.walker
    cw = compile_walker(walker)  # its buffers kept from step to step
    t_end, max_steps, rate = config.simulation.t_end, config.simulation.max_steps, config.output.sample_rate
    deadline = wall_deadline(config)
    pushes = ordered_pushes(config)
    trace = RigidTrace()
    t0, x = 0.0, start.state
    ground = rigid_ground(config)
    profile = (
        None
        if ground is None
        else ProfileStrike(walker, ground, Footing(-walker.contact_point(x[: walker.n_q])[0], 0.0))
    )
    evals = accepted = 0
    work = 0.0  # the joint elements' dissipated work since the run's start, at the step's start
    while True:
        step_index = len(trace.strike_time)
        finished = t0 >= t_end or (max_steps is not None and step_index >= max_steps)
        if finished or time.monotonic() > deadline:
            trace.add_samples(np.array([t0]), x, step_index, work)  # the state the run ends on, after a strike
            if finished:
                return trace, WalkEnd("walking", None, None, t0, evals, accepted)
            return trace, WalkEnd("timeout", TIMEOUT_REASON, t0, t0, evals, accepted)
        pending = [(at - t0, impulse) for at, impulse in pushes[len(trace.pushes) :]]
        step = rigid_step(walker, x, rate, pending, profile, cw=cw)
        trace.pushes += [(t0 + at, work, ground) for at, work, ground in step.pushes]
        trace.stop_losses += [(t0 + at, loss) for at, loss in step.stop_strikes]
        evals += step.rhs_evals
        accepted += step.accepted_steps
        local = step.samples_t < step.period  # the strike (or fall) state is recorded below, not interpolated
        t_samples = t0 + step.samples_t[local]
        kept = t_samples <= t_end
        trace.add_samples(
            t_samples[kept], step.samples_x[local][kept], step_index, work + step.samples_work[local][kept]
        )
        t_step_end = t0 + step.period
        if t_step_end > t_end:
            return trace, WalkEnd("walking", None, None, t_end, evals, accepted)
        if step.status != "strike" or step.x_plus is None:
            trace.add_samples(np.array([t_step_end]), step.x_minus, step_index, work + step.element_work)
            return trace, WalkEnd("fell", fall_reason(walker, step), t_step_end, t_step_end, evals, accepted)
        trace.strike_time.append(t_step_end)
        trace.strike_pre.append(step.x_minus)
        trace.strike_post.append(step.x_plus)
        trace.step_lengths.append(step.length)
        if profile is not None:
            profile = profile.after(step.x_minus, step.x_plus)
            trace.strike_levels.append(profile.footing.level)
        t0, x, work = t_step_end, step.x_plus, work + step.element_work
        if progress is not None:
            progress(t0)


def summarize_rigid(result: RigidRunResult) -> dict[str, Any]:
    """The summary.json content: the compliant keys where they make sense, plus ``dynamics`` and ``units``.

    ``energy_dissipated``: ``impact`` is the kinetic energy lost at the strikes; ``normal`` repeats it (the
    plastic impact is the rigid limit of normal damping, so tables of rigid and compliant runs compare) and
    ``friction`` is 0 (no slip): impact = normal + friction. ``constraint_violation_max`` is exactly 0: the
    reduced coordinates satisfy the constraints by construction. Solver counters are the integrator's. A rigid run
    of a walker in space (:class:`~biped_sim.simulate.space_rigid.SpaceRunResult`) has the same attributes.
    """
    config = result.config
    residual_max = float(np.max(np.abs(result.energy.residual))) if len(result.time) else 0.0
    return {
        "status": result.status,
        "status_reason": result.status_reason,
        "stop_time": result.stop_time,
        "t_end": result.t_final,
        **result.step_summary(),
        "energy_dissipated": result.energy_dissipated(),
        **push_summary(config, [{"work": work, "ground_normal_impulse": ground} for _, work, ground in result.pushes]),
        "energy_residual_max": residual_max,
        "energy_residual_max_relative": residual_max / result.energy_scale,
        "constraint_violation_max": {"position": 0.0, "velocity": 0.0},
        "max_penetration": None,
        "peak_normal_force": result.peak_normal_force(),
        "rhs_evals": result.rhs_evals,
        "accepted_steps": result.accepted_steps,
        "wall_time_s": result.wall_time_s,
        "integrator": result.integrator,
        "config_hash": config.hash(),
        "version": package_version(),
        "dynamics": "rigid",
        "units": {"time": result.unit("s"), "length": result.unit("m"), "energy": result.unit("J")},
    }


def simulate_rigid(
    config: Config, start: RigidStart | None = None, progress: Callable[[float], None] | None = None
) -> RigidRunResult:
    """Simulate ``config`` with the rigid model and measure the gait; writes nothing.

    ``start`` is :func:`rigid_start`'s result when the caller has validated the config already;
    ``progress(t)`` is called after each heel strike.
    """
    start = start or rigid_start(config)
    walker = start.walker
    clock = time.perf_counter()
    trace, end = walk(config, start, progress)
    wall = time.perf_counter() - clock
    ny = len(start.state)
    times = np.concatenate(trace.times)
    states = np.vstack(trace.states)
    return RigidRunResult(
        config=config,
        walker=walker,
        status=end.status,
        status_reason=end.reason,
        stop_time=end.stop_time,
        t_final=end.t_final,
        time=times,
        state=states,
        strike_time=np.array(trace.strike_time),
        strike_pre=np.array(trace.strike_pre).reshape(-1, ny),
        strike_post=np.array(trace.strike_post).reshape(-1, ny),
        pushes=trace.pushes,
        steps=rigid_step_table(walker, trace),
        rhs_evals=end.rhs_evals,
        accepted_steps=end.accepted_steps,
        wall_time_s=wall,
        start=start,
        trace=trace,
    )
