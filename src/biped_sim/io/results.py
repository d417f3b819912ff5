"""Writing and reading a run directory: trajectory.h5, summary.json, steps.csv.

HDF5 layout (readable with plain h5py; ``time`` is a dimension scale so xarray sees named dims):

    /time                      (ns,)         s
    /state                     (ns, ny)      mixed units, names in /state_names
    /state_names               (ny,)         strings
    /contact/penetration       (ns, nf)      m
    /contact/normal_force      (ns, nf)      N
    /contact/friction_force    (ns, nf)      N
    /contact/slip_velocity     (ns, nf)      m/s
    /contact/{friction_force_lateral,slip_velocity_lateral}   (ns, nf)   N, m/s   (spatial only: along z)
    /contact/modes             (ns, nf, 3)   armed, touching, remembered impact velocity
    /energy/{kinetic,potential,elastic,dissipated_normal,dissipated_friction,residual}  (ns,) J
    /constraints/position, /constraints/velocity   (ns,)  m, m/s
    /constraints/normalization (ns,)         ||p.p - 1|| over the bodies (spatial only)
    /hip                       (ns, 2)       m (spatial: (ns, 3), x, y, z)
    /attitude/{pitch,roll,yaw} (ns, nb)      rad (spatial only: leg angle, lateral rocking, heading drift)
    /attitude/pitch_rate       (ns, nb)      rad/s (spatial only: leg angular rate about the lateral axis)
    /steps/{strike_time,foot,period,length,slip,stance_angle,stance_rate,swing_angle,swing_rate}
    /events/contact_log        (nl, 4)       time, foot, +1 touchdown / -1 lift-off, approach velocity

Root attributes: config (resolved YAML), config_hash, status, version, git_commit, git_dirty, created,
library versions. Every dataset carries a ``units`` attribute.

A rigid run (``dynamics: rigid``, :mod:`biped_sim.rigid.run`; root attribute ``dynamics = "rigid"``) has no
contact, constraint or event data (contact is a rolling constraint and heel strike an impact map):

    /time                      (ns,)         s
    /state                     (ns, ny)      the walker's reduced state, names in /state_names (legs relabelled
                                             at each strike: 'stance' is the current stance leg)
    /state_names               (ny,)         strings
    /energy/{kinetic,potential,dissipated_impact,residual}  (ns,) J
    /hip                       (ns, 2)       m
    /steps/{strike_time,foot,period,length,slip,stance_angle,stance_rate,swing_angle,swing_rate}
                                             touchdown (pre-impact) angles and rates, as compliant runs record them
    /strikes/time              (n,)          s
    /strikes/pre_impact, /strikes/post_impact   (n, ny)   state just before and just after each strike

Its units are SI except for the simplest walker, nondimensional ("1 (g = l = 1)" for time, lengths, rates
and energies), and the rimless wheel's energies, in J per kg of hub mass ("J/kg").
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import h5py
import numpy as np

from biped_sim.analysis.gait import attitude_channels, contact_channels, hip_position, violation_names
from biped_sim.io.atomic import write_json_atomic, write_text_atomic, write_with
from biped_sim.io.provenance import provenance
from biped_sim.rigid.run import RigidRunResult
from biped_sim.simulate import RunResult

CHANNEL_UNITS = {
    "penetration": "m",
    "normal_force": "N",
    "friction_force": "N",
    "slip_velocity": "m/s",
    "friction_force_lateral": "N",
    "slip_velocity_lateral": "m/s",
}
STEP_COLUMNS = (
    ("strike_time", "s"),
    ("foot", "1"),
    ("period", "s"),
    ("length", "m"),
    ("slip", "m"),
    ("stance_angle", "rad"),
    ("stance_rate", "rad/s"),
    ("swing_angle", "rad"),
    ("swing_rate", "rad/s"),
)


def _dataset(group: h5py.Group, name: str, data: np.ndarray, units: str, time_scale: h5py.Dataset | None) -> None:
    data = np.asarray(data)
    kwargs = {}
    if data.ndim >= 1 and data.shape[0] > 0:
        chunks = (min(4096, data.shape[0]), *data.shape[1:])
        kwargs = {"compression": "gzip", "compression_opts": 4, "shuffle": True, "chunks": chunks}
    ds = group.create_dataset(name, data=data, track_times=False, **kwargs)
    ds.attrs["units"] = units
    if time_scale is not None and data.ndim >= 1 and data.shape[0] == time_scale.shape[0]:
        ds.dims[0].attach_scale(time_scale)


def _root(f: h5py.File, result: RunResult | RigidRunResult, time: np.ndarray) -> h5py.Dataset:
    """Provenance and config root attributes; the ``time`` dimension scale (returned)."""
    for key, value in provenance().items():
        f.attrs[key] = value
    f.attrs["config"] = result.config.to_yaml()
    f.attrs["config_hash"] = result.config.hash()
    f.attrs["status"] = result.status
    time_ds = f.create_dataset("time", data=time, track_times=False)
    time_ds.attrs["units"] = result.unit("s")
    time_ds.make_scale("time")
    return time_ds


def _state(
    f: h5py.File, state: np.ndarray, names: list[str] | tuple[str, ...], units: str, time_ds: h5py.Dataset
) -> None:
    """The sampled state and its column names."""
    _dataset(f, "state", state, units, time_ds)
    names_ds = f.create_dataset("state_names", data=np.array(names, dtype=h5py.string_dtype()), track_times=False)
    names_ds.attrs["units"] = "none (names)"


def _steps(f: h5py.File, result: RunResult | RigidRunResult) -> None:
    """The step table, one row per heel strike, in the run's units."""
    steps = f.create_group("steps", track_order=True)
    for name, units in STEP_COLUMNS:
        _dataset(steps, name, getattr(result.steps, name), result.unit(units), None)


def write_trajectory(result: RunResult, path: Path) -> None:
    """Write trajectory.h5 (atomically)."""
    run, model = result.run, result.model
    channels = contact_channels(model, run)

    def writer(tmp: Path) -> None:
        with h5py.File(tmp, "w", track_order=True) as f:
            time_ds = _root(f, result, run.t)
            _state(f, run.y, model.state_names(), "SI (see state_names)", time_ds)
            contact = f.create_group("contact", track_order=True)
            for name, values in channels.items():
                _dataset(contact, name, values, CHANNEL_UNITS[name], time_ds)
            _dataset(contact, "modes", run.modes, "armed (1/0), touching (1/0), impact velocity (m/s)", time_ds)
            contact.attrs["feet"] = model.foot_names
            energy = f.create_group("energy", track_order=True)
            audit = result.energy
            for name in ("kinetic", "potential", "elastic", "dissipated_normal", "dissipated_friction", "residual"):
                _dataset(energy, name, getattr(audit, name), "J", time_ds)
            constraints = f.create_group("constraints", track_order=True)
            _dataset(constraints, "position", result.violation[:, 0], "m", time_ds)
            _dataset(constraints, "velocity", result.violation[:, 1], "m/s", time_ds)
            if "normalization" in violation_names(model):
                _dataset(constraints, "normalization", result.violation[:, 2], "1", time_ds)
            _dataset(f, "hip", hip_position(model, run), "m", time_ds)
            attitude = attitude_channels(model, run)
            if attitude:
                group = f.create_group("attitude", track_order=True)
                for name, values in attitude.items():
                    _dataset(group, name, values, "rad/s" if name == "pitch_rate" else "rad", time_ds)
                group.attrs["bodies"] = model.body_names
            _steps(f, result)
            events = f.create_group("events")
            _dataset(events, "contact_log", run.contact_log, "s, index, +1/-1, m/s", None)

    write_with(path, writer)


def write_rigid_trajectory(result: RigidRunResult, path: Path) -> None:
    """Write a rigid run's trajectory.h5 (atomically; layout in the module docstring)."""
    angle_units, rate_units = result.unit("rad"), result.unit("rad/s")

    def writer(tmp: Path) -> None:
        with h5py.File(tmp, "w", track_order=True) as f:
            time_ds = _root(f, result, result.time)
            f.attrs["dynamics"] = "rigid"
            _state(
                f, result.state, result.walker.state_names, f"{angle_units}, {rate_units} (see state_names)", time_ds
            )
            energy = f.create_group("energy", track_order=True)
            for name in ("kinetic", "potential", "dissipated_impact", "residual"):
                _dataset(energy, name, getattr(result.energy, name), result.unit("J"), time_ds)
            _dataset(f, "hip", result.hip, result.unit("m"), time_ds)
            _steps(f, result)
            strikes = f.create_group("strikes", track_order=True)
            _dataset(strikes, "time", result.strike_time, result.unit("s"), None)
            for name, states in (("pre_impact", result.strike_pre), ("post_impact", result.strike_post)):
                _dataset(strikes, name, states, f"{angle_units}, {rate_units} (see state_names)", None)

    write_with(path, writer)


def steps_csv(result: RunResult | RigidRunResult) -> str:
    """steps.csv: one row per heel strike (the step it begins)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(
        ["step"] + [f"{name} [{result.unit(units)}]" if units != "1" else name for name, units in STEP_COLUMNS]
    )
    s = result.steps
    for k in range(len(s.strike_time)):
        row = [k + 1]
        for name, _ in STEP_COLUMNS:
            value = getattr(s, name)[k]
            row.append(int(value) if name == "foot" else ("" if not np.isfinite(value) else repr(float(value))))
        writer.writerow(row)
    return buffer.getvalue()


def write_run(result: RunResult | RigidRunResult, out_dir: Path) -> None:
    """Write the four files of a run directory, each atomically; summary.json last (it marks completion)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    if isinstance(result, RigidRunResult):
        write_rigid_trajectory(result, out_dir / "trajectory.h5")
    else:
        write_trajectory(result, out_dir / "trajectory.h5")
    write_text_atomic(out_dir / "steps.csv", steps_csv(result))
    write_text_atomic(out_dir / "config.yaml", result.config.to_yaml())
    write_json_atomic(out_dir / "summary.json", result.summary)
