"""A compliant run: the penalty-contact model of a config, integrated and measured."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from biped_sim.config import Config
from biped_sim.integrate.blowup import Scales
from biped_sim.integrate.driver import Integration, integrate_model
from biped_sim.integrate.recorder import fall_reason
from biped_sim.io.atomic import json_safe
from biped_sim.io.provenance import package_version
from biped_sim.io.run_files import Channel, TrajectoryFile
from biped_sim.measure.channels import (
    attitude_channels,
    constraint_drift,
    contact_channels,
    contact_peaks,
    hip_position,
    lateral_summary,
    violation_names,
)
from biped_sim.measure.energy import EnergyAudit, energy_audit
from biped_sim.measure.steps import StepTable, step_table
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.simulate.result import RunResult, ordered_pushes, push_summary, wall_deadline
from biped_sim.walkers import BuiltModel

CHANNEL_UNITS = {
    "penetration": "m",
    "normal_force": "N",
    "friction_force": "N",
    "slip_velocity": "m/s",
    "friction_force_lateral": "N",
    "slip_velocity_lateral": "m/s",
}
ENERGY_TERMS = (
    "kinetic", "potential", "elastic", "dissipated_normal", "dissipated_friction", "push_work", "residual",
)  # fmt: skip
VIOLATION_UNITS = {"position": "m", "velocity": "m/s", "normalization": "1"}


@dataclass(repr=False)  # RunResult.__repr__: one line, not every array
class CompliantRunResult(RunResult):
    """A compliant simulation and what it measured.

    The integration and its step table are computed by :func:`simulate_compliant`; everything measured over the
    samples (energy audit, constraint drift, contact channels, hip, attitude) and the summary built from them
    are computed the first time something asks (a study that reads the steps pays for no channel).
    """

    config: Config
    model: BuiltModel
    run: Integration
    steps: StepTable
    wall_time_s: float
    status: str = "walking"  # the loop's: 'walking', 'fell', 'diverged' (integrate.blowup) or 'timeout'
    status_reason: str | None = None
    stop_time: float | None = None  # time of the fall, the divergence or the timeout

    @property
    def t_final(self) -> float:
        """The last simulated time [s]."""
        return self.run.t_final

    @cached_property
    def energy(self) -> EnergyAudit:
        """The energy audit at the samples."""
        return energy_audit(self.model, self.run)

    @cached_property
    def violation(self) -> np.ndarray:
        """(ns, 2) ||Phi||, ||Phidot|| (spatial: (ns, 3), + ||p.p - 1||) at the samples."""
        return constraint_drift(self.model, self.run)

    def energy_dissipated(self) -> dict[str, float]:
        """The work dissipated over the run [J] by normal damping, friction and (walkers with joint stops or
        elements) the stops' damping and the elements: the integrated work states (no energy audit needed)."""
        layout = formulation_of(self.model.system).layout_of(self.model.system)
        work = {"normal": layout.work_normal, "friction": layout.work_friction, "stops": layout.work_stop,
                "elements": layout.work_element}  # fmt: skip
        y = self.run.y
        return {name: float(y[-1, k] - y[0, k]) for name, k in work.items() if k is not None}

    def peak_normal_force(self) -> float | None:
        """The largest normal force of any foot at the samples [N] (None without samples)."""
        return contact_peaks(self.contact)["peak_normal_force"]

    @cached_property
    def summary(self) -> dict[str, Any]:
        """The summary.json content (plain JSON data)."""
        return json_safe(summarize(self))

    @cached_property
    def contact(self) -> dict[str, np.ndarray]:
        """Per-foot contact channels at the samples (penetration, forces, slip velocities), (ns, nf) each."""
        return contact_channels(self.model, self.run)

    @cached_property
    def hip(self) -> np.ndarray:
        """(ns, 2) or, spatial, (ns, 3) hip position in the slope frame [m]."""
        return hip_position(self.model, self.run)

    @cached_property
    def attitude(self) -> dict[str, np.ndarray]:
        """Spatial runs: per-body pitch, roll, yaw [rad] and pitch rate [rad/s]; empty for planar runs."""
        return attitude_channels(self.model, self.run)

    def integrity_text(self) -> str:
        return f"|Phi| <= {self.summary['constraint_violation_max']['position']:.1e} m"

    def trajectory(self) -> TrajectoryFile:
        run, model = self.run, self.model
        channels = [Channel(f"contact/{name}", values, CHANNEL_UNITS[name]) for name, values in self.contact.items()]
        channels.append(Channel("contact/modes", run.modes, "armed (1/0), touching (1/0), impact velocity (m/s)"))
        joints = [name for name, rows in (("dissipated_stops", model.system.stops), ("dissipated_elements",
                  model.system.elements)) if rows.law.shape[0]]  # fmt: skip  # W_stop, W_element: walkers with them
        channels += [Channel(f"energy/{name}", getattr(self.energy, name), "J") for name in (*ENERGY_TERMS, *joints)]
        channels += [
            Channel(f"constraints/{name}", self.violation[:, k], VIOLATION_UNITS[name])
            for k, name in enumerate(violation_names(model))
        ]
        channels.append(Channel("hip", self.hip, "m"))
        channels += [
            Channel(f"attitude/{name}", values, "rad/s" if name == "pitch_rate" else "rad")
            for name, values in self.attitude.items()
        ]
        channels += [
            Channel(f"steps/{name}", getattr(self.steps, name), units, False) for name, units in self.steps.columns
        ]
        channels.append(Channel("events/contact_log", run.contact_log, "s, index, +1/-1, m/s", False))
        group_attrs: dict[str, dict[str, Any]] = {"contact": {"feet": model.foot_names}}
        if self.attitude:
            group_attrs["attitude"] = {"bodies": model.body_names}
        return TrajectoryFile(
            run.t, "s", run.y, model.state_names(), "SI (see state_names)", channels, group_attrs=group_attrs
        )


def energy_scale(model: BuiltModel, config: Config) -> float:
    """m g l [J]: the unit of the relative energy residual."""
    return model.total_mass * config.gravity * model.leg_length


def summarize(result: CompliantRunResult) -> dict[str, Any]:
    """The summary.json content."""
    run, config = result.run, result.config
    scale = energy_scale(result.model, config)
    return {
        "status": result.status,
        "status_reason": result.status_reason,
        "stop_time": result.stop_time,
        "t_end": run.t_final,
        **result.step_summary(),
        "energy_dissipated": result.energy_dissipated(),
        **push_summary(config, [{"work": work} for work in result.run.pushes[:, 2]]),
        "energy_residual_max": float(np.max(np.abs(result.energy.residual))),
        "energy_residual_max_relative": float(np.max(np.abs(result.energy.residual)) / scale),
        "constraint_violation_max": {
            name: float(np.max(result.violation[:, k])) for k, name in enumerate(violation_names(result.model))
        },
        **contact_peaks(result.contact),
        **lateral_summary(result.attitude, result.contact),
        "rhs_evals": run.rhs_evals,
        "accepted_steps": run.accepted_steps,
        "rejected_steps": run.rejected_steps,
        "events": run.events,
        "wall_time_s": result.wall_time_s,
        "integrator": config.integrator.method,
        "config_hash": config.hash(),
        "version": package_version(),
    }


def integrate_config(config: Config, model: BuiltModel, progress: Callable[[float], None] | None = None) -> Integration:
    """The integration of a run: the built ``model`` of ``config`` over its time, pushes and budgets."""
    return integrate_model(
        model.system,
        model.y0,
        model.modes0,
        config.integrator,
        config.simulation.t_end,
        config.output.sample_rate,
        max_strikes=config.simulation.max_steps,
        progress=progress,
        deadline=wall_deadline(config),
        pushes=ordered_pushes(config),
        checks=Scales(energy_scale(model, config), model.leg_length),
    )


def simulate_compliant(
    config: Config, model: BuiltModel, progress: Callable[[float], None] | None = None
) -> CompliantRunResult:
    """Integrate the built ``model`` of ``config`` and take its step table; writes nothing (the other measures
    are computed when asked)."""
    start = time.perf_counter()
    run = integrate_config(config, model, progress)
    wall = time.perf_counter() - start
    return CompliantRunResult(
        config=config,
        model=model,
        run=run,
        steps=step_table(model, run),
        wall_time_s=wall,
        status=run.status,
        status_reason=run.stop_reason if run.fall_code is None else fall_reason(run.fall_code, model.body_names),
        stop_time=run.stop_time,
    )
