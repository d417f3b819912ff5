"""Gait metrics from an integration: steps, periods, lengths, slip, energy audit, constraint drift.

Heel strikes come from the compiled loop (the first touchdown of a leading foot that is not the
previous strike's foot: bounces are debounced there). Everything here is post-processing over
the recorded samples and strike states, using the same compiled kinematics and force functions
as the right-hand side (one source of truth per equation), reached through the formulation's
:class:`~biped_sim.multibody.dispatch.Measures` so that planar and spatial runs are measured alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from biped_sim.integrate.driver import Integration
from biped_sim.multibody.dispatch import measures
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


class StepAccess:
    """Step accessors shared by the compliant and the rigid run results (which hold a ``steps`` StepTable)."""

    steps: StepTable

    @property
    def heel_strike_times(self) -> np.ndarray:
        return self.steps.strike_time

    @property
    def step_periods(self) -> np.ndarray:
        """Periods of the completed steps (between consecutive heel strikes)."""
        return self.steps.period[:-1] if len(self.steps.period) else self.steps.period

    @property
    def step_lengths(self) -> np.ndarray:
        return self.steps.length[:-1] if len(self.steps.length) else self.steps.length

    @property
    def heel_strike_states(self) -> list[dict[str, float]]:
        """Touchdown leg angles and rates at each heel strike; 'stance' is the leg that just touched down."""
        s = self.steps
        return [
            {
                "stance_angle": float(s.stance_angle[k]),
                "stance_rate": float(s.stance_rate[k]),
                "swing_angle": float(s.swing_angle[k]),
                "swing_rate": float(s.swing_rate[k]),
            }
            for k in range(len(s.strike_time))
        ]

    def step_summary(self) -> dict[str, Any]:
        """The summary.json entries of the steps: times, feet, periods, lengths, mean speed, slip."""
        steps, periods, lengths = self.steps, self.step_periods, self.step_lengths
        span = float(steps.strike_time[-1] - steps.strike_time[0]) if len(steps.strike_time) > 1 else 0.0
        return {
            "n_steps": len(steps.strike_time),
            "step_times": steps.strike_time.tolist(),
            "step_feet": steps.foot.tolist(),
            "step_periods": periods.tolist(),
            "step_lengths": lengths.tolist(),
            "mean_step_period": _finite_or_none(float(np.mean(periods))) if len(periods) else None,
            "last_step_period": _finite_or_none(float(periods[-1])) if len(periods) else None,
            "mean_speed": float(np.nansum(lengths)) / span if span > 0 else 0.0,
            "slip_per_step": steps.slip[:-1].tolist() if len(steps.slip) else [],
        }


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _rolling_coordinate(y: np.ndarray, model: BuiltModel, foot: int) -> float:
    """x_C + R theta of a foot: constant while the arc rolls without slipping, so its change is the slip."""
    system = model.system
    m = measures(system)
    theta = m.pitch(y, system, int(system.foot_body[foot]))[0]
    return m.contact_x(y, system, foot) + system.foot_radius[foot] * theta


def step_table(model: BuiltModel, run: Integration) -> StepTable:
    """Per-step quantities from the heel-strike states."""
    system = model.system
    m = measures(system)
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
        angles[k] = [*m.pitch(y, system, stance_body), *m.pitch(y, system, swing_body)]
        if k + 1 < n:
            y_next = run.strike_y[k + 1]
            period[k] = run.strike_t[k + 1] - run.strike_t[k]
            next_foot = int(run.strike_foot[k + 1])
            length[k] = m.contact_x(y_next, system, next_foot) - m.contact_x(y, system, foot)
            slip[k] = _rolling_coordinate(y_next, model, foot) - _rolling_coordinate(y, model, foot)
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
    energy = measures(model.system).mechanical_energy
    terms = np.array([energy(run.y[i], model.system, run.modes[i]) for i in range(ns)]).reshape(ns, 3)
    w_normal = run.y[:, -2]
    w_friction = run.y[:, -1]
    total = terms.sum(axis=1)
    residual = total - total[0] + (w_normal - w_normal[0]) + (w_friction - w_friction[0])
    return EnergyAudit(terms[:, 0], terms[:, 1], terms[:, 2], w_normal, w_friction, residual)


def violation_names(model: BuiltModel) -> tuple[str, ...]:
    """Names of the columns of :func:`constraint_drift`: position, velocity (and normalization for spatial)."""
    return measures(model.system).violation_names


def constraint_drift(model: BuiltModel, run: Integration) -> np.ndarray:
    """(ns, k): ||Phi||, ||Phidot|| (and, spatial, ||p.p - 1|| over the bodies) at each sample."""
    m = measures(model.system)
    return np.array([m.violation(y, model.system) for y in run.y]).reshape(len(run.t), len(m.violation_names))


def contact_channels(model: BuiltModel, run: Integration) -> dict[str, np.ndarray]:
    """Per-foot contact channels at the samples, (ns, nf) each.

    Penetration, normal force, friction force and slip velocity along the slope (x); spatial
    formulations add the lateral (z) friction force and slip velocity.
    """
    m = measures(model.system)
    ns, nf = len(run.t), model.n_feet
    out = {name: np.zeros((ns, nf)) for name in m.contact_names}
    for i in range(ns):
        for f in range(nf):
            values = m.contact(run.y[i], model.system, run.modes[i], f)
            for name, value in zip(m.contact_names, values, strict=True):
                out[name][i, f] = value
    return out


def hip_position(model: BuiltModel, run: Integration) -> np.ndarray:
    """(ns, 2) planar or (ns, 3) spatial position of joint 0 (the hip) in the slope frame."""
    hip = measures(model.system).hip
    return np.array([hip(y, model.system) for y in run.y]).reshape(len(run.t), -1)


def attitude_channels(model: BuiltModel, run: Integration) -> dict[str, np.ndarray]:
    """Spatial only (else empty): per-body pitch, roll (lateral rocking), yaw (heading drift) [rad] and pitch rate
    (the planar leg angle rate) [rad/s], (ns, nb) each."""
    attitude = measures(model.system).attitude
    if attitude is None:
        return {}
    ns, nb = len(run.t), model.n_bodies
    values = np.array([[attitude(run.y[i], model.system, b) for b in range(nb)] for i in range(ns)])
    values = values.reshape(ns, nb, 4)
    return {"pitch": values[:, :, 0], "roll": values[:, :, 1], "yaw": values[:, :, 2], "pitch_rate": values[:, :, 3]}


def lateral_summary(model: BuiltModel, run: Integration) -> dict[str, dict[str, float]]:
    """Spatial only (else empty): the summary's ``lateral`` entry.

    Largest |roll| of any body (lateral rocking), final yaw of body 0 (heading drift) [rad], and
    the largest lateral friction force and slip velocity of any foot [N, m/s].
    """
    attitude = attitude_channels(model, run)
    if not attitude:
        return {}
    channels = contact_channels(model, run)
    return {
        "lateral": {
            "roll_max": float(np.max(np.abs(attitude["roll"]))),
            "yaw_final": float(attitude["yaw"][-1, 0]),
            "yaw_max": float(np.max(np.abs(attitude["yaw"]))),
            "friction_force_lateral_max": float(np.max(np.abs(channels["friction_force_lateral"]))),
            "slip_velocity_lateral_max": float(np.max(np.abs(channels["slip_velocity_lateral"]))),
        }
    }
