"""A walker in space (``walker.kind: description3d``) in MuJoCo: its description as MJCF, started on our start.

The MJCF's world is the rigid model's slope frame (x downhill, y left, z along the slope normal; gravity tilted
by the slope, the ground the plane z = 0). The left leg floats on a free joint, its body frame the walker frame
(origin at the hinge's midpoint, x forward, y along the hinge, z up the leg); the right leg hangs from it on a hinge
about y. Masses, centres of mass and full inertia tensors are the compliant builder's (the hip mass on the left
leg, each principal moment floored as there); each foot is a sphere geom. Our start (the rigid gait's state, the
stance foot's contact point at the origin) sets the free joint and the hinge. The contact is matched as for the
planar benchmark walker (:func:`~biped_sim.bench.mujoco_contact.matched_solref`: our law's frequency linearised at
the static penetration under the whole weight, the damping ratio whose clipped contact loses what ours loses), and
the scuffing guard, heel-strike log and fall check are its loop (:class:`~biped_sim.bench.mujoco_walker.MujocoWalker`).

What each side assumes: MuJoCo's contact is a soft constraint on the acceleration, linear in penetration with its
damping acting from the first instant, and its friction an elliptic cone that holds true stick within the
constraint's softness; ours is a force law (Flores: Hertz stiffness with hysteresis damping, zero at zero
penetration) with regularised friction that creeps below its stick velocity.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from biped_sim.bench.mujoco_contact import IMPEDANCE, matched_solref
from biped_sim.bench.mujoco_walker import TIMESTEP, MujocoWalker
from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.walkers.model import contact_stiffness, static_contact_penetration
from biped_sim.walkers.space_geometry import TO_SPATIAL, LegGeometry, leg_geometry, rolling_states, with_point_mass
from biped_sim.walkers.space_walker import body_inertia, check_initial


def space_legs(config: Config) -> tuple[LegGeometry, LegGeometry]:
    """The two legs as the compliant builder has them (hip mass on the left leg)."""
    space = config.walker.space  # type: ignore[union-attr]
    if space.leg.foot.shape != "sphere":
        raise ConfigError("walker.space.leg.foot.shape", "the MuJoCo walker in space takes sphere feet only")
    return with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1)


def _body(leg: LegGeometry, foot: str, contact: str) -> str:
    """A leg's inertial element and foot geom (walker frame)."""
    j = TO_SPATIAL.T @ body_inertia(leg) @ TO_SPATIAL
    full = " ".join(repr(float(v)) for v in (j[0, 0], j[1, 1], j[2, 2], j[0, 1], j[0, 2], j[1, 2]))
    com = " ".join(repr(float(v)) for v in leg.com)
    centre = " ".join(repr(float(v)) for v in leg.foot_centre)
    return (
        f'<inertial pos="{com}" mass="{float(leg.mass)!r}" fullinertia="{full}"/>'
        f'<geom name="{foot}" type="sphere" pos="{centre}" size="{float(leg.foot_radius)!r}" mass="0" {contact}/>'
    )


def space_mjcf(config: Config, timestep: float = TIMESTEP, integrator: str = "RK4") -> str:
    """MJCF of the walker in space of ``config`` on its slope."""
    legs = space_legs(config)
    mass = legs[0].mass + legs[1].mass
    stiffness = contact_stiffness(config, legs[0].foot_radius)
    k, b = matched_solref(config, mass, stiffness, static_contact_penetration(config, mass, stiffness))
    mu = config.friction.mu_kinetic
    contact = f'friction="{mu!r} 0 0" solref="{-k!r} {-b!r}" solimp="{IMPEDANCE} {IMPEDANCE} 0.001"'
    g, slope = config.gravity, config.ground.slope
    gravity = f"{g * math.sin(slope)!r} 0 {-g * math.cos(slope)!r}"
    return f"""<mujoco model="walker_in_space">
  <compiler angle="radian" inertiafromgeom="false"/>
  <option timestep="{timestep!r}" integrator="{integrator}" gravity="{gravity}" cone="elliptic"/>
  <worldbody>
    <geom name="ground" type="plane" size="50 50 0.1" friction="{mu!r} 0 0"/>
    <body name="left">
      <freejoint name="base"/>
      {_body(legs[0], "foot0", contact)}
      <body name="right">
        <joint name="hinge" type="hinge" axis="0 1 0"/>
        {_body(legs[1], "foot1", contact)}
      </body>
    </body>
  </worldbody>
</mujoco>
"""


class MujocoSpaceWalker(MujocoWalker):
    """The walker in space in MuJoCo, with the planar benchmark walker's guard, strike log and fall check."""

    def __init__(self, config: Config, initial: dict[str, float], timestep: float = TIMESTEP) -> None:
        self.config = config
        self.model = mujoco.MjModel.from_xml_string(space_mjcf(config, timestep))
        self.data = mujoco.MjData(self.model)
        self.feet = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"foot{i}") for i in (0, 1)]
        self.radius = config.walker.space.leg.foot.radius  # type: ignore[union-attr]
        legs = space_legs(config)
        mass = legs[0].mass + legs[1].mass
        self.clearance = static_contact_penetration(config, mass, contact_stiffness(config, self.radius))
        self.qpos0, self.qvel0 = self._space_state(legs, check_initial(initial))

    @staticmethod
    def _space_state(legs: tuple[LegGeometry, LegGeometry], initial: dict[str, float]) -> tuple[np.ndarray, ...]:
        """qpos, qvel: the free joint at the hinge's midpoint (world velocity, body-frame rate) and the hinge."""
        states = rolling_states(legs, initial)
        stance = states.rotation[0]
        origin = states.com[0] - stance @ legs[0].com
        x, y, z, w = Rotation.from_matrix(stance).as_quat()
        qpos = np.array([*origin, w, x, y, z, initial["swing_angle"]])
        omega = states.omega[0]
        qvel = np.array([*np.cross(omega, origin), *(stance.T @ omega), initial["swing_rate"]])
        return qpos, qvel

    def foot_state(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """((x, height of the sphere's bottom) for each foot) in the slope frame."""
        mujoco.mj_kinematics(self.model, self.data)  # the geoms where the state is now (mj_step leaves them behind)
        xpos = self.data.geom_xpos
        (x0, _, z0), (x1, _, z1) = xpos[self.feet[0]], xpos[self.feet[1]]
        return (float(x0), float(z0 - self.radius)), (float(x1), float(z1 - self.radius))

    def hip_height(self) -> float:
        """The hinge midpoint's height above the slope [m]."""
        return float(self.data.qpos[2])
