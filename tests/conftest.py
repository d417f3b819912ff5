"""Shared fixtures and helpers: the bundled configs, runs and a sweep simulated once per session, the CLI.

The fast tier (``make test``) shares one short run (:func:`short_run`, 2 s of the default walker)
and one tiny sweep (:func:`tiny_sweep_dir`, 8 runs of 1.3 s) among the tests that only read them;
:func:`default_run` (the full 15 s) is for the slow tier (``make validate``), whose tests are marked
``@pytest.mark.slow``.

CLI tests call the typer app in-process (:func:`invoke`, milliseconds); :func:`run_cli` starts a fresh
interpreter (about a second) and is kept for where the process boundary is the point: the exit code
and stderr of the real entry point, worker processes, a kill -9.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import time
import tracemalloc
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import pytest
from click.testing import Result
from numba.core.registry import CPUDispatcher
from typer.testing import CliRunner

import biped_sim
from biped_sim import load_config, simulate
from biped_sim.cli import app
from biped_sim.multibody.dispatch import FORMULATIONS
from biped_sim.multibody.formulation import KERNEL_SIGNATURES
from biped_sim.simulate import RunResult
from biped_sim.testing import default_walker, write_tiny_sweep

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"
DEFAULT_CONFIG = CONFIGS / "round_foot_walker.yaml"
CLI = [sys.executable, "-m", "biped_sim.cli"]
T = TypeVar("T")
ENGINE = ("biped_sim.contact", "biped_sim.multibody", "biped_sim.integrate")  # the compliant engine's packages
# what refusing a huge input may allocate (:func:`allocation_peak`): building it would take gigabytes
MEMORY_BOUND = 64 * 2**20


def child_env() -> dict[str, str]:
    """This environment with the directory this session imports biped_sim from first on PYTHONPATH.

    A child started in another directory then runs the same code as the tests in this process: with a
    relative PYTHONPATH (``PYTHONPATH=src``) it would import the editable install instead, possibly
    another tree, and compile that tree's kernels (40 s) on the way.
    """
    here = str(Path(biped_sim.__file__).resolve().parents[1])
    paths = [here, *(p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p)]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(paths)}


def run_cli(*args: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """``biped-sim ARGS`` in a fresh interpreter (the real entry point: exit code, stdout, stderr)."""
    return subprocess.run([*CLI, *args], cwd=cwd, env=child_env(), capture_output=True, text=True, timeout=timeout)


def invoke(*args: str) -> Result:
    """``biped-sim ARGS`` in this process (typer's CliRunner): exit code, stdout and stderr apart."""
    return CliRunner().invoke(app, list(args))


def one_line_error(stderr: str) -> str:
    """The single line of a user error on stderr (asserts there is exactly one, and no traceback)."""
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), stderr
    assert "Traceback" not in stderr
    return lines[0]


def pytest_configure(config: pytest.Config) -> None:
    """The ``serial`` mark (beside pyproject's ``slow``): ``make validate`` runs these slow tests alone, after the
    others have run in parallel, because they time themselves or kill processes on deadlines."""
    config.addinivalue_line("markers", "serial: a slow test that make validate runs alone, not beside others")


# Modules that share an expensive session fixture (tiny_sweep_dir: eight runs on two worker processes): xdist runs
# them on one worker, which computes it once; every other module is a unit of its own, so that its module-scoped
# fixtures are computed once too. pytest-xdist's loadgroup would do this with marks, but groups nothing with
# pytest 9.2 (pytest-dev/pytest-xdist#1386).
SHARED_FIXTURE_MODULES = {
    f"tests/{name}.py": "tiny_sweep"
    for name in ("test_compare", "test_report", "test_study_arguments", "test_study_faults", "test_sweep_run")
}
# The slow tier's costliest units, costliest first (CPU times in docs/guide/development.md, "Where CI time goes"):
# xdist hands them out before the others, so that the tier does not end with one worker alone on a long test while
# the other idles. A test named here (its module has no module-scoped fixture) is a unit of its own: the two
# recovery pairs run side by side.
LONGEST_FIRST = (
    "tests/test_fit_recovery_kneed.py::test_hidden_kneed_values_drawn_at_random_are_recovered",
    "tests/test_fit_recovery.py::test_hidden_values_drawn_at_random_are_recovered[inertia+restitution]",
    "tests/test_fit_recovery.py::test_hidden_values_drawn_at_random_are_recovered[stiffness+friction]",
    "tests/test_fit_coverage.py",
    "tests/test_fit_contest.py",
    "tests/test_described.py",
    "tests/test_uncertainty.py",
    "tests/test_validation.py",
    "tests/test_bench.py",
    "tiny_sweep",
)


def work_unit(nodeid: str) -> str:
    """The unit of work xdist hands a worker for the test ``nodeid``: a test of :data:`LONGEST_FIRST`, a group of
    :data:`SHARED_FIXTURE_MODULES`, or the test's module."""
    if nodeid in LONGEST_FIRST:
        return nodeid
    module = nodeid.split("::", 1)[0]
    return SHARED_FIXTURE_MODULES.get(module, module)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """Under ``-n N`` with the default distribution, hand out tests by :func:`work_unit`, :data:`LONGEST_FIRST`
    first (the rest as xdist orders them: the units of most tests first)."""
    if config.getoption("dist") != "load":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class UnitScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return work_unit(nodeid)

        def _assign_work_unit(self, node: Any) -> None:
            costliest = [unit for unit in LONGEST_FIRST if unit in self.workqueue]
            for unit in reversed(costliest):
                self.workqueue.move_to_end(unit, last=False)
            super()._assign_work_unit(node)

    return UnitScheduling(config, log)


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter, config: pytest.Config) -> None:
    """Name the order the tests ran in (pytest-randomly shuffles it), even under ``-q``: a failure that depends on
    the order is then reproduced with the same seed."""
    seed = getattr(config.option, "randomly_seed", None)
    if isinstance(seed, int):
        terminalreporter.write_line(f"tests shuffled with --randomly-seed={seed} (pass it to run them in this order)")


def plain_function(compiled: CPUDispatcher) -> Callable[..., Any]:
    """The plain-Python function of ``compiled``: its ``.py_func``, but for an inlined copy
    (:func:`biped_sim.kernel.inlined`, the same code object) the original kernel's, whose callees are looked up
    in its module; the copy's own globals hold compiled copies of them, which numba would compile anew (nothing
    caches them) in every session that calls them from Python."""
    plain = compiled.py_func
    original = getattr(sys.modules.get(plain.__module__), plain.__name__, None)
    if isinstance(original, CPUDispatcher):
        original = original.py_func
    # the original may be plain already (its module patched first): the copy's own globals hold compiled callees
    return original if getattr(original, "__code__", None) is plain.__code__ else plain


def run_as_plain_python(patch: pytest.MonkeyPatch, packages: tuple[str, ...]) -> None:
    """Replace every compiled function of the loaded modules of ``packages`` (also in a tuple: the law
    registries) by its plain-Python function (:func:`plain_function`), for a slow reference of the same source."""
    for name, module in list(sys.modules.items()):
        if name.startswith(packages):
            for attribute, value in list(vars(module).items()):
                if isinstance(value, CPUDispatcher):
                    patch.setattr(module, attribute, plain_function(value))
                elif isinstance(value, tuple) and value and all(isinstance(v, CPUDispatcher) for v in value):
                    patch.setattr(module, attribute, tuple(plain_function(v) for v in value))


@contextmanager
def plain_engine() -> Iterator[None]:
    """Inside the block, the compliant engine (:data:`ENGINE`) runs as plain Python (:func:`run_as_plain_python`),
    the formulations' registered kernels and measures too, so that ``system_rhs`` or ``measures`` called from
    Python run the source rather than compile its Python-called twin (:class:`biped_sim.kernel.Kernel`): for checks
    of a formulation's equations, which the compiled runs' own tests (golden, the formulations' runs) do not need
    compiled twice."""
    with pytest.MonkeyPatch.context() as patch:
        run_as_plain_python(patch, ENGINE)
        for system_type, formulation in list(FORMULATIONS.items()):
            kernels = {kernel: plain_function(getattr(formulation, kernel)) for kernel in KERNEL_SIGNATURES}
            measured = {
                name: plain_function(value)
                for name, value in formulation.measures._asdict().items()
                if isinstance(value, CPUDispatcher)
            }
            measures = formulation.measures._replace(**measured)
            patch.setitem(FORMULATIONS, system_type, dataclasses.replace(formulation, **kernels, measures=measures))
        yield


@pytest.fixture(scope="session")
def default_run() -> RunResult:
    """The default walker, as `make run` simulates it (15 s, 34 steps): for the slow tier's settled-gait checks."""
    return simulate(load_config(DEFAULT_CONFIG))


@pytest.fixture(scope="session")
def short_run() -> RunResult:
    """The default walker for 2 s (four heel strikes): read-only, shared by every test that needs some walking."""
    return simulate(default_walker())


@pytest.fixture(scope="session")
def short_run_dir(short_run: RunResult, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """:func:`short_run` written as a run directory; shared by the plot, animate and compare tests.

    Tests may add outputs below it (``figures/``) but must not change the run's own files.
    """
    out = tmp_path_factory.mktemp("short_run") / "run"
    short_run.write(out)
    return out


@pytest.fixture(scope="session")
def tiny_sweep_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tiny sweep (biped_sim.testing.write_tiny_sweep), run once by ``biped-sim sweep --jobs 2``.

    Two worker processes: the runs finish out of order and the table must not.
    Shared (read-only) by the sweep runner, report and compare tests, which write below it only into
    directories of their own.
    """
    root = tmp_path_factory.mktemp("tiny_sweep")
    path = write_tiny_sweep(root)
    result = invoke("sweep", str(path), "--jobs", "2", "--out", str(root / "sweep"))
    assert result.exit_code == 0, result.output
    assert "8 runs: 0 already finished, 8 to run" in result.stdout
    # not a terminal: no live display but one progress line per run
    assert sum(line.startswith("[") for line in result.stdout.splitlines()) == 8
    return root / "sweep"


FREEZE_HOOK = Path(__file__).resolve().parent / "freeze"


def freezing_env(markers: Path, *points: str) -> dict[str, str]:
    """:func:`child_env` with the freeze hook (tests/freeze/sitecustomize.py) armed at ``points`` ('NAME@N').

    The first process (the CLI or a worker it starts) to reach a point stops there for good, before the N-th
    rename onto a file named NAME, and writes its pid to ``markers/NAME``: a kill then lands at a known point.
    """
    markers.mkdir(parents=True, exist_ok=True)
    env = child_env()
    env["PYTHONPATH"] = os.pathsep.join([str(FREEZE_HOOK), env["PYTHONPATH"]])
    env["BIPED_SIM_TEST_FREEZE"] = "|".join([str(markers), *points])
    return env


def wait_frozen(process: subprocess.Popen[Any], markers: Path, *names: str, timeout: float = 180) -> dict[str, int]:
    """The pids of the processes frozen at ``names`` (:func:`freezing_env`), once all are; fails if ``process`` ends."""
    deadline = time.monotonic() + timeout
    while not all((markers / name).exists() for name in names):
        assert process.poll() is None, f"the process ended (exit code {process.returncode}) before freezing"
        assert time.monotonic() < deadline, f"nothing froze at {names} within {timeout} s"
        time.sleep(0.02)
    return {name: int((markers / name).read_text()) for name in names}


def allocation_peak(call: Callable[[], T]) -> tuple[T, int]:
    """``call()`` and the most memory (bytes) Python and numpy held at once for it, as tracemalloc counts.

    A bound on it checks that a huge input was refused before anything was built from it, whatever the
    machine's speed or load (a bound on the time taken would not).
    """
    tracemalloc.start()
    try:
        result = call()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return result, peak
