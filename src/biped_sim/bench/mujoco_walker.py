"""The benchmark walker in MuJoCo: the same compass walker as MJCF, stepped with MuJoCo's RK4.

How the model is matched (docs/guide/performance.md says the same):

* Geometry and inertia are the compass's description written as MJCF (:func:`.mjcf.planar_mjcf`): each
  leg is a body with mass m + M_H/2, centre of mass d = m c / (m + M_H/2) below the hip and
  inertia J = I + m (c - d)^2 + (M_H/2) d^2 about the hip-normal axis; a capsule (massless,
  visual) from the hip to the foot centre, and a sphere of radius R at l - R from the hip (the
  round foot: its contact with a plane is our arc's contact).
* Base: the stance leg floats on a planar joint set (slide along the slope, slide along its
  normal, hinge about the out-of-plane axis), which is the free-floating base of a planar walker;
  the swing leg hangs on the hip hinge. The slope is a plane tilted by gamma inside a static
  parent body, so every coordinate is in the slope frame and gravity stays vertical.
* Contact: MuJoCo's soft constraint is linear in penetration and acts on accelerations
  (a + d (b v + k r) = (1 - d) a0), not a force law. We match its natural frequency to our Hertz
  law linearised at the static penetration, omega^2 = 1.5 K delta_s^0.5 / M, and its damping
  ratio to our law's effective restitution (:mod:`.mujoco_contact`: the clipped oscillator's), with impedance d = 0.95
  (``solref = -k -b``). Friction is MuJoCo's cone with mu = mu_kinetic and no regularisation velocity.
* Scuffing guard: MuJoCo has none, so the loop applies ours (the same arming rule) every
  :data:`GUARD_STEPS` steps by switching a foot's collision on or off. "In the air" means higher
  than our static penetration: MuJoCo's penetration is about 30 times smaller, and an unloaded
  stance foot at late stance would otherwise count as lifted. Heel strikes are the touchdowns of
  the leading, armed foot, timed by interpolating the foot height.

Differences that remain: the force at touchdown (Flores is zero at zero penetration; MuJoCo's
damping acts at once), the static penetration (MuJoCo's is (1 - d) g / omega^2), and stick
(MuJoCo's cone allows true stick with constraint softness, ours creeps below v0).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from biped_sim.bench.mjcf import TIMESTEP, planar_mjcf
from biped_sim.bench.mujoco_contact import IMPEDANCE, matched_solref
from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.walkers import build_model
from biped_sim.walkers.model import contact_stiffness

GUARD_STEPS = 5  # MuJoCo steps between two applications of the scuffing guard (0.5 ms)


def static_penetration(config: Config) -> float:
    """Penetration of our contact law under the walker's weight [m]."""
    w = config.walker
    n = 1.0 if config.contact.model == "kelvin_voigt" else config.contact.exponent
    load = (2.0 * w.leg_mass + w.hip_mass) * config.gravity * math.cos(config.ground.slope)
    return (load / contact_stiffness(config)) ** (1.0 / n)


def contact_solref(config: Config) -> tuple[float, float]:
    """(k, b) of MuJoCo's direct solref matching our contact's frequency and restitution at static load."""
    w = config.walker
    mass = 2.0 * w.leg_mass + w.hip_mass
    return matched_solref(config, mass, contact_stiffness(config), static_penetration(config))


class MujocoWalker:
    """A MuJoCo model of the walker with our initial state, scuffing guard and heel-strike log."""

    def __init__(self, config: Config, timestep: float = TIMESTEP, integrator: str = "RK4") -> None:
        for name in ("leg_com_offset", "foot_offset"):
            if getattr(config.walker, name) != 0.0:
                raise ConfigError(f"walker.{name}", "the MuJoCo benchmark's walker has no offsets: must be 0")
        self.config = config
        self.model = mujoco.MjModel.from_xml_string(planar_mjcf(config, timestep, integrator))
        self.data = mujoco.MjData(self.model)
        self.feet = [mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"foot{i}") for i in (0, 1)]
        self.reach = config.walker.leg_length - config.walker.foot_radius
        self.radius = config.walker.foot_radius
        self.clearance = static_penetration(config)
        self.qpos0, self.qvel0 = self._initial_state()

    def _initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        """qpos, qvel from our built model's initial state (hip position/velocity, leg angles/rates)."""
        built = build_model(self.config)
        y0, system = built.y0, built.system
        (x0, y0_, th0), (_, _, th1) = y0[0:3], y0[3:6]
        vx0, vy0, om0 = y0[6:9]
        om1 = y0[11]
        d = system.joint_points[0, 1]
        hip = np.array([x0 - d * math.sin(th0), y0_ + d * math.cos(th0)])  # body point (0, d) of leg 0
        v_hip = np.array([vx0 - om0 * d * math.cos(th0), vy0 - om0 * d * math.sin(th0)])
        return np.array([hip[0], hip[1], th0, th1 - th0]), np.array([v_hip[0], v_hip[1], om0, om1 - om0])

    def foot_state(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """((x, height of the foot bottom) for each foot) in the slope frame."""
        q = self.data.qpos
        out = []
        for theta in (q[2], q[2] + q[3]):
            out.append((q[0] + self.reach * math.sin(theta), q[1] - self.reach * math.cos(theta) - self.radius))
        return out[0], out[1]

    def hip_height(self) -> float:
        """The hip's height above the slope [m]."""
        return float(self.data.qpos[1])

    def run(self, t_end: float) -> dict[str, Any]:
        """Simulate from the initial state to ``t_end`` (or a fall); heel-strike times and step count."""
        model, data = self.model, self.data
        mujoco.mj_resetData(model, data)
        data.qpos[:] = self.qpos0
        data.qvel[:] = self.qvel0
        armed = [True, False]
        touching = [True, False]
        last_strike = 0
        strikes: list[float] = []
        feet = self.foot_state()
        height_prev = [feet[0][1], feet[1][1]]
        for i in (0, 1):
            self._set_contact(i, armed[i])
        n_chunks = round(t_end / (GUARD_STEPS * model.opt.timestep))
        fall_height = self.config.simulation.fall_hip_height * self.config.walker.leg_length
        steps = 0
        for _ in range(n_chunks):
            t_prev = data.time
            mujoco.mj_step(model, data, nstep=GUARD_STEPS)
            steps += GUARD_STEPS
            feet = self.foot_state()
            for i in (0, 1):
                x, height = feet[i]
                ahead = x - feet[1 - i][0]
                airborne = height > self.clearance
                new_armed = not (airborne and ahead <= 0.0) if armed[i] else (height > 0.0 and ahead > 0.0)
                if new_armed != armed[i]:
                    armed[i] = new_armed
                    self._set_contact(i, new_armed)
                now_touching = armed[i] and height < 0.0
                if now_touching and not touching[i] and i != last_strike and ahead > 0.0:
                    h0 = height_prev[i]
                    frac = h0 / (h0 - height) if h0 > 0.0 else 1.0
                    strikes.append(t_prev + frac * (data.time - t_prev))
                    last_strike = i
                touching[i] = now_touching
                height_prev[i] = height
            self._sample(len(strikes), last_strike)
            if self.hip_height() < fall_height:
                return {"status": "fell", "t_final": float(data.time), "steps": steps, "strikes": strikes}
        return {"status": "walking", "t_final": float(data.time), "steps": steps, "strikes": strikes}

    def _sample(self, n_strikes: int, last_foot: int) -> None:
        """Called after every chunk of steps with the strikes so far and the last striking foot: a subclass's
        per-step measures (the planar walker has none)."""

    def _set_contact(self, foot: int, on: bool) -> None:
        self.model.geom_contype[self.feet[foot]] = 1 if on else 0
        self.model.geom_conaffinity[self.feet[foot]] = 1 if on else 0


def run_mujoco_bench(
    config: Config, t_end: float, repeats: int, reference: np.ndarray, log: Callable[[str], None]
) -> dict[str, Any]:
    """MuJoCo's wall time (median of ``repeats`` after a warm-up), real-time factor and steady step period."""
    walker = MujocoWalker(config)
    walker.run(0.05)
    walls = []
    result: dict[str, Any] = {}
    for _ in range(repeats):
        start = time.perf_counter()
        result = walker.run(t_end)
        walls.append(time.perf_counter() - start)
    wall = statistics.median(walls)
    periods = np.diff(result["strikes"])
    tail = periods[-min(5, len(periods)) :] if len(periods) else periods
    step_period = float(np.mean(tail)) if len(tail) else math.nan
    out = {
        "available": True,
        "version": mujoco.__version__,
        "integrator": "RK4",
        "timestep": walker.model.opt.timestep,
        "guard_steps": GUARD_STEPS,
        "status": result["status"],
        "wall_s": wall,
        "walls_s": walls,
        "steps": result["steps"],
        "us_per_step": wall / result["steps"] * 1e6,
        "rtf": result["t_final"] / wall,
        "n_strikes": len(result["strikes"]),
        "strike_times": result["strikes"],
        "step_period_s": step_period,
        "reference_step_period_s": float(np.mean(reference[-min(5, len(reference)) :])) if len(reference) else math.nan,
        "solref": list(contact_solref(config)),
        "impedance": IMPEDANCE,
        "mjcf": planar_mjcf(config),
    }
    log(f"MuJoCo RK4 dt {out['timestep']:g}: {wall:.3f} s, {result['status']}, step period {step_period:.4f} s")
    return out
