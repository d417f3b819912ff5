"""The start of a rigid run: the walker of a config and its validated post-impact initial state."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from biped_sim.config import Config
from biped_sim.config.walker_registry import capabilities
from biped_sim.errors import ConfigError
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.limit_cycle import rigid_limit_cycle_initial
from biped_sim.rigid.step import RTOL
from biped_sim.rigid.tree import RigidWalker

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
    caps = capabilities(walker.name)
    if caps.nondimensional:
        units.update(dict.fromkeys(("s", "m", "m/s", "rad/s", "J"), NONDIMENSIONAL))
    elif caps.energy_per_kg:
        units["J"] = "J/kg"  # the hub's mass is not a parameter: energies per kg of it
    return units


def _check_start(config: Config, walker: RigidWalker, state: np.ndarray) -> None:
    """ConfigError naming the field when the walker cannot start from ``state`` (just after a heel strike)."""
    legs = walker.legs_state(state)
    for name, value in legs.items():
        if not math.isfinite(value):
            raise ConfigError(f"simulation.initial.{name}", "must be a finite number")
    for k, name in enumerate(walker.state_names[: walker.n_q]):
        if abs(legs[name]) >= walker.fall_angles[k]:
            limit = f"the fall_angle of the body {name.removesuffix('_angle')!r}" if k in walker.off_legs else None
            raise ConfigError(
                f"simulation.initial.{name}", f"beyond {limit or 'simulation.fall_leg_angle'}: the walker starts fallen"
            )
    if walker.hip_height(state) <= config.simulation.fall_hip_height * walker.leg_length:
        raise ConfigError("simulation.initial.stance_angle", "the hip starts below simulation.fall_hip_height")
    if walker.shift:
        if abs(legs["stance_angle"]) > 0.5 * walker.shift + ANGLE_TOLERANCE:
            raise ConfigError(
                "simulation.initial.stance_angle",
                f"the rimless wheel's stance spoke must be within pi/N = {0.5 * walker.shift:.6g} rad of the slope "
                "normal (else another spoke starts below the ground)",
            )
    elif walker.hip_past_stance_foot(state):
        raise ConfigError(
            f"simulation.initial.{walker.state_names[0]}",
            "the rigid model starts just after a heel strike: the stance leg must not be past the slope normal "
            "(>= 0; with a walker.foot_offset d, the hip not past the arc centre: >= -atan2(d, l - R))",
        )


def rigid_start(config: Config) -> RigidStart:
    """Build the rigid walker of ``config`` and resolve its initial state (validated; ConfigError naming the field).

    ``simulation.initial: rigid_limit_cycle`` is resolved by Newton on the rigid step map.
    """
    if config.dynamics != "rigid":
        raise ValueError("rigid_start: the config has dynamics: compliant")
    walker = rigid_walker(config)
    initial = config.simulation.initial
    if isinstance(initial, str):
        legs = rigid_limit_cycle_initial(config)
    else:
        legs = initial if isinstance(initial, dict) else initial.model_dump()
    state = walker.state_from_legs(legs)
    _check_start(config, walker, state)
    return RigidStart(walker, state)


def touchdown_legs(walker: RigidWalker, x_minus: np.ndarray) -> dict[str, float]:
    """A pre-impact state named as at touchdown: 'stance' the leg (spoke) landing, 'swing' the one leaving.

    The landing leg is the swing leg until now (its hip body: ``landing_index``) and the rimless wheel's next
    spoke, which turns at the wheel's single rate. A leg of several bodies is named by its hip body.
    """
    n = walker.n_q
    return {
        "stance_angle": walker.next_stance_angle(x_minus),
        "stance_rate": float(x_minus[n + walker.landing_index]),
        "swing_angle": float(x_minus[0]),
        "swing_rate": float(x_minus[n]),
    }
