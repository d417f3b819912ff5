"""Small sample models and input files, for tests and examples (in the spirit of pydy's ``models``).

The bundled configs walk for 10-15 simulated seconds; most behaviours (a run's files, a heel strike,
a sweep's table, a report's figures) show in the first few steps. These builders give the smallest
inputs that still show them, so that the fast test tier stays fast and examples stay short:

- :func:`default_walker`: the default walker of ``configs/round_foot_walker.yaml`` (the schema
  defaults) for :data:`SHORT_T_END` seconds, four heel strikes;
- :func:`pendulum`: a hinged rod without contact, a smooth problem for integrator orders;
- :func:`write_config`, :func:`write_sweep` and :func:`write_tiny_sweep`: config and sweep files for the
  command line, the sweep runner and the report (:func:`write_tiny_sweep` varies every axis the
  report compares in :data:`TINY_SWEEP_RUNS` short runs);
- :func:`write_reference`: a step-period reference file with FICTITIOUS numbers.

Nothing here is a physical reference: the numbers are chosen to be cheap, not to be measurements.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from biped_sim.config import Config, config_from_dict
from biped_sim.multibody.planar import PlanarSystem

SHORT_T_END = 2.0  # [s] the default walker's first four heel strikes (the first at 0.39 s)
TINY_SWEEP_T_END = 1.3  # [s] three heel strikes per run of the tiny sweep
TINY_SWEEP_DT = 5e-5  # [s] rk2's step: at 1e-4 s the LuGre bristles are beyond its stability limit and it falls
TINY_SWEEP_SLOPES = (0.015, 0.02)
TINY_SWEEP_METHODS = ("dopri5", "rk2")
TINY_SWEEP_ZIP: dict[str, list[Any]] = {  # moved together: two model variants
    "contact.model": ["flores", "hunt_crossley"],
    "friction.model": ["ambrosio", "lugre"],  # both cheap: the stiff laws (coulomb, threlfall) cost 10x more
    "formulation.baumgarte.alpha": [10.0, 0.0],
    "formulation.baumgarte.beta": [10.0, 0.0],
}
TINY_SWEEP_RUNS = len(TINY_SWEEP_SLOPES) * len(TINY_SWEEP_METHODS) * 2


def default_walker(*overrides: str, t_end: float | None = SHORT_T_END) -> Config:
    """The default walker for ``t_end`` seconds (None: the schema's 15 s), with ``--set``-style overrides.

    The schema's defaults are the walker of ``configs/round_foot_walker.yaml``: the same motion bit for
    bit, though not the same config hash (the file spells out the default contact materials).
    """
    sets = [] if t_end is None else [f"simulation.t_end={t_end!r}"]
    return config_from_dict({}, [*sets, *overrides])


def pendulum(amplitude: float = 0.1, length: float = 1.0, mass: float = 1.0) -> tuple[PlanarSystem, np.ndarray]:
    """A uniform rod hinged to the ground at its end, released at rest ``amplitude`` rad from hanging.

    One body, one revolute joint, no feet and so no contact: a smooth problem whose small swings are
    nearly linear, for measuring the convergence order of the integrators. Returns the system and its
    initial state (position and velocity of the body, two Baumgarte terms).
    """
    system = PlanarSystem(
        body_mass=np.array([mass]),
        body_inertia=np.array([mass * length**2 / 12.0]),
        joint_bodies=np.array([[0, -1]], dtype=np.int64),
        joint_points=np.array([[0.0, 0.5 * length, 0.0, 0.0]]),
        foot_body=np.zeros(0, dtype=np.int64),
        foot_center=np.zeros((0, 2)),
        foot_radius=np.zeros(0),
        foot_partner=np.zeros(0, dtype=np.int64),
        gravity=np.array([0.0, -9.81]),
        baumgarte=np.array([10.0, 10.0]),
        normal_params=np.zeros(4),
        friction_params=np.zeros(10),
        switches=np.zeros(3, dtype=np.int64),
        limits=np.array([1e-3, -math.inf, math.inf, 0.0]),
    )
    centre = 0.5 * length * np.array([math.sin(amplitude), -math.cos(amplitude)])
    y0 = np.array([*centre, amplitude, 0.0, 0.0, 0.0, 0.0, 0.0])
    return system, y0


def write_config(path: Path, config: Config | None = None) -> Path:
    """Write ``config`` (default: :func:`default_walker`) as a fully resolved YAML config file at ``path``."""
    path.write_text((config or default_walker()).to_yaml())
    return path


def write_sweep(
    directory: Path,
    name: str = "tiny",
    *,
    base: Path | None = None,
    set_: dict[str, Any] | None = None,
    grid: dict[str, Any] | None = None,
    zip_: dict[str, list[Any]] | None = None,
) -> Path:
    """Write the sweep file ``directory/<name>.yaml`` and return its path.

    ``base`` is the config file the runs start from; without one, :func:`default_walker` is written
    next to the sweep file as ``<name>_base.yaml``. ``set_``, ``grid`` and ``zip_`` are the sweep
    file's ``set``, ``grid`` and ``zip`` sections (each left out when empty).
    """
    if base is None:
        base = write_config(directory / f"{name}_base.yaml")
    data: dict[str, Any] = {"name": name, "base": str(base)}
    for key, section in (("set", set_), ("grid", grid), ("zip", zip_)):
        if section:
            data[key] = section
    path = directory / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def write_tiny_sweep(directory: Path, name: str = "tiny", base: Path | None = None) -> Path:
    """A sweep that varies every axis the report compares, in :data:`TINY_SWEEP_RUNS` runs of 1.3 s.

    Slopes and integrators form the grid; contact law, friction law and Baumgarte gains move
    together (zip). Every run walks three steps.
    """
    return write_sweep(
        directory,
        name,
        base=base,
        set_={"simulation.t_end": TINY_SWEEP_T_END, "integrator.dt": TINY_SWEEP_DT},
        grid={"ground.slope": list(TINY_SWEEP_SLOPES), "integrator.method": list(TINY_SWEEP_METHODS)},
        zip_=TINY_SWEEP_ZIP,
    )


def write_reference(path: Path, values: list[float], **extra: Any) -> Path:
    """A step-period reference file at ``path`` with FICTITIOUS ``values`` [s] (test data, not a measurement).

    ``extra`` adds or replaces top-level fields (``std``, ``steps``, ``published_errors``, ...).
    """
    data = {
        "experiment": "liu_round_foot_walker",
        "description": "FICTITIOUS step periods for tests; not a measurement",
        "citation": {"authors": ["A. Tester"], "title": "Test data", "year": 2024},
        "source": {"kind": "table", "label": "Table 0"},
        "quantity": {"name": "step_period", "unit": "s", "statistic": "mean", "n_trials": 3},
        "values": values,
        **extra,
    }
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path
