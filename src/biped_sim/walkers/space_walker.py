"""A walker in space (``Config.in_space``) with compliant contact, in the spatial formulation.

Two bodies, the legs (:func:`~biped_sim.walkers.space_geometry.leg_geometry`: full inertia, the right leg the
left's mirror image; a hip mass is a point on the left leg at the hinge's midpoint, which moves alike on either
leg as it lies on the hinge axis), joined by a revolute hinge: a SPHERICAL primitive at the hinge's midpoint
(primitive 0: the "hip" that the falls and the measurements read) and two PERPENDICULAR ones keeping the hinge
axis z' of one leg along the other's. Feet: a sphere is the formulation's sphere, a point a sphere of radius 0,
and a ring its disc whose axis is the ring's plane normal (the lowest point of a circle against the ground
plane, in closed form), a torus that disc with its tube, an ellipsoid its quadric
(:func:`~biped_sim.multibody.spatial_feet.foot_bottom`); a torus's or ellipsoid's Hertz stiffness is that of its
bottom's equivalent radius (``SpaceFoot.hertz_radius``). Friction acts in the tangent plane on the slip velocity
vector (LuGre with a bristle vector), as for every spatial walker.

The start: ``simulation.initial`` holds the rigid gait's post-strike state (:data:`SPACE_STATE_KEYS`: the stance
leg's heading, bank, pitch and angular velocity, the hinge angle and rate; ``rigid_limit_cycle`` resolves it to the
rigid model's fixed point). The left leg stands on its foot, rolling without slip about its contact point, sunk
by the static penetration under the whole weight; the trailing (right) foot, behind the stance foot, is not
armed, so it leaves the ground as the rigid strike left it.
"""

from __future__ import annotations

import numpy as np

from biped_sim.config import Config
from biped_sim.config.space_description import SPACE_STATE_KEYS
from biped_sim.contact.profile import profile_ground
from biped_sim.errors import ConfigError
from biped_sim.multibody.spatial import PERPENDICULAR, SPHERICAL, SpatialSystem
from biped_sim.walkers.model import (
    BuiltModel,
    contact_arrays,
    contact_limits,
    contact_stiffness,
    standing_start,
    static_contact_penetration,
)
from biped_sim.walkers.space_geometry import (
    TO_SPATIAL,
    LegGeometry,
    euler_parameters,
    leg_geometry,
    rolling_states,
    with_point_mass,
)
from biped_sim.walkers.spatial_described import X, Y, Z, jointed_bodies, spatial_gravity

SLENDER_FLOOR = 1e-4  # the smallest principal moment a leg takes, of its largest (a thin rod's 0 about its axis)
BODY_NAMES = ["left", "right"]
FOOT_NAMES = ["left", "right"]


def hinge(legs: tuple[LegGeometry, LegGeometry]) -> list[tuple[int, int, int, tuple[float, ...]]]:
    """The revolute hinge: the hinge midpoint (walker-frame origin) of both legs coincide, z' of leg 0 stays
    perpendicular to x' and y' of leg 1."""
    s_a, s_b = (TO_SPATIAL @ -leg.com for leg in legs)
    return [
        (SPHERICAL, 0, 1, (*s_a, *s_b, 0.0)),
        (PERPENDICULAR, 0, 1, (*X, *Z, 0.0)),
        (PERPENDICULAR, 0, 1, (*Y, *Z, 0.0)),
    ]


def body_inertia(leg: LegGeometry) -> np.ndarray:
    """The leg's inertia in its body frame, each principal moment at least ``SLENDER_FLOOR`` of the largest: the
    formulation inverts it, and a thin rod has none about its axis (the hinge ties that spin to the other leg, so
    the floor only adds a small inertia to the walker's yaw)."""
    moments, axes = np.linalg.eigh(TO_SPATIAL @ leg.inertia @ TO_SPATIAL.T)
    moments = np.maximum(moments, SLENDER_FLOOR * moments.max())
    return (axes * moments) @ axes.T


def start_state(
    legs: tuple[LegGeometry, LegGeometry], initial: dict[str, float], sinkage: float
) -> tuple[np.ndarray, np.ndarray]:
    """(q, qd), one row (r, p) and (rdot, pdot) per leg, of the rigid gait state ``initial`` sunk by ``sinkage``."""
    states = rolling_states(legs, initial)
    q, qd = np.zeros((2, 7)), np.zeros((2, 7))
    for b in range(2):
        rotation = TO_SPATIAL @ states.rotation[b] @ TO_SPATIAL.T
        p, pdot = euler_parameters(rotation, TO_SPATIAL @ states.omega[b])
        q[b] = [*(TO_SPATIAL @ states.com[b] - [0.0, sinkage, 0.0]), *p]
        qd[b] = [*(TO_SPATIAL @ states.velocity[b]), *pdot]
    return q, qd


def check_initial(initial: object, optional: tuple[str, ...] = ()) -> dict[str, float]:
    """The initial state as the rigid gait's keys and perhaps ``optional`` ones (a torso's; ConfigError naming
    simulation.initial otherwise)."""
    if not isinstance(initial, dict) or not set(SPACE_STATE_KEYS) <= set(initial) <= {*SPACE_STATE_KEYS, *optional}:
        also = f" (optional: {', '.join(optional)})" if optional else ""
        raise ConfigError(
            "simulation.initial", f"a walker in space starts from the keys {', '.join(SPACE_STATE_KEYS)}{also}"
        )
    return {k: float(v) for k, v in initial.items()}


def build_space_walker(config: Config, initial: object) -> BuiltModel:
    """The compliant model of a walker in space, standing on its left foot in the gait state ``initial``."""
    space = config.walker.space  # type: ignore[union-attr]
    start = check_initial(initial)
    legs = (with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1))
    total_mass = legs[0].mass + legs[1].mass
    stiffness = contact_stiffness(config, space.leg.foot.hertz_radius)
    normal, friction, switches = contact_arrays(config, stiffness, total_mass)
    inertia = np.array([body_inertia(leg) for leg in legs])
    system = SpatialSystem(
        body_mass=np.array([leg.mass for leg in legs]),
        **jointed_bodies(inertia, hinge(legs)),
        foot_body=np.array([0, 1], dtype=np.int64),
        foot_center=np.array([TO_SPATIAL @ (leg.foot_centre - leg.com) for leg in legs]),
        foot_axis=np.array([np.zeros(3) if leg.foot_normal is None else TO_SPATIAL @ leg.foot_normal for leg in legs]),
        foot_radius=np.array([leg.foot_radius for leg in legs]),
        foot_tube=np.array([leg.foot_tube for leg in legs]),
        foot_quadric=np.array([TO_SPATIAL @ leg.foot_quadric @ TO_SPATIAL.T for leg in legs]),
        foot_partner=np.array([1, 0], dtype=np.int64),
        gravity=spatial_gravity(config),
        baumgarte=np.array([config.formulation.baumgarte.alpha, config.formulation.baumgarte.beta]),
        normal_params=normal,
        friction_params=friction,
        switches=switches,
        limits=contact_limits(config),
        ground=profile_ground(config.ground.profile, config.ground.slope),
    )
    sinkage = static_contact_penetration(config, total_mass, stiffness)
    q, qd = start_state(legs, start, sinkage)
    speed = float(np.linalg.norm(qd[0, :3]))
    y0, modes0 = standing_start(system, q, qd, (0,), max(speed, config.contact.impact_velocity_floor))
    meta = {"static_penetration": sinkage}
    return BuiltModel(system, y0, modes0, BODY_NAMES, FOOT_NAMES, space.leg_length(), total_mass, stiffness, meta)
