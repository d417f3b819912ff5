"""Per-sample channels of a compliant run: constraint drift, contact forces, hip path, body attitude."""

from __future__ import annotations

import numpy as np

from biped_sim.integrate.driver import Integration
from biped_sim.measure.loops import attitude_loop, contact_loop, hip_loop, violation_loop
from biped_sim.multibody.dispatch import measures
from biped_sim.walkers.model import BuiltModel


def violation_names(model: BuiltModel) -> tuple[str, ...]:
    """Names of the columns of :func:`constraint_drift`: position, velocity (and normalization for spatial)."""
    return measures(model.system).violation_names


def constraint_drift(model: BuiltModel, run: Integration) -> np.ndarray:
    """(ns, k): ||Phi||, ||Phidot|| (and, spatial, ||p.p - 1|| over the bodies) at each sample."""
    out = np.empty((len(run.t), len(violation_names(model))))
    violation_loop(run.y, model.system, out)
    return out


def contact_channels(model: BuiltModel, run: Integration) -> dict[str, np.ndarray]:
    """Per-foot contact channels at the samples, (ns, nf) each.

    Penetration, normal force, friction force and slip velocity along the slope (x); spatial
    formulations add the lateral (z) friction force and slip velocity.
    """
    names = measures(model.system).contact_names
    out = np.empty((len(names), len(run.t), model.n_feet))
    contact_loop(run.y, run.modes, model.system, out)
    return {name: out[k] for k, name in enumerate(names)}


def hip_position(model: BuiltModel, run: Integration) -> np.ndarray:
    """(ns, 2) planar or (ns, 3) spatial position of joint 0 (the hip) in the slope frame."""
    out = np.empty((len(run.t), len(measures(model.system).hip(model.y0, model.system))))
    hip_loop(run.y, model.system, out)
    return out


def attitude_channels(model: BuiltModel, run: Integration) -> dict[str, np.ndarray]:
    """Spatial only (else empty): per-body pitch, roll (lateral rocking), yaw (heading drift) [rad] and pitch rate
    (the planar leg angle rate) [rad/s], (ns, nb) each."""
    if measures(model.system).attitude is None:
        return {}
    values = np.empty((len(run.t), model.n_bodies, 4))
    attitude_loop(run.y, model.system, values)
    return {"pitch": values[:, :, 0], "roll": values[:, :, 1], "yaw": values[:, :, 2], "pitch_rate": values[:, :, 3]}


def lateral_summary(attitude: dict[str, np.ndarray], channels: dict[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """Spatial runs (``attitude`` not empty; else empty): the summary's ``lateral`` entry.

    Largest |roll| of any body (lateral rocking), final yaw of body 0 (heading drift) [rad], and
    the largest lateral friction force and slip velocity of any foot [N, m/s].
    """
    if not attitude:
        return {}
    return {
        "lateral": {
            "roll_max": float(np.max(np.abs(attitude["roll"]))),
            "yaw_final": float(attitude["yaw"][-1, 0]),
            "yaw_max": float(np.max(np.abs(attitude["yaw"]))),
            "friction_force_lateral_max": float(np.max(np.abs(channels["friction_force_lateral"]))),
            "slip_velocity_lateral_max": float(np.max(np.abs(channels["slip_velocity_lateral"]))),
        }
    }


def contact_peaks(channels: dict[str, np.ndarray]) -> dict[str, float | None]:
    """The summary's largest penetration [m] and normal force [N] over the samples and feet (None without samples)."""
    penetration, normal = channels["penetration"], channels["normal_force"]
    if penetration.size == 0:
        return {"max_penetration": None, "peak_normal_force": None}
    return {"max_penetration": float(np.max(penetration)), "peak_normal_force": float(np.max(normal))}
