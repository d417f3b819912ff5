"""Writing and reading a run directory: trajectory.h5, summary.json, steps.csv.

HDF5 layout (readable with plain h5py; ``time`` is a dimension scale so xarray sees named dims):

    /time                      (ns,)         s
    /state                     (ns, ny)      mixed units, names in /state_names
    /state_names               (ny,)         strings
    /contact/penetration       (ns, nf)      m
    /contact/normal_force      (ns, nf)      N
    /contact/friction_force    (ns, nf)      N
    /contact/slip_velocity     (ns, nf)      m/s
    /contact/modes             (ns, nf, 3)   armed, touching, remembered impact velocity
    /energy/{kinetic,potential,elastic,dissipated_normal,dissipated_friction,residual}  (ns,) J
    /constraints/position, /constraints/velocity   (ns,)  m, m/s
    /hip                       (ns, 2)       m
    /steps/{strike_time,foot,period,length,slip,stance_angle,stance_rate,swing_angle,swing_rate}
    /events/contact_log        (nl, 4)       time, foot, +1 touchdown / -1 lift-off, approach velocity

Root attributes: config (resolved YAML), config_hash, version, git_commit, git_dirty, created,
library versions. Every dataset carries a ``units`` attribute.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import h5py
import numpy as np

from biped_sim.analysis.gait import contact_channels, hip_position
from biped_sim.io.atomic import write_json_atomic, write_text_atomic, write_with
from biped_sim.io.provenance import provenance
from biped_sim.simulate import RunResult

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


def write_trajectory(result: RunResult, path: Path) -> None:
    """Write trajectory.h5 (atomically)."""
    run, model = result.run, result.model
    channels = contact_channels(model, run)
    names = model.state_names()

    def writer(tmp: Path) -> None:
        with h5py.File(tmp, "w", track_order=True) as f:
            for key, value in provenance().items():
                f.attrs[key] = value
            f.attrs["config"] = result.config.to_yaml()
            f.attrs["config_hash"] = result.config.hash()
            f.attrs["status"] = run.status
            time_ds = f.create_dataset("time", data=run.t, track_times=False)
            time_ds.attrs["units"] = "s"
            time_ds.make_scale("time")
            _dataset(f, "state", run.y, "SI (see state_names)", time_ds)
            f.create_dataset("state_names", data=np.array(names, dtype=h5py.string_dtype()), track_times=False)
            contact = f.create_group("contact", track_order=True)
            for name, units in (
                ("penetration", "m"),
                ("normal_force", "N"),
                ("friction_force", "N"),
                ("slip_velocity", "m/s"),
            ):
                _dataset(contact, name, channels[name], units, time_ds)
            _dataset(contact, "modes", run.modes, "armed (1/0), touching (1/0), impact velocity (m/s)", time_ds)
            contact.attrs["feet"] = model.foot_names
            energy = f.create_group("energy", track_order=True)
            audit = result.energy
            for name in ("kinetic", "potential", "elastic", "dissipated_normal", "dissipated_friction", "residual"):
                _dataset(energy, name, getattr(audit, name), "J", time_ds)
            constraints = f.create_group("constraints", track_order=True)
            _dataset(constraints, "position", result.violation[:, 0], "m", time_ds)
            _dataset(constraints, "velocity", result.violation[:, 1], "m/s", time_ds)
            _dataset(f, "hip", hip_position(model, run), "m", time_ds)
            steps = f.create_group("steps", track_order=True)
            for name, units in STEP_COLUMNS:
                _dataset(steps, name, getattr(result.steps, name), units, None)
            events = f.create_group("events")
            _dataset(events, "contact_log", run.contact_log, "s, index, +1/-1, m/s", None)

    write_with(path, writer)


def steps_csv(result: RunResult) -> str:
    """steps.csv: one row per heel strike (the step it begins)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["step"] + [f"{name} [{units}]" if units != "1" else name for name, units in STEP_COLUMNS])
    s = result.steps
    for k in range(len(s.strike_time)):
        row = [k + 1]
        for name, _ in STEP_COLUMNS:
            value = getattr(s, name)[k]
            row.append(int(value) if name == "foot" else ("" if not np.isfinite(value) else repr(float(value))))
        writer.writerow(row)
    return buffer.getvalue()


def write_run(result: RunResult, out_dir: Path) -> None:
    """Write the three files of a run directory, each atomically; summary.json last (it marks completion)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    write_trajectory(result, out_dir / "trajectory.h5")
    write_text_atomic(out_dir / "steps.csv", steps_csv(result))
    write_text_atomic(out_dir / "config.yaml", result.config.to_yaml())
    write_json_atomic(out_dir / "summary.json", result.summary)
