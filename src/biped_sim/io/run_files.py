"""Writing a run directory: trajectory.h5, summary.json, steps.csv and config.yaml, each atomically.

HDF5 layout (readable with plain h5py; ``time`` is a dimension scale so xarray sees named dims):

    /time                      (ns,)         s
    /state                     (ns, ny)      mixed units, names in /state_names
    /state_names               (ny,)         strings
    /contact/penetration       (ns, nf)      m
    /contact/normal_force      (ns, nf)      N
    /contact/friction_force    (ns, nf)      N
    /contact/slip_velocity     (ns, nf)      m/s
    /contact/{friction_force_lateral,slip_velocity_lateral}   (ns, nf)   N, m/s   (spatial only: along z)
    /contact/modes             (ns, nf, 4)   armed, touching, remembered impact velocity, last lift-off time
    /energy/{kinetic,potential,elastic,dissipated_normal,dissipated_friction,push_work,residual}  (ns,) J
    /constraints/position, /constraints/velocity   (ns,)  m, m/s
    /constraints/normalization (ns,)         ||p.p - 1|| over the bodies (spatial only)
    /hip                       (ns, 2)       m (spatial: (ns, 3), x, y, z)
    /attitude/{pitch,roll,yaw} (ns, nb)      rad (spatial only: leg angle, lateral rocking, heading drift)
    /attitude/pitch_rate       (ns, nb)      rad/s (spatial only: leg angular rate about the lateral axis)
    /steps/{strike_time,foot,period,length,slip,stance_angle,stance_rate,swing_angle,swing_rate}
    /events/contact_log        (nl, 4)       time, foot, +1 touchdown / -1 lift-off, approach velocity

Root attributes: config (resolved YAML), config_hash, status, version, git_commit, git_dirty, created,
library versions. Every dataset carries a ``units`` attribute. This module writes whatever a run result
describes (:class:`TrajectoryFile`); the layouts above are those of the two result types in
:mod:`biped_sim.simulate`.

A rigid run (``dynamics: rigid``, :mod:`biped_sim.simulate.rigid`; root attribute ``dynamics = "rigid"``) has no
contact, constraint or event data (contact is a rolling constraint and heel strike an impact map):

    /time                      (ns,)         s
    /state                     (ns, ny)      the walker's reduced state, names in /state_names (legs relabelled
                                             at each strike: 'stance' is the current stance leg)
    /state_names               (ny,)         strings
    /energy/{kinetic,potential,dissipated_impact,dissipated_elements,push_work,residual}  (ns,) J
    /hip                       (ns, 2)       m
    /steps/{strike_time,foot,period,length,slip,stance_angle,stance_rate,swing_angle,swing_rate}
                                             touchdown (pre-impact) angles and rates, as compliant runs record them
    /strikes/time              (n,)          s
    /strikes/pre_impact, /strikes/post_impact   (n, ny)   state just before and just after each strike

A rigid run of a walker in space also has ``/attitude/{pitch,roll,yaw,pitch_rate}`` (ns, 2), its left and right
legs' as a spatial run's bodies', its ``/hip`` is (ns, 3) and its steps have the lateral columns.

Its units are SI except for the simplest walker, nondimensional ("1 (g = l = 1)" for time, lengths, rates
and energies), and the rimless wheel's energies, in J per kg of hub mass ("J/kg").
"""

from __future__ import annotations

import io
import json
import shutil
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from biped_sim.io.atomic import remove_stale_temporaries, write_json_atomic, write_text_atomic, write_with
from biped_sim.io.provenance import provenance

DERIVED_DIR = "figures"  # what `biped-sim plot` draws from a run, beside its files


@dataclass(frozen=True)
class Channel:
    """One dataset: its path in the file ('contact/normal_force'), values, units, and whether it is per sample."""

    path: str
    data: np.ndarray
    units: str
    per_sample: bool = True  # attach the ``time`` dimension scale to its first axis


@dataclass
class TrajectoryFile:
    """What a run puts in trajectory.h5: the sampled state, named channels, group and root attributes."""

    time: np.ndarray
    time_units: str
    state: np.ndarray
    state_names: Sequence[str]
    state_units: str
    channels: list[Channel]
    group_attrs: dict[str, dict[str, Any]] = field(default_factory=dict)
    root_attrs: dict[str, str] = field(default_factory=dict)


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


def _group(f: h5py.File, path: str) -> tuple[h5py.Group, str]:
    """The group holding ``path`` (created in insertion order on first use) and the dataset's own name."""
    parent, _, name = path.rpartition("/")
    if not parent:
        return f, name
    if parent not in f:
        f.create_group(parent, track_order=True)
    return f[parent], name


def trajectory_image(trajectory: TrajectoryFile, config_yaml: str, config_hash: str, status: str) -> bytes:
    """The bytes of trajectory.h5: provenance and config as root attributes, ``time`` as dimension scale.

    The file is built in memory: HDF5 itself never writes to the disk, so that a full disk or a failing
    device is one Python OSError at :func:`write_trajectory`, not a crash inside the HDF5 library.
    """
    buffer = io.BytesIO()
    with h5py.File(buffer, "w", track_order=True) as f:
        for key, value in provenance().items():
            f.attrs[key] = value
        f.attrs["config"] = config_yaml
        f.attrs["config_hash"] = config_hash
        f.attrs["status"] = status
        for key, value in trajectory.root_attrs.items():
            f.attrs[key] = value
        time_ds = f.create_dataset("time", data=trajectory.time, track_times=False)
        time_ds.attrs["units"] = trajectory.time_units
        time_ds.make_scale("time")
        _dataset(f, "state", trajectory.state, trajectory.state_units, time_ds)
        names = np.array(list(trajectory.state_names), dtype=h5py.string_dtype())
        f.create_dataset("state_names", data=names, track_times=False).attrs["units"] = "none (names)"
        for channel in trajectory.channels:
            group, name = _group(f, channel.path)
            _dataset(group, name, channel.data, channel.units, time_ds if channel.per_sample else None)
        for group_name, attrs in trajectory.group_attrs.items():
            for key, value in attrs.items():
                f[group_name].attrs[key] = value
    return buffer.getvalue()


def write_trajectory(path: Path, trajectory: TrajectoryFile, config_yaml: str, config_hash: str, status: str) -> None:
    """Write trajectory.h5 atomically (the file built in memory by :func:`trajectory_image`)."""
    image = trajectory_image(trajectory, config_yaml, config_hash, status)
    write_with(path, lambda tmp: tmp.write_bytes(image))


def start_run_directory(out_dir: Path) -> None:
    """Make ``out_dir`` ready for a new write: create it, remove the completion marker (summary.json) first, then
    the temporary files a killed write left and the figures drawn from the old run (``figures/``).

    From then until summary.json is written again the directory reads as unfinished, so a write that dies
    half-way never leaves an old summary beside new data files.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "summary.json").unlink(missing_ok=True)
    remove_stale_temporaries(out_dir)
    shutil.rmtree(out_dir / DERIVED_DIR, ignore_errors=True)  # figures of the old run


def previous_run(out_dir: Path) -> str | None:
    """'the run of config 1a2b..., status walking' when ``out_dir`` holds a finished run (None otherwise)."""
    try:
        summary = json.loads((out_dir / "summary.json").read_text())
        return f"the run of config {summary['config_hash']}, status {summary['status']}"
    except (OSError, ValueError, KeyError, TypeError):
        return None


def write_run_directory(
    out_dir: Path,
    trajectory: TrajectoryFile,
    *,
    config_yaml: str,
    config_hash: str,
    status: str,
    steps_csv: str,
    summary: dict[str, Any],
) -> None:
    """Write the four files of a run directory, each atomically: the old summary.json is removed first and the
    new one written last (it marks completion)."""
    start_run_directory(out_dir)
    write_trajectory(out_dir / "trajectory.h5", trajectory, config_yaml, config_hash, status)
    write_text_atomic(out_dir / "steps.csv", steps_csv)
    write_text_atomic(out_dir / "config.yaml", config_yaml)
    write_json_atomic(out_dir / "summary.json", summary)
