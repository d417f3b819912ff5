"""A walker in space (``walker.kind: description3d``) in MuJoCo: its description as MJCF, started on our start.

The MJCF is :func:`~biped_sim.bench.mjcf.space_mjcf`'s (the left leg on a free joint, the right on the hinge, full
inertias, the contact matched to ours); this walker takes sphere feet, whose bottom it follows. Our start (the rigid
gait's state, the stance foot's contact point at the origin) sets the free joint and the hinge; the scuffing guard,
heel-strike log and fall check are the planar benchmark walker's loop
(:class:`~biped_sim.bench.mujoco_walker.MujocoWalker`).

What each side assumes: MuJoCo's contact is a soft constraint on the acceleration, linear in penetration with its
damping acting from the first instant, and its friction an elliptic cone that holds true stick within the
constraint's softness; ours is a force law (Flores: Hertz stiffness with hysteresis damping, zero at zero
penetration) with regularised friction that creeps below its stick velocity.
"""

from __future__ import annotations

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from biped_sim.bench.mjcf import TIMESTEP, space_mjcf
from biped_sim.bench.mujoco_walker import MujocoWalker
from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.walkers.model import contact_stiffness, static_contact_penetration
from biped_sim.walkers.space_geometry import LegGeometry, leg_geometry, rolling_states, with_point_mass
from biped_sim.walkers.space_walker import check_initial


def space_legs(config: Config) -> tuple[LegGeometry, LegGeometry]:
    """The two legs as the compliant builder has them (hip mass on the left leg)."""
    space = config.walker.space  # type: ignore[union-attr]
    if space.leg.foot.shape != "sphere":
        raise ConfigError("walker.space.leg.foot.shape", "the MuJoCo walker in space takes sphere feet only")
    return with_point_mass(leg_geometry(space, 0), space.hip_mass), leg_geometry(space, 1)


class MujocoSpaceWalker(MujocoWalker):
    """The walker in space in MuJoCo, with the planar benchmark walker's guard, strike log and fall check."""

    def __init__(self, config: Config, initial: dict[str, float], timestep: float = TIMESTEP) -> None:
        legs = space_legs(config)
        self.config = config
        self.model = mujoco.MjModel.from_xml_string(space_mjcf(config, timestep))
        self.data = mujoco.MjData(self.model)
        self.feet = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"foot{i}") for i in (0, 1)]
        self.radius = config.walker.space.leg.foot.radius  # type: ignore[union-attr]
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
