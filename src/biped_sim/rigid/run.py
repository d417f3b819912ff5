"""A rigid run: the classical impulsive model of a walker config, walked step after step and measured.

``dynamics: rigid`` simulates the config's walker (``compass`` with round or point feet, Garcia's
``simplest`` walker, the ``rimless_wheel``) with the models of :mod:`biped_sim.rigid.models`: the stance
foot rolls without slip, the swing leg swings freely (mid-stance scuffing ignored) and each heel strike is
an instantaneous, perfectly plastic impact located to about 1e-12 by :func:`~biped_sim.rigid.stepping.rigid_step`.

The run starts just after a heel strike, from ``simulation.initial`` (or the rigid limit cycle), with the
stance contact point at x = 0, and steps until ``simulation.t_end``, ``simulation.max_steps`` heel strikes,
or a fall. A step that ends in a fall (a leg past ``simulation.fall_leg_angle``, the hip on the ground) or a
stall (no heel strike within ``stepping.MAX_STEP_TIME`` natural periods: the walker rocked back or stopped)
ends the run with status ``fell`` and ``stop_time`` at the end of that step: a stall counts as a fall.

What it measures, and how it relates to a compliant run:

* Samples every ``1 / output.sample_rate`` on each step's own clock: the grid restarts at each heel strike,
  whose post-impact state is therefore always a sample (time runs on across steps). A fall's last state
  is the run's last sample.
* Heel strikes: time, foot (0 is the initial stance foot, so strikes alternate 1, 0, 1, ...; for the rimless
  wheel the spoke, 1, 2, ..., N - 1, 0, ...), the pre-impact state and the post-impact state (the walker's
  state order; the post-impact one relabelled, its stance leg the one that just landed).
* The step table (:class:`~biped_sim.analysis.gait.StepTable`, one row per strike, the step it begins) holds
  the *touchdown* (pre-impact) angles and rates, with 'stance' the leg touching down and 'swing' the one about
  to leave the ground, as the compliant model records them (its impact takes time); the post-impact states
  are in ``strike_post``. Slip is zero by construction (rolling without slip).
* Energy at the samples in one frame for the whole run (the potential of every step measured from the same
  slope origin): kinetic, potential, the energy dissipated by the impacts up to the sample (each strike's
  kinetic-energy loss, booked at its time), and the balance residual E(t) - E(0) + W(t), zero up to the
  integration error.
* The hip position: x along the slope continuous across steps (the stance contact point advances by R dtheta
  as the foot rolls and by each step's length at a strike), y along the slope normal.

The reduced coordinates satisfy the rolling and joint constraints exactly, so the constraint violation is 0
by construction. Units are SI except for the simplest walker, which is nondimensional (g = l = 1, hip mass
1), and the rimless wheel, whose energies are per kg of hub mass.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from biped_sim.analysis.gait import StepAccess, StepTable
from biped_sim.config import Config, InitialState
from biped_sim.errors import ConfigError
from biped_sim.rigid import rigid_limit_cycle_initial
from biped_sim.rigid.models import RigidWalker, RimlessWheel, SimplestWalker, rigid_walker
from biped_sim.rigid.stepping import RTOL, rigid_step

NONDIMENSIONAL = "1 (g = l = 1)"
INTEGRATOR = f"DOP853 rtol {RTOL:g} (rigid)"
ANGLE_TOLERANCE = 1e-12  # the rimless wheel may start exactly on its double-support angle pi/N


@dataclass(frozen=True)
class RigidStart:
    """A validated rigid run's start: the walker and its post-impact state at t = 0 (the walker's state order)."""

    walker: RigidWalker
    state: np.ndarray


def rigid_units(walker: RigidWalker) -> dict[str, str]:
    """This walker's units for each SI unit the outputs use ('s', 'm', 'm/s', 'rad', 'rad/s', 'J', '1')."""
    units = {unit: unit for unit in ("s", "m", "m/s", "rad", "rad/s", "J", "1")}
    if isinstance(walker, SimplestWalker):
        units.update(dict.fromkeys(("s", "m", "m/s", "rad/s", "J"), NONDIMENSIONAL))
    elif isinstance(walker, RimlessWheel):
        units["J"] = "J/kg"  # the hub's mass is not a parameter: energies per kg of it
    return units


def _check_start(config: Config, walker: RigidWalker, state: np.ndarray) -> None:
    """ConfigError naming the field when the walker cannot start from ``state`` (just after a heel strike)."""
    legs = walker.legs_state(state)
    for name, value in legs.items():
        if not math.isfinite(value):
            raise ConfigError(f"simulation.initial.{name}", "must be a finite number")
    for name in walker.state_names[: walker.n_q]:
        if abs(legs[name]) >= walker.fall_leg_angle:
            raise ConfigError(
                f"simulation.initial.{name}", "beyond simulation.fall_leg_angle: the walker starts fallen"
            )
    if walker.hip_height(state) <= config.simulation.fall_hip_height * walker.leg_length:
        raise ConfigError("simulation.initial.stance_angle", "the hip starts below simulation.fall_hip_height")
    if isinstance(walker, RimlessWheel):
        if abs(legs["stance_angle"]) > walker.half_angle + ANGLE_TOLERANCE:
            raise ConfigError(
                "simulation.initial.stance_angle",
                f"the rimless wheel's stance spoke must be within pi/N = {walker.half_angle:.6g} rad of the slope "
                "normal (else another spoke starts below the ground)",
            )
    elif legs["stance_angle"] < 0.0:
        raise ConfigError(
            "simulation.initial.stance_angle",
            "the rigid model starts just after a heel strike: the stance leg must not be past the slope normal (>= 0)",
        )


def rigid_start(config: Config) -> RigidStart:
    """Build the rigid walker of ``config`` and resolve its initial state (validated; ConfigError naming the field).

    ``simulation.initial: rigid_limit_cycle`` is resolved by Newton on the rigid step map.
    """
    if config.dynamics != "rigid":
        raise ValueError("rigid_start: the config has dynamics: compliant")
    walker = rigid_walker(config)
    initial = config.simulation.initial
    legs = initial.model_dump() if isinstance(initial, InitialState) else rigid_limit_cycle_initial(config)
    state = walker.state_from_legs(legs)
    _check_start(config, walker, state)
    return RigidStart(walker, state)


def touchdown_legs(walker: RigidWalker, x_minus: np.ndarray) -> dict[str, float]:
    """A pre-impact state named as at touchdown: 'stance' the leg (spoke) landing, 'swing' the one leaving.

    The landing leg is the last coordinate of a biped (the swing leg until now) and the rimless wheel's next
    spoke, which turns at the wheel's single rate.
    """
    n = walker.n_q
    return {
        "stance_angle": walker.next_stance_angle(x_minus),
        "stance_rate": float(x_minus[2 * n - 1]),
        "swing_angle": float(x_minus[0]),
        "swing_rate": float(x_minus[n]),
    }


@dataclass
class RigidEnergy:
    """Energy terms at the samples; residual = E(t) - E(0) + W_impact(t) (J, J/kg or nondimensional)."""

    kinetic: np.ndarray
    potential: np.ndarray
    dissipated_impact: np.ndarray
    residual: np.ndarray


@dataclass
class RigidRunResult(StepAccess):
    """A rigid simulation and what it measured (the counterpart of :class:`biped_sim.simulate.RunResult`)."""

    config: Config
    walker: RigidWalker
    status: str  # 'walking' or 'fell' (a stall counts as a fall)
    stop_time: float | None  # end of the step that fell or stalled
    t_final: float  # last simulated time: t_end, the last strike (max_steps), or the fall
    time: np.ndarray  # (ns,)
    state: np.ndarray  # (ns, ny), the walker's reduced state, relabelled at each strike
    energy: RigidEnergy
    hip: np.ndarray  # (ns, 2)
    strike_time: np.ndarray  # (n,)
    strike_pre: np.ndarray  # (n, ny) just before each strike
    strike_post: np.ndarray  # (n, ny) just after, new stance leg first
    steps: StepTable
    rhs_evals: int
    accepted_steps: int
    wall_time_s: float
    summary: dict[str, Any] = field(default_factory=dict)

    @property
    def units(self) -> dict[str, str]:
        return rigid_units(self.walker)

    def unit(self, si_unit: str) -> str:
        """This run's unit for an SI unit ('s' is '1 (g = l = 1)' for the simplest walker)."""
        return self.units[si_unit]

    @property
    def post_impact_states(self) -> list[dict[str, float]]:
        """Leg angles and rates just after each strike (the Poincaré section of the rigid limit cycle)."""
        return [self.walker.legs_state(x) for x in self.strike_post]


@dataclass
class _Trace:
    """What the stepping loop collects: samples (with the step each belongs to) and strikes."""

    times: list[np.ndarray] = field(default_factory=list)
    states: list[np.ndarray] = field(default_factory=list)
    sample_step: list[np.ndarray] = field(default_factory=list)
    strike_time: list[float] = field(default_factory=list)
    strike_pre: list[np.ndarray] = field(default_factory=list)
    strike_post: list[np.ndarray] = field(default_factory=list)
    step_lengths: list[float] = field(default_factory=list)  # of the completed steps, the first from t = 0

    def add_samples(self, t: np.ndarray, x: np.ndarray, step_index: int) -> None:
        if not len(t):
            return
        self.times.append(t)
        self.states.append(x.reshape(len(t), -1))
        self.sample_step.append(np.full(len(t), step_index))


def _walk(
    config: Config, start: RigidStart, progress: Callable[[float], None] | None
) -> tuple[_Trace, str, float | None, float, int, int]:
    """Step from the start until t_end, max_steps or a fall; (trace, status, stop_time, t_final, evals, steps)."""
    walker = start.walker
    t_end, max_steps, rate = config.simulation.t_end, config.simulation.max_steps, config.output.sample_rate
    trace = _Trace()
    t0, x = 0.0, start.state
    evals = accepted = 0
    while True:
        step_index = len(trace.strike_time)
        if t0 >= t_end or (max_steps is not None and step_index >= max_steps):
            trace.add_samples(np.array([t0]), x, step_index)  # the state the run ends on, just after a strike
            return trace, "walking", None, t0, evals, accepted
        step = rigid_step(walker, x, rate)
        evals += step.rhs_evals
        accepted += step.accepted_steps
        local = step.samples_t < step.period  # the strike (or fall) state is recorded below, not interpolated
        t_samples = t0 + step.samples_t[local]
        kept = t_samples <= t_end
        trace.add_samples(t_samples[kept], step.samples_x[local][kept], step_index)
        t_step_end = t0 + step.period
        if t_step_end > t_end:
            return trace, "walking", None, t_end, evals, accepted
        if step.status != "strike" or step.x_plus is None:
            trace.add_samples(np.array([t_step_end]), step.x_minus, step_index)
            return trace, "fell", t_step_end, t_step_end, evals, accepted
        trace.strike_time.append(t_step_end)
        trace.strike_pre.append(step.x_minus)
        trace.strike_post.append(step.x_plus)
        trace.step_lengths.append(step.length)
        t0, x = t_step_end, step.x_plus
        if progress is not None:
            progress(t0)


def _strike_feet(walker: RigidWalker, n: int) -> np.ndarray:
    """Foot (spoke) of strikes 1..n, the initial stance foot being 0."""
    feet = walker.spokes if isinstance(walker, RimlessWheel) else 2
    return np.arange(1, n + 1) % feet


def _step_table(walker: RigidWalker, trace: _Trace) -> StepTable:
    """One row per strike: the step it begins (period and length nan for the last), touchdown angles and rates."""
    n = len(trace.strike_time)
    strike_time = np.array(trace.strike_time)
    period = np.full(n, np.nan)
    length = np.full(n, np.nan)
    slip = np.full(n, np.nan)
    if n > 1:
        period[:-1] = np.diff(strike_time)
        length[:-1] = trace.step_lengths[1:n]
        slip[:-1] = 0.0
    touchdown = [touchdown_legs(walker, x) for x in trace.strike_pre]
    legs = {
        key: np.array([state[key] for state in touchdown], dtype=float)
        for key in ("stance_angle", "stance_rate", "swing_angle", "swing_rate")
    }
    return StepTable(strike_time, _strike_feet(walker, n), period, length, slip, **legs)


def _energy_and_hip(
    walker: RigidWalker, start: RigidStart, trace: _Trace, times: np.ndarray, states: np.ndarray
) -> tuple[RigidEnergy, np.ndarray]:
    """Energy terms and hip position at the samples, in one slope frame for the whole run.

    Step k's models measure positions from its own origin O_k, where its contact point would be at zero stance
    angle: the contact point is at x = O_k - R theta. O_0 = R theta_0 (contact at x = 0 at the start). A step's
    length is its contact point's advance from the step's start to the next one's, so
    O_{k+1} - R theta_{k+1}+ = O_k - R theta_k+ + length_k. Potentials shift by -(weight) sin(gamma) O_k.
    """
    R, l = walker.foot_radius, walker.leg_length
    step_start = np.vstack([start.state, *trace.strike_post])[:, 0]
    origin = np.zeros(len(step_start))
    origin[0] = R * step_start[0]
    for k, length in enumerate(trace.step_lengths):
        origin[k + 1] = origin[k] + length + R * (step_start[k + 1] - step_start[k])
    weight = walker.reference_mass * walker.gravity  # hip mass 1 and g = 1 for the simplest walker
    losses = [
        walker.energy(pre)[0] - walker.energy(post)[0]
        for pre, post in zip(trace.strike_pre, trace.strike_post, strict=True)
    ]
    dissipated_by_step = np.concatenate([[0.0], np.cumsum(losses)])
    step_of_sample = np.concatenate(trace.sample_step)
    sample_origin = origin[step_of_sample]
    terms = np.array([walker.energy(x) for x in states]).reshape(len(times), 2)
    kinetic = terms[:, 0]
    potential = terms[:, 1] - weight * math.sin(walker.slope) * sample_origin
    kinetic_0, potential_0 = walker.energy(start.state)
    energy_0 = kinetic_0 + potential_0 - weight * math.sin(walker.slope) * origin[0]
    dissipated = dissipated_by_step[step_of_sample]
    residual = kinetic + potential - energy_0 + dissipated
    theta = states[:, 0]
    hip = np.column_stack([sample_origin - R * theta - (l - R) * np.sin(theta), R + (l - R) * np.cos(theta)])
    return RigidEnergy(kinetic, potential, dissipated, residual), hip


def summarize_rigid(result: RigidRunResult) -> dict[str, Any]:
    """The summary.json content: the compliant keys where they make sense, plus ``dynamics`` and ``units``.

    ``energy_dissipated``: ``impact`` is the kinetic energy lost at the strikes; ``normal`` repeats it (the
    plastic impact is the rigid limit of normal damping, so tables of rigid and compliant runs compare) and
    ``friction`` is 0 (no slip): impact = normal + friction. ``constraint_violation_max`` is exactly 0: the
    reduced coordinates satisfy the constraints by construction. Solver counters are scipy's DOP853's.
    """
    from biped_sim.io.provenance import package_version

    config, walker = result.config, result.walker
    impact = float(result.energy.dissipated_impact[-1]) if len(result.time) else 0.0
    residual_max = float(np.max(np.abs(result.energy.residual))) if len(result.time) else 0.0
    return {
        "status": result.status,
        "stop_time": result.stop_time,
        "t_end": result.t_final,
        **result.step_summary(),
        "energy_dissipated": {"impact": impact, "normal": impact, "friction": 0.0},
        "energy_residual_max": residual_max,
        "energy_residual_max_relative": residual_max / (walker.reference_mass * walker.gravity * walker.leg_length),
        "constraint_violation_max": {"position": 0.0, "velocity": 0.0},
        "rhs_evals": result.rhs_evals,
        "accepted_steps": result.accepted_steps,
        "wall_time_s": result.wall_time_s,
        "integrator": INTEGRATOR,
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
    trace, status, stop_time, t_final, evals, accepted = _walk(config, start, progress)
    wall = time.perf_counter() - clock
    ny = len(start.state)
    times = np.concatenate(trace.times)
    states = np.vstack(trace.states)
    energy, hip = _energy_and_hip(walker, start, trace, times, states)
    result = RigidRunResult(
        config=config,
        walker=walker,
        status=status,
        stop_time=stop_time,
        t_final=t_final,
        time=times,
        state=states,
        energy=energy,
        hip=hip,
        strike_time=np.array(trace.strike_time),
        strike_pre=np.array(trace.strike_pre).reshape(-1, ny),
        strike_post=np.array(trace.strike_post).reshape(-1, ny),
        steps=_step_table(walker, trace),
        rhs_evals=evals,
        accepted_steps=accepted,
        wall_time_s=wall,
    )
    result.summary = summarize_rigid(result)
    return result
