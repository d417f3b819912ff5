"""The warm-up (``biped-sim warmup``, a sweep worker's first run) and what a run compiles: its own group only."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from numba import njit

from biped_sim import load_config, simulate
from biped_sim._compiled_cache import profiling_compilations, recording_compilations
from biped_sim.config import derive
from biped_sim.multibody.dispatch import FORMULATIONS
from biped_sim.rigid.build import initial_state, rigid_walker
from biped_sim.rigid.compiled import walk_starts
from biped_sim.simulate import RunResult, study_formulation, warmup
from biped_sim.studies.uncertainty.mfpt import height_walk_config
from biped_sim.sweep import load_sweep
from biped_sim.testing import default_walker

from .conftest import CONFIGS, ROOT, child_env, invoke
from .record_golden import read_golden
from .test_space_compliant import GAIT

# modules whose compiled code a planar run with an explicit method must neither compile nor load
OTHER_GROUPS = (
    "biped_sim.multibody.spatial",
    "biped_sim.multibody.spatial_kernels",
    "biped_sim.multibody.euler_parameters",
    "biped_sim.integrate.stiff",
)

# bundled configs whose group the warm-up leaves to their first run: the 3D kneed walkers' (Euler parameters with joint
# stops), which only the slow tier and a user who asks for it run
NOT_WARMED = {"kneed_walker_3d.yaml", "kneed_walker_3d_settled.yaml"}

# the profile geometry and the profile implementations of the ground's functions: a flat run compiles none
PROFILE_CODE = ("biped_sim.contact.ground.", "biped_sim.contact.response._profile_")

_LOADED_BY_A_PLANAR_RUN = """
import json, sys
from numba.core.registry import CPUDispatcher
from biped_sim import simulate
from biped_sim.testing import default_walker

def compiled(value):
    entry = getattr(value, "python_entry", None)  # a kernel called from Python runs its wrapped twin
    return isinstance(value, CPUDispatcher) and bool(value.signatures or (entry is not None and entry.signatures))

def loaded():  # each function under the module that defines it, not under every module that imports it
    return sorted(
        f"{name}.{attribute}"
        for name, module in list(sys.modules.items()) if name.startswith("biped_sim")
        for attribute, value in vars(module).items() if compiled(value) and value.py_func.__module__ == name
    )

import biped_sim.cli  # every command's module
at_import = loaded()
simulate(default_walker(t_end=0.01))
print(json.dumps({"at_import": at_import, "after_run": loaded()}))
"""


def test_recording_compilations_lists_what_numba_compiles() -> None:
    @njit
    def twice(x: float) -> float:
        return 2.0 * x

    with recording_compilations() as first:
        twice(1.0)
    with recording_compilations() as again:
        twice(2.0)
    assert first == [f"{__name__}.{twice.py_func.__qualname__}"]
    assert again == []


def test_profiling_compilations_charges_each_function_its_own_compile() -> None:
    @njit
    def inner(x: float) -> float:
        return x + 1.0

    @njit
    def outer(x: float) -> float:
        return inner(x) * 2.0

    with profiling_compilations() as profile:
        outer(1.0)
    summary = profile.summary()
    names = {entry["function"] for entry in summary["top"]}
    assert summary["functions"] == 2
    assert {f"{__name__}.{f.py_func.__qualname__}" for f in (inner, outer)} <= names
    assert summary["lowering_cpu_s"] > 0.0 and summary["front_end_cpu_s"] > 0.0
    passes = summary["lowering_cpu_s"] + summary["front_end_cpu_s"]
    assert sum(entry["cpu_s"] for entry in summary["top"]) < 1.5 * passes + 0.05  # each pass counted once
    with profiling_compilations() as again:
        outer(2.0)
    assert again.summary()["functions"] == 0


def test_warmup_command_warms_the_bundled_groups_and_a_profile_run_then_compiles_nothing(
    short_run: RunResult, monkeypatch: pytest.MonkeyPatch
) -> None:
    """After ``biped-sim warmup`` (what make setup ends with) a first run on a ground profile (in the plane, in space),
    or of a rigid walker, or a rigid walker's walks from many starts (a basin's), or with a stiff method, or of another
    rigid walker in space, loads its code."""
    monkeypatch.setattr(warmup, "_WARMED", set())
    result = invoke("warmup")
    assert result.exit_code == 0, result.output
    lines = result.output.strip().splitlines()
    assert [line.split(":")[0] for line in lines] == [
        "rigid step map", "spatial explicit (dopri5)", "rigid step map in space",
        "spatial explicit (dopri5, on a profile)", "planar explicit (dopri5, on a profile)",
        "minimal explicit (dopri5, on a profile)",
        "planar explicit (dopri5, with joint stops)", "minimal explicit (dopri5, with joint stops)",
        "minimal explicit (dopri5)", "minimal explicit (dopri5, with joint elements)",
        "planar explicit (dopri5, with joint elements)", "planar stiff (radau)", "planar explicit (dopri5)",
    ]  # fmt: skip
    assert invoke("warmup").output == ""  # once per process and group
    with recording_compilations() as compiled:
        rough = "ground.profile={kind: random, seed: 3, roughness: 0.002}"
        simulate(default_walker(rough, t_end=0.05))
        simulate(default_walker(rough, "formulation.kind=spatial", t_end=0.05))
        simplest = load_config(CONFIGS / "simplest_walker.yaml", ["simulation.max_steps=1"])
        simulate(simplest)  # another rigid walker
        walker = rigid_walker(simplest)
        walk_starts(walker, np.array([initial_state(simplest, walker)] * 2), 1)  # a basin's walks of its starts
        simulate(default_walker("integrator.method=radau", t_end=0.05))
        simulate(load_config(CONFIGS / "space" / "tinkertoy.yaml", [f"simulation.initial={json.dumps(GAIT)}",
                                                                     "simulation.max_steps=1"]))  # fmt: skip
    assert compiled == []


def test_the_bundled_configs_sweeps_and_golden_cases_run_in_the_warmed_groups() -> None:
    """Every run of configs/, configs/space/ and configs/sweeps/, and every golden case (tests/test_golden.py), is in
    a group ``biped-sim warmup`` warms (the fast tier would compile it otherwise, each test process its own copy)."""
    paths = [path for pattern in ("*.yaml", "space/*.yaml") for path in sorted(CONFIGS.glob(pattern))]
    configs = [load_config(path) for path in paths if path.name not in NOT_WARMED]
    configs += [run.config for path in sorted((CONFIGS / "sweeps").glob("*.yaml")) for run in load_sweep(path).runs]
    configs += [load_config(ROOT / case["config"], case["overrides"]) for case in read_golden()["cases"].values()]
    groups = {warmup.group_of(config) for config in configs}
    assert groups <= set(warmup.BUNDLED_GROUPS)
    assert {("planar", "explicit", "flat"), ("spatial", "explicit", "flat"), (*warmup.RIGID, "flat")} <= groups
    assert (*warmup.RIGID_SPACE, "flat") in groups  # the rigid walkers in space's flow
    assert ("planar", "stiff", "flat") in groups  # the golden case radau_short's
    assert ("planar", "explicit", "flat" + warmup.JOINT_STOPS) in groups  # the compliant kneed walker's knees
    assert ("planar", "explicit", "flat" + warmup.JOINT_ELEMENTS) in groups  # the torso walker's springs


def test_the_bundled_configs_studies_run_in_the_warmed_groups() -> None:
    """A fit evaluation or an uncertainty sample runs a planar walker in minimal coordinates: groups the warm-up
    warms too (the tests' studies, and a user's first, would compile them otherwise, each worker its own copy)."""
    configs = [load_config(path) for path in sorted(CONFIGS.glob("*.yaml"))]
    groups = {warmup.group_of(derive(config, {"formulation.kind": study_formulation(config)})) for config in configs}
    assert groups <= set(warmup.BUNDLED_GROUPS)
    assert ("minimal", "explicit", "flat") in groups  # the default walker's
    assert ("minimal", "explicit", "flat" + warmup.JOINT_STOPS) in groups  # the compliant kneed walker's
    mfpt = height_walk_config(load_config(CONFIGS / "round_foot_walker.yaml"), 0.01, 0, 10)
    assert warmup.group_of(mfpt) == ("minimal", "explicit", "profile") in warmup.BUNDLED_GROUPS  # its MFPT's walks


def test_warm_up_all_covers_every_formulation_integrator_family_and_ground() -> None:
    """Every registered formulation (the engine's registry, not the schema) x both families x the grounds it has."""
    groups = {warmup.group_of(config) for config in warmup.warm_up_configs(True)}
    kinds = {formulation.name for formulation in FORMULATIONS.values()}
    assert {"planar", "spatial", "minimal"} <= kinds
    assert {(kind, family, "flat") for kind in kinds for family in ("explicit", "stiff")} <= groups
    assert ("planar", "explicit", "profile") in groups and ("spatial", "explicit", "profile") in groups
    assert {
        ("planar", "explicit", "profile" + warmup.JOINT_STOPS),
        ("minimal", "stiff", "flat" + warmup.JOINT_STOPS),
        ("planar", "explicit", "flat" + warmup.JOINT_ELEMENTS),
        ("minimal", "explicit", "profile" + warmup.JOINT_STOPS + warmup.JOINT_ELEMENTS),
    } <= groups
    assert ("spatial", "stiff", "flat" + warmup.JOINT_STOPS + warmup.JOINT_ELEMENTS) in groups  # multibody.hinge's
    assert (*warmup.RIGID, "flat") in groups


@pytest.mark.parametrize(
    "overrides",
    [["integrator.method=rk4", "integrator.dt=3e-3"], ["output.sample_rate=100"], ["integrator.method=radau"]],
)
def test_a_worker_warms_up_on_any_valid_run(overrides: list[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """The warm-up is a short copy of the run: it must pass the run's own checks (a step longer than the warm-up,
    a sample rate too low for it once made every first run of a worker an error)."""
    monkeypatch.setattr(warmup, "_WARMED", set())
    family = "stiff" if "radau" in overrides[0] else "explicit"
    done = warmup.warm_up(default_walker(*overrides))
    assert done is not None and (done.formulation, done.family, done.ground) == ("planar", family, "flat")
    assert warmup.warm_up(default_walker(*overrides)) is None


def test_a_planar_explicit_run_compiles_only_its_own_group(short_run: RunResult) -> None:
    """Nothing is compiled at import; a planar dopri5 run neither compiles nor loads the spatial formulation's
    kernels or the stiff driver's (numba dispatchers list the signatures they compiled or loaded).

    Whether the child loads its group from the cache or compiles it (an entry another process's concurrent
    write lost, an empty cache) must not matter: a compile also gives signatures to the callees it types, among
    them the contact laws and solver the spatial modules import, so each function counts under its own module."""
    out = subprocess.run(
        [sys.executable, "-c", _LOADED_BY_A_PLANAR_RUN], env=child_env(), capture_output=True, text=True, check=True
    )
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert loaded["at_import"] == []
    assert "biped_sim.integrate.explicit.advance" in loaded["after_run"]
    assert [name for name in loaded["after_run"] if name.startswith(OTHER_GROUPS)] == []
    # the flat ground's specialisation holds no profile code: no function of the profile geometry is compiled
    assert [name for name in loaded["after_run"] if name.startswith(PROFILE_CODE)] == []
