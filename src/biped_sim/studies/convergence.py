"""The compliant gait approaching the rigid one as the contact stiffens, dissipates and stops slipping.

The second strong check of the compliant model (MODEL.md 8): with stiff contact, e -> 0 and no slip it
must converge to the rigid (impulsive-impact) model's gait.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from biped_sim.config import STATE_KEYS, Config, derive
from biped_sim.config.walker_registry import capabilities, require_study
from biped_sim.errors import ArgumentError
from biped_sim.multibody.dispatch import measures
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import LimitCycle, StepFailedError, rigid_limit_cycle
from biped_sim.rigid.strike_check import StrikeCheck, strike_check
from biped_sim.simulate import CompliantRunResult, simulate
from biped_sim.walkers.model import contact_stiffness

CONVERGE_LEVELS = 5
LEVELS = range(2, 8)  # contact settings a study may take: the stiffest (x10^6) is near the limit of dop853 steps
CONVERGE_STEPS = 20
MU_KINETIC, MU_STATIC = 1.0, 1.2  # the study's LuGre friction coefficients
STOP_STIFFENING = 100.0  # a joint stop's stiffness factor per level: the square of the feet's (see stops_level)
BRISTLE_DAMPING = 20.0  # LuGre sigma1 [s/m per N of normal load], the same at every level (see converge)


@dataclass
class ConvergenceRow:
    """The compliant gait at one contact setting against the rigid gait."""

    stiffness: float
    restitution: float
    bristle_stiffness: float
    status: str
    touchdown_difference: float  # max |compliant - rigid| over the four touchdown variables
    period_difference: float  # compliant - rigid step period [s]
    settled: float  # change of the touchdown state over the last compliant step
    slip: float  # stance-foot slip over the last step [m]


def rigid_strike_check(config: Config, rigid: LimitCycle, mu_kinetic: float | None = None) -> StrikeCheck:
    """The rigid gait's strike against the conditions under which a stiff compliant strike tends to it
    (``mu_kinetic`` None: the study's ``MU_KINETIC``).

    ``StrikeCheck.violations(mu_static)`` lists why the compliant gait of :func:`converge` with that friction
    cannot converge to the rigid one (empty: it can); :func:`strike_violations` both at once.
    """
    mu_kinetic = MU_KINETIC if mu_kinetic is None else mu_kinetic
    walker = rigid_walker(config)
    step = rigid_step(walker, walker.from_section(rigid.section_point))
    if step.status != "strike":
        raise StepFailedError(f"rigid_strike_check: the rigid cycle's step {step.status}")
    return strike_check(walker, step.x_minus, mu_kinetic)


def strike_violations(
    config: Config, rigid: LimitCycle, mu_kinetic: float | None = None, mu_static: float | None = None
) -> tuple[StrikeCheck | None, list[str]]:
    """:func:`rigid_strike_check` and its violations at the study's friction (None: ``MU_KINETIC``, ``MU_STATIC``);
    (None, []) for a walker other than the compass, which the check does not cover."""
    if not capabilities(config.walker.kind).strike_check:
        return None, []
    check = rigid_strike_check(config, rigid, mu_kinetic)
    return check, check.violations(MU_STATIC if mu_static is None else mu_static)


def check_converge(config: Config, levels: int, mu_kinetic: float, mu_static: float) -> None:
    """What :func:`converge` refuses: a walker other than the compass (ConfigError), ``levels`` outside
    ``LEVELS``, negative friction coefficients or ``mu_static`` below ``mu_kinetic`` (ArgumentError)."""
    require_study(config.walker.kind, "converge", "converge compares the compliant and rigid compass walker")
    if levels not in LEVELS:
        raise ArgumentError("levels", f"must be from {LEVELS.start} to {LEVELS.stop - 1} (stiffness x10 each)")
    for name, value in (("mu_kinetic", mu_kinetic), ("mu_static", mu_static)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ArgumentError(name, f"must be a finite number >= 0, got {value}")
    if mu_static < mu_kinetic:
        raise ArgumentError("mu_static", f"must be >= the kinetic coefficient ({mu_kinetic})")


def stops_level(config: Config, k: int) -> dict[str, Any]:
    """A described walker's joint stops at level k of :func:`converge`: stiffness 100^k times its own (the square
    of the feet's factor), restitution its own over sqrt(10)^k (as the feet's contact); nothing for a walker
    without a description.

    The rigid heel strike holds both knees rigid through its impulse: the limit of a knee stop (latch) much
    stiffer than the foot contact, whose time scale (I / K_stop)^(2/5) against the foot's (m / K_foot)^(2/5)
    (both laws of exponent 3/2) then falls as 10^(-2k/5). Stiffened as the feet are, the ratio would stay fixed
    and the impulse would flex the knees by the same amount at every level."""
    if config.walker.description is None:
        return {}
    description = config.walker.description.model_dump(mode="json")
    for joint in description["joints"]:
        for stop in joint["stops"]:
            stop["stiffness"] *= STOP_STIFFENING**k
            stop["restitution"] /= math.sqrt(10.0) ** k
    return {"walker.description": description}


def touchdown_states(result: CompliantRunResult) -> list[dict[str, float]]:
    """Each heel strike's state by the walker's initial-state keys; 'stance' is the leg that just touched down
    (the compass: :attr:`heel_strike_states`; a described walker: every body of both legs, hip down, then the
    bodies off the legs)."""
    described = result.config.walker.description
    if described is None:
        return result.heel_strike_states
    model, run = result.model, result.run
    pitch = measures(model.system).pitch
    legs = [[model.body_names.index(body) for body in leg] for leg in described.legs]
    off_legs = [model.body_names.index(body) for body in described.off_leg_bodies()]
    states = []
    for k in range(len(run.strike_t)):
        struck = int(model.system.foot_body[run.strike_foot[k]])
        stance = next(i for i, leg in enumerate(legs) if struck in leg)
        bodies = [b for leg in (legs[stance], legs[1 - stance]) for b in leg] + off_legs
        values = [v for b in bodies for v in pitch(run.strike_y[k], model.system, b)]
        states.append(dict(zip(described.state_keys(), values, strict=True)))
    return states


def converge(
    config: Config,
    levels: int = CONVERGE_LEVELS,
    steps: int = CONVERGE_STEPS,
    mu_kinetic: float | None = None,
    mu_static: float | None = None,
) -> tuple[LimitCycle, list[ConvergenceRow]]:
    """The compliant gait approaching the rigid one as the contact stiffens, dissipates and stops slipping.

    Level k (0-based): contact stiffness 10^k times the config's (Hertz or explicit), restitution
    0.3 / sqrt(10)^k, and LuGre friction (mu_k, mu_s) whose bristle stiffness sigma0 = 1e4 * 10^k per metre:
    LuGre sticks elastically instead of creeping as the regularised laws do, so the slip vanishes with
    sigma0. Each compliant run starts on the rigid limit cycle and walks ``steps`` steps; its last touchdown
    state and step period are compared with the rigid touchdown (the pre-impact state, relabelled) and period.

    The bristle damping sigma1 stays ``BRISTLE_DAMPING`` at every level: LuGre's force F_N (sigma0 z + sigma1
    zdot) exceeds Coulomb's bound while the bristles deflect (zdot ~ v: the ratio reaches sigma1 |v|), and a
    foot loaded through a strike of duration tau ~ 1/sqrt(stiffness) takes a friction impulse ~ F_N sigma1 v
    tau: it vanishes for a fixed sigma1, not for sigma1 ~ sqrt(sigma0) (the bristles' critical damping). The
    limit is the rigid strike only where :func:`rigid_strike_check` finds no violation (a leading foot that
    lands slipping backwards pushes the trailing one into the ground through friction when mu_k is large).
    ``mu_kinetic``, ``mu_static`` None: ``MU_KINETIC``, ``MU_STATIC``. Bad arguments are refused first
    (:func:`check_converge`). A described walker's joint stops stiffen faster than the feet (:func:`stops_level`), and
    its touchdown state is every body of both legs (:func:`touchdown_states`) against the rigid walker's.
    """
    mu_kinetic = MU_KINETIC if mu_kinetic is None else mu_kinetic
    mu_static = MU_STATIC if mu_static is None else mu_static
    check_converge(config, levels, mu_kinetic, mu_static)
    rigid = rigid_limit_cycle(config)
    keys = STATE_KEYS if config.walker.description is None else list(rigid.touchdown)
    rigid_touchdown = np.array([rigid.touchdown[k] for k in keys])
    described = config.walker.description
    base_stiffness = contact_stiffness(config, None if described is None else max(f.radius for f in described.feet))
    rows = []
    for k in range(levels):
        stiffness = base_stiffness * 10.0**k
        restitution = 0.3 / math.sqrt(10.0) ** k
        sigma0 = 1e4 * 10.0**k
        level = {
            "contact.stiffness": stiffness, "contact.materials": None, "contact.restitution": restitution,
            "friction.model": "lugre", "friction.mu_kinetic": mu_kinetic, "friction.mu_static": mu_static,
            "friction.sigma0": sigma0, "friction.sigma1": BRISTLE_DAMPING, "simulation.initial": rigid.fixed_point,
            "simulation.max_steps": steps, "simulation.t_end": max(200.0, config.simulation.t_end),
        }  # fmt: skip
        result = simulate(derive(config, {**level, **stops_level(config, k)}))
        states = touchdown_states(result)
        if result.status != "walking" or len(states) < 3:
            rows.append(
                ConvergenceRow(stiffness, restitution, sigma0, result.status, math.nan, math.nan, math.nan, math.nan)
            )
            continue
        touchdowns = np.array([[s[key] for key in keys] for s in states])
        rows.append(
            ConvergenceRow(
                stiffness=stiffness,
                restitution=restitution,
                bristle_stiffness=sigma0,
                status=result.status,
                touchdown_difference=float(np.max(np.abs(touchdowns[-1] - rigid_touchdown))),
                period_difference=float(result.step_periods[-1] - rigid.step_period),
                settled=float(np.max(np.abs(touchdowns[-1] - touchdowns[-2]))),
                slip=float(result.step_summary()["slip_per_step"][-1]),
            )
        )
    return rigid, rows
