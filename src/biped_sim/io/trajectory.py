"""Reading a finished run directory back: trajectory.h5 (layout in :mod:`biped_sim.io.run_files`) and summary.json.

Figures, animations, reports and comparisons all read runs through :func:`load_run`, so a run
directory is the one interface between simulating and presenting. A rigid run (``dynamics: rigid``) reads as
one too (``RunData.dynamics``): its state holds the angles and rates in role order, its energy terms are the
rigid model's, it has no contact channels (no columns) and its constraints hold exactly (zeros).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from biped_sim.config import Config, config_from_dict, parse_yaml
from biped_sim.errors import ConfigError


@dataclass
class RunData:
    """The arrays of one run, in the slope frame (x downhill along the slope, y along its normal)."""

    run_dir: Path
    config: Config
    summary: dict[str, Any]
    time: np.ndarray  # (ns,) s
    state: np.ndarray  # (ns, ny)
    state_names: list[str]
    normal_force: np.ndarray  # (ns, nf) N
    friction_force: np.ndarray  # (ns, nf) N
    penetration: np.ndarray  # (ns, nf) m
    energy: dict[str, np.ndarray]  # kinetic, potential, elastic, dissipated_*, push_work, residual
    violation_position: np.ndarray  # (ns,) m
    violation_velocity: np.ndarray  # (ns,) m/s
    hip: np.ndarray  # (ns, 2) m; spatial runs (ns, 3) with z lateral
    steps: dict[str, np.ndarray]  # strike_time, foot, period, length, slip, ...
    violation_normalization: np.ndarray | None = None  # (ns,) ||p.p - 1||, spatial runs only
    attitude: dict[str, np.ndarray] | None = None  # pitch, roll, yaw [rad], pitch_rate [rad/s] (ns, nb), in space only
    dynamics: str = "compliant"  # or 'rigid'
    attitude_bodies: list[str] | None = None  # the attitudes' columns: the bodies the run wrote (in space only)

    def column(self, name: str) -> np.ndarray:
        """One state entry over time, by name (e.g. 'phi_leg0')."""
        try:
            return self.state[:, self.state_names.index(name)]
        except ValueError:
            raise ConfigError(str(self.run_dir), f"trajectory.h5 has no state {name!r}") from None

    def leg_angles(self) -> np.ndarray:
        """(ns, nb) sagittal leg angle of each body [rad]: phi (planar), the pitch (spatial), or a rigid run's angle
        of each role (stance, swing: the legs swap at each heel strike)."""
        if self.attitude is not None:
            return self.attitude["pitch"]
        if self.dynamics == "rigid":
            return np.column_stack([self.column(f"{role}_angle") for role in self.body_names])
        return np.column_stack([self.column(f"phi_{body}") for body in self.body_names])

    def leg_rates(self) -> np.ndarray:
        """(ns, nb) sagittal leg angular rate of each body (rigid: each role) [rad/s]."""
        if self.attitude is not None:
            return self.attitude["pitch_rate"]
        if self.dynamics == "rigid":
            return np.column_stack([self.column(f"{role}_rate") for role in self.body_names])
        return np.column_stack([self.column(f"omega_{body}") for body in self.body_names])

    @property
    def body_names(self) -> list[str]:
        """Bodies in state order: those of the attitudes' columns (a run in space), from the 'phi_<body>' entries
        (planar, minimal), else the 'x_<body>' ones (spatial; minimal-coordinate states also hold 'x_hip', which is no
        body); a rigid run's roles ('<role>_angle')."""
        if self.attitude_bodies is not None:
            return list(self.attitude_bodies)
        if self.dynamics == "rigid":
            return [name.removesuffix("_angle") for name in self.state_names if name.endswith("_angle")]
        planar = [name[4:] for name in self.state_names if name.startswith("phi_")]
        return planar or [name[2:] for name in self.state_names if name.startswith("x_")]

    @property
    def label(self) -> str:
        return self.run_dir.name


def _first_line(exc: BaseException) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0]


def load_summary(run_dir: Path) -> dict[str, Any]:
    """summary.json of a finished run; ConfigError if the directory holds no finished run or the file is damaged."""
    path = run_dir / "summary.json"
    if not path.is_file():
        raise ConfigError(str(run_dir), "not a finished run directory (no summary.json)")
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError) as exc:  # ValueError: truncated or not JSON (JSONDecodeError, UnicodeDecodeError)
        raise ConfigError(str(path), f"damaged or truncated ({_first_line(exc)})") from None
    if not isinstance(summary, dict):
        raise ConfigError(str(path), "damaged: not a run summary")
    return summary


def trajectory_problem(path: Path, config_hash: str) -> str | None:
    """Why the trajectory.h5 at ``path`` cannot be the result of the config with ``config_hash``, or None.

    Opens the file and reads its metadata (every group and dataset header, which HDF5 writes last), not its
    data: cheap enough to check every finished run when a sweep resumes.
    """
    try:
        with h5py.File(path, "r") as f:
            if f.attrs.get("config_hash") != config_hash:
                return "trajectory.h5 of another config"
            f.visititems(lambda name, item: None)
    except (OSError, KeyError, RuntimeError, ValueError) as exc:
        return "trajectory.h5 missing" if not path.exists() else f"trajectory.h5 unreadable ({_first_line(exc)})"
    return None


def load_run(run_dir: str | Path) -> RunData:
    """Read a finished run directory (ConfigError if it is not one, or if its files are damaged)."""
    run_dir = Path(run_dir)
    summary = load_summary(run_dir)
    path = run_dir / "trajectory.h5"
    if not path.is_file():
        raise ConfigError(str(run_dir), "no trajectory.h5 in the run directory")
    try:
        return _read_trajectory(run_dir, path, summary)
    except ConfigError:
        raise
    except (OSError, KeyError, RuntimeError, ValueError) as exc:  # what h5py raises on a truncated or damaged file
        raise ConfigError(str(path), f"damaged or truncated ({_first_line(exc)})") from None


def _read_trajectory(run_dir: Path, path: Path, summary: dict[str, Any]) -> RunData:
    """The arrays of a run's trajectory.h5 (h5py's own errors are turned into one line by the caller)."""
    with h5py.File(path, "r") as f:
        config = config_from_dict(parse_yaml(f.attrs["config"], source=f"{path}:config"))
        if f.attrs.get("dynamics") == "rigid":
            return _rigid_run(run_dir, f, config, summary)
        return RunData(
            run_dir=run_dir,
            config=config,
            summary=summary,
            time=f["time"][:],
            state=f["state"][:],
            state_names=list(f["state_names"].asstr()[:]),
            normal_force=f["contact/normal_force"][:],
            friction_force=f["contact/friction_force"][:],
            penetration=f["contact/penetration"][:],
            energy={name: ds[:] for name, ds in f["energy"].items()},
            violation_position=f["constraints/position"][:],
            violation_velocity=f["constraints/velocity"][:],
            hip=f["hip"][:],
            steps={name: ds[:] for name, ds in f["steps"].items()},
            violation_normalization=f["constraints/normalization"][:] if "normalization" in f["constraints"] else None,
            attitude={name: ds[:] for name, ds in f["attitude"].items()} if "attitude" in f else None,
            attitude_bodies=_attitude_bodies(f),
        )


def _attitude_bodies(f: h5py.File) -> list[str] | None:
    """The bodies of the attitudes' columns (the group's ``bodies`` attribute), None without them (a planar run)."""
    if "attitude" not in f or "bodies" not in f["attitude"].attrs:
        return None
    return [str(name) for name in f["attitude"].attrs["bodies"]]


def _rigid_run(run_dir: Path, f: h5py.File, config: Config, summary: dict[str, Any]) -> RunData:
    """A rigid run's arrays: no contact channels (no feet's columns), constraints exact (zeros)."""
    time = f["time"][:]
    no_feet, zeros = np.zeros((len(time), 0)), np.zeros(len(time))
    return RunData(
        run_dir=run_dir,
        config=config,
        summary=summary,
        time=time,
        state=f["state"][:],
        state_names=list(f["state_names"].asstr()[:]),
        normal_force=no_feet,
        friction_force=no_feet,
        penetration=no_feet,
        energy={name: ds[:] for name, ds in f["energy"].items()},
        violation_position=zeros,
        violation_velocity=zeros,
        hip=f["hip"][:],
        steps={name: ds[:] for name, ds in f["steps"].items()},
        attitude={name: ds[:] for name, ds in f["attitude"].items()} if "attitude" in f else None,
        dynamics="rigid",
        attitude_bodies=_attitude_bodies(f),
    )
