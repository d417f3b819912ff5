"""The public API, pinned: what ``biped_sim`` and each of its packages export (their ``__all__``).

A rename, a removal or a new export fails here, so that it is a visible change (and the API reference,
generated from these lists by ``docs/apigen.py``, changes with it). A package that exports nothing is
used through its modules; it is listed with no names, so that a first export is visible too.
"""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType

import pytest

import biped_sim

EXPORTS: dict[str, list[str]] = {
    "biped_sim": ["Config", "ConfigError", "RunResult", "config_from_dict", "load_config", "run", "simulate"],
    "biped_sim.bench": [],
    "biped_sim.cli": [],
    "biped_sim.config": [
        "LEG_KEYS", "STATE_KEYS", "BaumgarteConfig", "BodySpec", "CompassWalker", "Config", "ContactConfig",
        "DescribedWalker", "FootSpec", "FormulationConfig", "FourLeggedWalker", "FrictionConfig", "GroundConfig",
        "InitialState", "IntegratorConfig", "JointSpec", "MaterialConfig", "MaterialsConfig", "OutputConfig",
        "PointMassSpec", "Push", "RimlessWheelWalker", "SimplestWalker", "SimulationConfig", "StopSpec",
        "WalkerConfig", "WalkerDescription", "apply_override", "config_from_dict", "default_output_dir", "derive",
        "get_dotted", "is_number_annotation", "load_config", "parse_yaml", "read_text_file", "set_dotted",
    ],
    "biped_sim.contact": [],
    "biped_sim.integrate": [],
    "biped_sim.io": [],
    "biped_sim.measure": [],
    "biped_sim.multibody": [],
    "biped_sim.report": ["REPORT_OUTPUT", "Report", "build_report", "report_markdown"],
    "biped_sim.rigid": [],
    "biped_sim.simulate": [
        "CompliantRunResult", "RigidRunResult", "RigidStart", "RunResult", "SpaceRunResult", "SpaceStart",
        "initial_state", "prepare_model", "run", "simulate", "study_formulation",
    ],
    "biped_sim.studies": [],
    "biped_sim.studies.fit": [
        "GLOBAL_METHODS", "Calibration", "FitParameter", "FitProblem", "FitResult", "Outcome", "PosteriorRun",
        "Prior", "calibrate", "contest", "fit_parameter", "fit_problems", "parse_each", "parse_parameter",
        "parse_prior", "priors_for", "sampler_size", "synthetic_reference", "synthetic_reference_data",
    ],
    "biped_sim.studies.uncertainty": [],
    "biped_sim.sweep": [
        "RangeSpec", "RunSpec", "SchedulerLostError", "Sweep", "SweepOutcome", "SweepProgress", "SweepSpec",
        "check_buildable", "check_executor", "dask_executor", "default_jobs", "execute_run", "expand", "load_sweep",
        "local_executor", "make_executor", "pending_runs", "read_sweep", "run_sweep", "study_executor",
        "workers_for",
    ],
    "biped_sim.walkers": ["BuiltModel", "build_model", "describe"],
}  # fmt: skip
OPTIONAL = {"biped_sim.bench.mujoco_walker", "biped_sim.bench.mujoco_space"}  # need the bench extra (MuJoCo)


def every_module() -> list[str]:
    """Every module of the package tree (but those of optional extras)."""
    names = [info.name for info in pkgutil.walk_packages(biped_sim.__path__, prefix="biped_sim.")]
    return [name for name in names if name not in OPTIONAL and not name.endswith("__main__")]


def packages() -> list[str]:
    """``biped_sim`` and every package under it."""
    found = [info.name for info in pkgutil.walk_packages(biped_sim.__path__, prefix="biped_sim.") if info.ispkg]
    return ["biped_sim", *found]


def test_every_package_is_listed() -> None:
    assert sorted(packages()) == sorted(EXPORTS)


@pytest.mark.parametrize("name", sorted(EXPORTS))
def test_a_package_exports_what_is_listed(name: str) -> None:
    package = importlib.import_module(name)
    assert sorted(getattr(package, "__all__", [])) == sorted(EXPORTS[name])


def test_every_export_is_there_and_is_not_shadowed_by_a_module() -> None:
    """Importing a submodule binds its name on the package: an export of the same name would then be the module.
    Every module imported first, every export must still be what the package defined."""
    for name in every_module():
        importlib.import_module(name)
    for name, exported in EXPORTS.items():
        package = importlib.import_module(name)
        for attribute in exported:
            value = getattr(package, attribute)
            assert not isinstance(value, ModuleType), f"{name}.{attribute} is shadowed by its submodule"
