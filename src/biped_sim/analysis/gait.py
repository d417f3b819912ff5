"""Gait metrics from an integration: steps, periods, lengths, slip, energy audit, constraint drift.

Heel strikes come from the compiled loop (the first touchdown of a leading foot that is not the
previous strike's foot: bounces are debounced there). Everything here is post-processing over
the recorded samples and strike states, using the same compiled kinematics and force functions
as the right-hand side (one source of truth per equation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from biped_sim.integrate.driver import Integration
from biped_sim.multibody.planar import (
    PlanarSystem,
    constraint_violation,
    foot_forces,
    foot_kinematics,
    mechanical_energy,
)
from biped_sim.walkers.model import BuiltModel


@dataclass
class StepTable:
    """One row per heel strike k: the step that strike begins."""

    strike_time: np.ndarray
    foot: np.ndarray
    period: np.ndarray  # t_{k+1} - t_k (nan for the last strike)
    length: np.ndarray  # contact point advance to the next strike (nan for the last)
    slip: np.ndarray  # stance-foot slip during the step (nan for the last)
    stance_angle: np.ndarray
    stance_rate: np.ndarray
    swing_angle: np.ndarray
    swing_rate: np.ndarray


def _rolling_coordinate(y: np.ndarray, system: PlanarSystem, foot: int) -> float:
    """x_C + R phi of a foot: constant while the arc rolls without slipping, so its change is the slip."""
    b = system.foot_body[foot]
    x_contact = foot_kinematics(y, system, foot)[3]
    return x_contact + system.foot_radius[foot] * y[3 * b + 2]


def step_table(model: BuiltModel, run: Integration) -> StepTable:
    """Per-step quantities from the heel-strike states."""
    system = model.system
    nb = model.n_bodies
    n = len(run.strike_t)
    period = np.full(n, np.nan)
    length = np.full(n, np.nan)
    slip = np.full(n, np.nan)
    angles = np.zeros((n, 4))
    for k in range(n):
        y = run.strike_y[k]
        foot = int(run.strike_foot[k])
        stance_body = int(system.foot_body[foot])
        swing_body = int(system.foot_body[system.foot_partner[foot]]) if system.foot_partner[foot] >= 0 else stance_body
        angles[k] = [
            y[3 * stance_body + 2],
            y[3 * nb + 3 * stance_body + 2],
            y[3 * swing_body + 2],
            y[3 * nb + 3 * swing_body + 2],
        ]
        if k + 1 < n:
            y_next = run.strike_y[k + 1]
            period[k] = run.strike_t[k + 1] - run.strike_t[k]
            next_foot = int(run.strike_foot[k + 1])
            length[k] = foot_kinematics(y_next, system, next_foot)[3] - foot_kinematics(y, system, foot)[3]
            slip[k] = _rolling_coordinate(y_next, system, foot) - _rolling_coordinate(y, system, foot)
    return StepTable(run.strike_t.copy(), run.strike_foot.copy(), period, length, slip, *angles.T)


@dataclass
class EnergyAudit:
    """Energy terms at the samples; residual = E(t) - E(0) + W_dissipated(t)."""

    kinetic: np.ndarray
    potential: np.ndarray
    elastic: np.ndarray
    dissipated_normal: np.ndarray
    dissipated_friction: np.ndarray
    residual: np.ndarray


def energy_audit(model: BuiltModel, run: Integration) -> EnergyAudit:
    """Energy balance over the samples (the dissipated work is integrated as ODE states)."""
    ns = len(run.t)
    terms = np.array([mechanical_energy(run.y[i], model.system, run.modes[i]) for i in range(ns)]).reshape(ns, 3)
    w_normal = run.y[:, -2]
    w_friction = run.y[:, -1]
    total = terms.sum(axis=1)
    residual = total - total[0] + (w_normal - w_normal[0]) + (w_friction - w_friction[0])
    return EnergyAudit(terms[:, 0], terms[:, 1], terms[:, 2], w_normal, w_friction, residual)


def constraint_drift(model: BuiltModel, run: Integration) -> np.ndarray:
    """(ns, 2): ||Phi|| and ||Phidot|| at each sample."""
    return np.array([constraint_violation(y, model.system) for y in run.y]).reshape(len(run.t), 2)


def contact_channels(model: BuiltModel, run: Integration) -> dict[str, np.ndarray]:
    """Per-foot penetration, normal force, friction force and slip velocity at the samples, (ns, nf) each."""
    ns, nf = len(run.t), model.n_feet
    out = {name: np.zeros((ns, nf)) for name in ("penetration", "normal_force", "friction_force", "slip_velocity")}
    for i in range(ns):
        for f in range(nf):
            f_n, f_t, _, _, _, delta, _, slip, _, _ = foot_forces(run.y[i], model.system, run.modes[i], f)
            out["penetration"][i, f] = delta
            out["normal_force"][i, f] = f_n
            out["friction_force"][i, f] = f_t
            out["slip_velocity"][i, f] = slip
    return out


def hip_position(model: BuiltModel, run: Integration) -> np.ndarray:
    """(ns, 2) position of joint 0 (the hip) in the slope frame."""
    system = model.system
    b = int(system.joint_bodies[0, 0])
    sx, sy = system.joint_points[0, 0], system.joint_points[0, 1]
    phi = run.y[:, 3 * b + 2]
    x = run.y[:, 3 * b] + np.cos(phi) * sx - np.sin(phi) * sy
    y = run.y[:, 3 * b + 1] + np.sin(phi) * sx + np.cos(phi) * sy
    return np.column_stack([x, y])
