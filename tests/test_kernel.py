"""The engine's kernels: compiled without the Python entry, callable from Python all the same."""

from __future__ import annotations

import importlib
import inspect
import json
import os
import pkgutil
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import numba
import numpy as np
import pytest
from numba import njit
from numba.core.errors import NumbaError
from numba.core.registry import CPUDispatcher

import biped_sim
from biped_sim._compiled_cache import OPT_LEVEL
from biped_sim.integrate.explicit import advance
from biped_sim.kernel import (
    OVERLOAD_SUFFIX,
    PYTHON_ENTRY_SUFFIX,
    Kernel,
    inlined,
    kernel,
    missing_numba_internals,
    overload_by_type,
)

from .conftest import child_env


@kernel
def _weighted_sum(values: np.ndarray, weight: float) -> float:
    total = 0.0
    for v in values:
        total += weight * v
    return total


@kernel
def _entry_sum(values: np.ndarray, weight: float) -> float:
    """:func:`_weighted_sum`'s arithmetic in a kernel of its own, for ``entry_for``'s test: a test that calls a kernel
    from Python compiles its twin, which another test checks is not there before its first such call."""
    total = 0.0
    for v in values:
        total += weight * v
    return total


@njit(cache=True)
def _calls_the_kernel(values: np.ndarray) -> float:
    return _weighted_sum(values, 2.0)


def test_the_numba_internals_the_kernels_rely_on_are_there() -> None:
    missing = missing_numba_internals()
    assert missing == [], (
        f"numba {numba.__version__} (llvmlite {numba.llvmlite.__version__}) lacks what biped_sim.kernel relies on: "
        f"{'; '.join(missing)}. Adapt biped_sim/kernel.py, or install the numba pinned in pyproject.toml."
    )


class _Flat(NamedTuple):
    height: float


class _Tilted(NamedTuple):
    height: float
    slope: float


@kernel
def _flat_level(ground: _Flat, x: float) -> float:
    return ground.height


@kernel
def _tilted_level(ground: _Tilted, x: float) -> float:
    return ground.height + ground.slope * x


def _level(ground: tuple, x: float) -> float:
    return {_Flat: _flat_level, _Tilted: _tilted_level}[type(ground)](ground, x)


_level.__signature__ = inspect.Signature(  # type: ignore[attr-defined]  # the parameters, as the registries give them
    [inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD) for name in ("ground", "x")]
)
overload_by_type(_level, "ground", {_Flat: _flat_level, _Tilted: _tilted_level}.get, inline=True)


@njit
def _levels(flat: _Flat, tilted: _Tilted) -> tuple[float, float]:
    return _level(flat, 2.0), _level(tilted, 2.0)


def test_a_call_is_resolved_by_its_argument_type_at_compile_time() -> None:
    """numba picks the kernel from the NamedTuple class of one argument (biped_sim.kernel.overload_by_type)."""
    assert _levels(_Flat(1.0), _Tilted(1.0, 0.5)) == (1.0, 2.0)
    assert _level(_Tilted(1.0, 0.5), 2.0) == 2.0  # from Python: looked up by type


_LEVELS_IN_A_NEW_PROCESS = """
import json
from biped_sim._compiled_cache import recording_compilations
from tests.test_kernel import _Flat, _levels, _Tilted
with recording_compilations() as compiled:
    _levels(_Flat(1.0), _Tilted(1.0, 0.5))
print(json.dumps(compiled))
"""


@pytest.mark.slow
def test_an_overload_implementation_compiled_in_one_process_is_loaded_from_the_cache_in_the_next(
    tmp_path: Path,
) -> None:
    """numba compiles an overload's implementation (even one it inlines) with every caller that reaches it first in
    a process; cached under a name of its own (not the kernel's: other options), a second process loads it."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # empty: the first process compiles everything
    runs = [subprocess.run([sys.executable, "-c", _LEVELS_IN_A_NEW_PROCESS], env=env, capture_output=True, text=True)]
    runs.append(
        subprocess.run([sys.executable, "-c", _LEVELS_IN_A_NEW_PROCESS], env=env, capture_output=True, text=True)
    )
    assert all(run.returncode == 0 for run in runs), [run.stderr for run in runs]
    first, second = (json.loads(run.stdout.strip().splitlines()[-1]) for run in runs)
    implementations = {f"tests.test_kernel.{k}{OVERLOAD_SUFFIX}" for k in ("_flat_level", "_tilted_level")}
    assert implementations <= set(first)
    assert "tests.test_kernel._levels" in second and not implementations & set(second)  # the caller, not them


_LEVEL_IN_A_NEW_PROCESS = "import biped_sim, numba; print(int(numba.config.OPT), numba.config.CACHE_DIR)"


@pytest.mark.slow
def test_the_package_compiles_at_its_optimisation_level_unless_numba_opt_is_set() -> None:
    """LLVM's level OPT_LEVEL by default, the user's NUMBA_OPT if set; the code of each level in a cache of its own."""
    env = {k: v for k, v in child_env().items() if k not in ("NUMBA_OPT", "NUMBA_CACHE_DIR")}
    runs = [
        subprocess.run([sys.executable, "-c", _LEVEL_IN_A_NEW_PROCESS], env=env | user, capture_output=True, text=True)
        for user in ({}, {"NUMBA_OPT": "3"})
    ]
    assert all(run.returncode == 0 for run in runs), [run.stderr for run in runs]
    (default, default_cache), (chosen, chosen_cache) = (run.stdout.split() for run in runs)
    assert (default, chosen) == (OPT_LEVEL, "3") and default_cache != chosen_cache


def test_a_kernel_has_no_python_wrapper_and_python_calls_reach_its_twin() -> None:
    values = np.arange(5.0)
    assert _calls_the_kernel(values) == 20.0  # compiled caller: the kernel itself
    assert _weighted_sum.targetoptions["no_cpython_wrapper"] and _weighted_sum.python_entry is None
    assert _weighted_sum(values, 3.0) == 30.0  # from Python: the twin, compiled with the wrapper
    entry = _weighted_sum.python_entry
    assert entry is not None and not entry.targetoptions.get("no_cpython_wrapper", False)
    assert entry.py_func.__qualname__ == "_weighted_sum" + PYTHON_ENTRY_SUFFIX  # its own cache file
    assert _weighted_sum(values, 1.0) == 10.0 and _weighted_sum.python_entry is entry  # compiled once


def test_a_kernels_entry_for_argument_types_is_its_twins_compiled_code() -> None:
    """``entry_for``: the twin's compiled code for those types, called without numba's typing of the arguments."""
    values = np.arange(5.0)
    entry = _entry_sum.entry_for(values, 2.0)
    assert entry(values, 2.0) == _entry_sum(values, 2.0) == 20.0
    assert _entry_sum.entry_for(values, 2.0) is entry  # compiled once: the same code for the same types


@kernel(literal_arguments=False)
def _halved(x: float, half: bool) -> float:
    return 0.5 * x if half else x


@kernel
def _halved_by_value(x: float, half: bool) -> float:
    return 0.5 * x if half else x


@njit
def _both_ways(x: float) -> tuple[float, float]:
    return _halved(x, True) + _halved(x, False), _halved_by_value(x, True) + _halved_by_value(x, False)


def test_constants_passed_from_compiled_code_specialise_a_kernel_only_with_literal_arguments() -> None:
    """numba compiles a kernel once per constant a compiled caller passes (``True``, ``False``); with
    ``literal_arguments=False`` once for the constants' type."""
    assert _both_ways(2.0) == (3.0, 3.0)
    assert len(_halved.signatures) == 1 and len(_halved_by_value.signatures) == 2


def test_a_kernel_without_reference_counts_refuses_to_allocate() -> None:
    @kernel(reference_counts=False)
    def allocates(n: int) -> float:
        return np.zeros(n).sum()

    with pytest.raises(NumbaError, match="zeros"):
        allocates(3)


def test_the_integration_loop_counts_no_references() -> None:
    """The loop binds dozens of arrays and allocates none: reference counting off shortens its compilation."""
    assert isinstance(advance, Kernel) and advance.targetoptions["_nrt"] is False


OPTIONAL = {"biped_sim.bench.mujoco_walker", "biped_sim.bench.mujoco_space"}  # need the bench extra (MuJoCo)


def test_every_cached_engine_function_is_a_kernel_or_inlined() -> None:
    """A plain ``@njit(cache=True)`` in the package would compile the large Python wrapper again."""
    plain = []
    for info in pkgutil.walk_packages(biped_sim.__path__, "biped_sim."):
        if info.name in OPTIONAL | {"biped_sim.cli.__main__"}:  # the optional extra's modules; the CLI
            continue
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if not isinstance(value, CPUDispatcher) or isinstance(value, Kernel) or value.__module__ != info.name:
                continue
            if value.targetoptions.get("inline", "never") != "always":
                plain.append(f"{info.name}.{name}")
    assert plain == []


def test_an_inlined_copy_keeps_the_callees_named_as_calls() -> None:
    """``inlined(k, calls=...)``: a callee named there stays the kernel itself (an ordinary call), at any depth; the
    others become inlined copies (numba's inline="always")."""
    from biped_sim.rigid import tree_kernels

    names = inlined(tree_kernels.tree_rhs, calls=frozenset({"_solve"})).py_func.__globals__
    assert names["_solve"] is tree_kernels._solve
    assert names["_light_tier"].py_func.__globals__["_solve"] is tree_kernels._solve  # one level down
    assert names["_assemble"] is not tree_kernels._assemble
    assert names["_assemble"].targetoptions["inline"] == "always"


def test_a_missing_internal_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delattr(numba.core.config, "DISABLE_JIT")
    assert missing_numba_internals() == ["numba.core.config.DISABLE_JIT"]
