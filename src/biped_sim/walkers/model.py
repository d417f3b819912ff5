"""The product of a walker builder: compiled-system arrays plus names and metadata."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field, replace

import numpy as np

from biped_sim.config import Config, MaterialsConfig
from biped_sim.contact.friction import FRICTION_LAWS, friction_parameters
from biped_sim.contact.normal import NORMAL_LAWS, hertz_stiffness, normal_parameters
from biped_sim.contact.response import ARMED, IMPACT_SPEED, N_MODE_COLUMNS, TOUCHING
from biped_sim.errors import ConfigError
from biped_sim.multibody.dispatch import contact_buffers, formulation_of
from biped_sim.multibody.events import contact_count, system_update_modes
from biped_sim.multibody.minimal import MinimalSystem, tree_system
from biped_sim.multibody.planar import PlanarSystem
from biped_sim.multibody.spatial import SpatialSystem
from biped_sim.multibody.tree import tree_state

_START_MODES_DEFERRED = ContextVar("start_modes_deferred", default=False)


@contextmanager
def start_modes_deferred() -> Iterator[None]:
    """Inside the block, :func:`update_start_modes` leaves out the start's mode update, so that a build compiles
    nothing: a model with the run's types, shapes and checks, whose only use is a compile's argument types (a
    first run's second process, :mod:`biped_sim.simulate.aside`, which starts before the update's compile), never
    a model to integrate."""
    token = _START_MODES_DEFERRED.set(True)
    try:
        yield
    finally:
        _START_MODES_DEFERRED.reset(token)


@dataclass
class BuiltModel:
    """A walker ready to integrate: the system, its initial state and what the numbers mean."""

    system: PlanarSystem | SpatialSystem | MinimalSystem
    y0: np.ndarray
    modes0: np.ndarray
    body_names: list[str]
    foot_names: list[str]
    leg_length: float
    total_mass: float
    stiffness: float
    meta: dict[str, float] = field(default_factory=dict)

    @property
    def n_bodies(self) -> int:
        return int(self.system.body_mass.shape[0])

    @property
    def n_feet(self) -> int:
        return int(self.system.foot_body.shape[0])

    def state_names(self) -> list[str]:
        """Names of the ODE state entries, in order (the formulation's state layout)."""
        return formulation_of(self.system).layout_of(self.system).names(self.body_names, self.foot_names)


def contact_stiffness(config: Config, foot_radius: float | None = None) -> float:
    """K from ``contact.stiffness`` or from Hertz theory with the materials and the foot radius (by default
    ``walker.foot_radius``)."""
    if config.contact.stiffness is not None:
        return config.contact.stiffness
    materials = config.contact.materials or MaterialsConfig()
    return hertz_stiffness(
        materials.foot.youngs_modulus,
        materials.foot.poisson_ratio,
        materials.ground.youngs_modulus,
        materials.ground.poisson_ratio,
        config.walker.foot_radius if foot_radius is None else foot_radius,
    )


def contact_arrays(
    config: Config, stiffness: float, effective_mass: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(normal_params, friction_params, switches) for the compiled kernels."""
    c, f = config.contact, config.friction
    normal = normal_parameters(c.model, stiffness, c.exponent, c.restitution, c.damping, effective_mass)
    friction = friction_parameters(
        f.mu_kinetic,
        f.mu_static,
        f.v0,
        f.v1,
        f.v_stribeck,
        f.stribeck_decay,
        f.viscous,
        f.sigma0,
        f.sigma1,
        f.sigma2,
        spin_radius=f.spin_radius,
    )
    switches = np.array(
        [NORMAL_LAWS[c.model].index, FRICTION_LAWS[f.model].index, 1 if c.scuffing_guard else 0], dtype=np.int64
    )
    return normal, friction, switches


def contact_limits(config: Config, leg_length: float | None = None) -> np.ndarray:
    """The kernels' ``limits`` array: impact velocity floor, fall hip height [m], fall leg angle [rad], re-contact
    time [s] (0 for ``contact.impact_memory: touchdown``: every touchdown a new impact). ``leg_length``: the
    walker's, by default ``walker.leg_length``."""
    contact = config.contact
    return np.array(
        [
            contact.impact_velocity_floor,
            config.simulation.fall_hip_height * (config.walker.leg_length if leg_length is None else leg_length),
            config.simulation.fall_leg_angle,
            contact.recontact_time if contact.impact_memory == "impact" else 0.0,
        ]
    )


MAX_STATIC_SINKAGE = 0.05  # of the leg length: a contact softer than this does not carry the walker


def static_contact_penetration(
    config: Config, load_mass: float, stiffness: float, leg_length: float | None = None
) -> float:
    """Penetration [m] at which one foot carries ``load_mass`` on the slope: K delta^n = m g cos(gamma).

    ConfigError when the contact cannot carry the walker (the foot would sink over ``MAX_STATIC_SINKAGE``
    of the leg length, by default ``walker.leg_length``): the stiffness, the masses or gravity are not those
    of a walker.
    """
    length = config.walker.leg_length if leg_length is None else leg_length
    exponent = 1.0 if config.contact.model == "kelvin_voigt" else config.contact.exponent
    weight = load_mass * config.gravity * math.cos(config.ground.slope)
    penetration = (weight / stiffness) ** (1.0 / exponent)
    if not penetration < MAX_STATIC_SINKAGE * length:
        raise ConfigError(
            "contact.stiffness",
            f"too soft for the walker's weight ({weight:.3g} N with walker masses and gravity): the stance foot "
            f"would sink {penetration:.3g} m, over {MAX_STATIC_SINKAGE:.0%} of walker.leg_length",
        )
    return penetration


def standing_start(
    system: PlanarSystem | SpatialSystem,
    q: np.ndarray,
    qd: np.ndarray,
    stance_feet: tuple[int, ...],
    impact_speed: float,
    update_modes: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """(y0, modes0) of a walker whose ``stance_feet`` "just struck": generalized coordinates ``q`` and rates ``qd``
    (absolute coordinates: one row per body), bristles relaxed, no work dissipated yet.

    The stance feet are armed and touching and remember ``impact_speed`` as their approach velocity; the mode
    update (:func:`update_start_modes`; ``update_modes=False``: left to the caller) then arms each other foot that
    is ahead of its partner and in the air.
    """
    layout = formulation_of(system).layout_of(system)
    y0 = np.zeros(layout.size)
    y0[layout.positions] = np.ravel(q)
    y0[layout.velocities] = np.ravel(qd)
    modes0 = np.zeros((contact_count(system), N_MODE_COLUMNS))  # the feet, then the joint stops
    for foot in stance_feet:
        modes0[foot, ARMED] = 1.0
        modes0[foot, TOUCHING] = 1.0
        modes0[foot, IMPACT_SPEED] = impact_speed
    if update_modes:
        update_start_modes(system, y0, modes0)
    return y0, modes0


def update_start_modes(system: PlanarSystem | SpatialSystem, y0: np.ndarray, modes0: np.ndarray) -> None:
    """The start's mode update of ``system`` at ``y0`` on ``modes0`` (in place): each foot ahead of its partner and
    in the air armed, each stop's contact state; left out under :func:`start_modes_deferred`."""
    if not _START_MODES_DEFERRED.get():
        system_update_modes(0.0, y0, system, modes0, contact_buffers(system))


def minimal_model(planar: BuiltModel) -> BuiltModel:
    """The planar walker ``planar`` (a tree of bodies rooted at the hip) in minimal coordinates: its system and
    start converted, so that both formulations describe the same walker by construction."""
    return replace(planar, system=tree_system(planar.system), y0=tree_state(planar.y0, planar.system))
