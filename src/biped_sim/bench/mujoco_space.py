"""A walker in space (``Config.in_space``) in MuJoCo: its description as MJCF, started on our start.

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

import time
from typing import Any

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from biped_sim.bench.mjcf import TIMESTEP, space_mjcf
from biped_sim.bench.mujoco_walker import MujocoWalker
from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.integrate.driver import Integration
from biped_sim.multibody.dispatch import measures
from biped_sim.simulate import prepare_model, simulate
from biped_sim.walkers.model import BuiltModel, contact_stiffness, static_contact_penetration
from biped_sim.walkers.space_geometry import LegGeometry, leg_geometry, rolling_states, with_point_mass
from biped_sim.walkers.space_walker import check_initial

STEPS_COMPARED = 3  # the laterally unstable Kuo-type compass falls after its third or fourth step


def space_legs(config: Config) -> tuple[LegGeometry, LegGeometry]:
    """The two legs as the compliant builder has them (hip mass on the left leg)."""
    space = config.walker.space  # type: ignore[union-attr]
    if space.leg.foot.shape != "sphere":
        raise ConfigError("walker.description.feet", "the MuJoCo walker in space takes sphere feet only")
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

    def run(self, t_end: float) -> dict[str, Any]:
        """The planar walker's run, tracing the strikes' contact points and the hip's lateral path."""
        self._places = [np.zeros(2)]  # the start: the stance foot's contact point at the origin
        self._lateral: list[list[float]] = [[]]
        return super().run(t_end)

    def _sample(self, n_strikes: int, last_foot: int) -> None:
        """The hip's lateral place; at a new strike (seen at the end of its chunk of steps, 0.5 ms at most after it)
        the striking sphere's lowest point."""
        y = float(self.data.qpos[1])
        if n_strikes >= len(self._places):
            self._lateral[-1].append(y)
            self._places.append(self.data.geom_xpos[self.feet[last_foot], :2].copy())
            self._lateral.append([])
        self._lateral[-1].append(y)

    def places(self) -> np.ndarray:
        """(downhill, lateral) of the start's contact point and of each strike's in the last run [m]."""
        return np.array(self._places)

    def sways(self) -> np.ndarray:
        """The hinge midpoint's lateral excursion (max - min) between consecutive strikes of the last run [m]."""
        return np.array([max(y) - min(y) for y in self._lateral[1:-1]])


def _our_places(model: BuiltModel, run: Integration) -> np.ndarray:
    """(downhill, lateral) of our start's contact point (the origin) and of each strike's (the striking foot's lowest
    point, as our step table has it)."""
    point = measures(model.system).foot_point
    strikes = [point(run.strike_y[k], model.system, int(run.strike_foot[k])) for k in range(len(run.strike_t))]
    return np.array([(0.0, 0.0), *strikes])


def side_by_side(config: Config, initial: dict[str, float], n_steps: int = STEPS_COMPARED) -> dict[str, Any]:
    """Our compliant run and MuJoCo's of the walker in space of ``config`` from the rigid gait's state ``initial``:
    per step of the first ``n_steps`` (the first from the start), its period, length and width (the downhill and
    lateral distance between the contact points of the strikes that begin and end it; the lateral sign flipped on
    our side, whose third axis points right), and from the second on the hip's lateral sway (our step table's);
    each side's status, wall time and real-time factor."""
    start = time.perf_counter()
    model = prepare_model(config)
    ours = simulate(config, model=model)
    our_wall = time.perf_counter() - start
    walker = MujocoSpaceWalker(config, initial)
    start = time.perf_counter()
    theirs = walker.run(config.simulation.t_end)
    their_wall = time.perf_counter() - start
    n = min(n_steps, len(ours.heel_strike_times), len(theirs["strikes"]))
    steps = [np.diff(_our_places(model, ours.run)[: n + 1], axis=0), np.diff(walker.places()[: n + 1], axis=0)]
    pairs = {
        "period": (np.diff(ours.heel_strike_times[:n], prepend=0.0), np.diff(theirs["strikes"][:n], prepend=0.0)),
        "length": (steps[0][:, 0], steps[1][:, 0]),
        "width": (np.abs(steps[0][:, 1]), np.abs(steps[1][:, 1])),
        "sway": (ours.steps.sway[: n - 1], walker.sways()[: n - 1]),  # from the first strike on (no start sway)
    }
    return {
        "quantities": {
            name: {"ours": a.tolist(), "mujoco": b.tolist(), "relative_difference": (b / a - 1.0).tolist()}
            for name, (a, b) in pairs.items()
        },
        "ours": {"status": ours.status, "wall_s": our_wall, "rtf": ours.t_final / our_wall},
        "mujoco": {"status": theirs["status"], "wall_s": their_wall, "rtf": theirs["t_final"] / their_wall},
    }
