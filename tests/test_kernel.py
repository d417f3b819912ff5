"""The engine's kernels: compiled without the Python entry, callable from Python all the same."""

from __future__ import annotations

import importlib
import pkgutil

import numpy as np
import pytest
from numba import njit
from numba.core.errors import NumbaError
from numba.core.registry import CPUDispatcher

import biped_sim
from biped_sim.integrate.explicit import advance
from biped_sim.kernel import PYTHON_ENTRY_SUFFIX, Kernel, kernel


@kernel
def _weighted_sum(values: np.ndarray, weight: float) -> float:
    total = 0.0
    for v in values:
        total += weight * v
    return total


@njit(cache=True)
def _calls_the_kernel(values: np.ndarray) -> float:
    return _weighted_sum(values, 2.0)


def test_a_kernel_has_no_python_wrapper_and_python_calls_reach_its_twin() -> None:
    values = np.arange(5.0)
    assert _calls_the_kernel(values) == 20.0  # compiled caller: the kernel itself
    assert _weighted_sum.targetoptions["no_cpython_wrapper"] and _weighted_sum.python_entry is None
    assert _weighted_sum(values, 3.0) == 30.0  # from Python: the twin, compiled with the wrapper
    entry = _weighted_sum.python_entry
    assert entry is not None and not entry.targetoptions.get("no_cpython_wrapper", False)
    assert entry.py_func.__qualname__ == "_weighted_sum" + PYTHON_ENTRY_SUFFIX  # its own cache file
    assert _weighted_sum(values, 1.0) == 10.0 and _weighted_sum.python_entry is entry  # compiled once


def test_a_kernel_without_reference_counts_refuses_to_allocate() -> None:
    @kernel(reference_counts=False)
    def allocates(n: int) -> float:
        return np.zeros(n).sum()

    with pytest.raises(NumbaError, match="zeros"):
        allocates(3)


def test_the_integration_loop_counts_no_references() -> None:
    """The loop binds dozens of arrays and allocates none: reference counting off shortens its compilation."""
    assert isinstance(advance, Kernel) and advance.targetoptions["_nrt"] is False


def test_every_cached_engine_function_is_a_kernel_or_inlined() -> None:
    """A plain ``@njit(cache=True)`` in the package would compile the large Python wrapper again."""
    plain = []
    for info in pkgutil.walk_packages(biped_sim.__path__, "biped_sim."):
        if info.name in ("biped_sim.bench.mujoco_walker", "biped_sim.cli.__main__"):  # an optional extra; the CLI
            continue
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if not isinstance(value, CPUDispatcher) or isinstance(value, Kernel) or value.__module__ != info.name:
                continue
            if value.targetoptions.get("inline", "never") != "always":
                plain.append(f"{info.name}.{name}")
    assert plain == []
