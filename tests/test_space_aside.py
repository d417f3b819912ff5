"""A rigid walker in space's first run compiled on two cores (simulate/space_aside.py, simulate/aside.py): the
stance phase compiled after both shares compiles none of them, the run's measures compile nothing, and a user error
of a cold run is one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numba
import pytest

from biped_sim.config import load_config
from biped_sim.errors import ConfigError
from biped_sim.simulate import SpaceStart, aside, simulate
from tests.conftest import CLI, CONFIGS, child_env, one_line_error
from tests.test_aside import _compiled_signatures
from tests.test_space_run import STARTED

TINKERTOY = CONFIGS / "space" / "tinkertoy.yaml"

_PHASE_AFTER_THE_SHARES = """
import json
from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import load_config
from biped_sim.kernel import compile_for
from biped_sim.simulate import simulate, space_aside
from tests.conftest import CONFIGS
from tests.test_space_run import STARTED
callees = (space_aside.first_callee(), *space_aside.flow_share(), *space_aside.events_share())
for function, args in callees:
    compile_for(function, args)
twin, args = space_aside.clearance_twin()
twin.entry_for(*args)
config = load_config(CONFIGS / "space" / "tinkertoy.yaml", [STARTED, "simulation.t_end=1.0"])
with recording_compilations() as compiled:
    simulate(config)  # a run's steps: the stance phase with samples
names = [f"{k.py_func.__module__}.{k.py_func.__qualname__}" for k, _ in callees]
print(json.dumps([names, compiled]))
"""


@pytest.mark.slow
def test_the_stance_phase_compiled_after_both_shares_finds_them_all_in_the_cache(tmp_path: Path) -> None:
    env = {**child_env(), "NUMBA_CACHE_DIR": str(tmp_path)}  # empty: the phase and its callees compile
    out = subprocess.run([sys.executable, "-c", _PHASE_AFTER_THE_SHARES], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    callees, compiled = json.loads(out.stdout.strip().splitlines()[-1])
    assert "biped_sim.rigid.space_kernels.space_flow" in callees  # the second process's share
    assert not set(callees) & set(compiled)
    ours = {name for name in compiled if name.startswith("biped_sim.")}
    assert ours == {  # the phase, the accepted step's bookkeeping over both trees, and two small shared kernels
        "biped_sim.rigid.space_integration.space_phase_python_entry",
        "biped_sim.rigid.space_integration._accepted",
        "biped_sim.rigid.space_integration._first_event",
        "biped_sim.rigid.integration.first_sample",
        "biped_sim.integrate.stepper.rms_norm",
    }


def test_a_rigid_run_in_space_on_a_warm_cache_starts_no_process(monkeypatch: pytest.MonkeyPatch) -> None:
    config = load_config(TINKERTOY, [STARTED, "simulation.t_end=1.0"])
    simulate(config)  # every kernel of the run compiled or loaded
    forked: list[object] = []
    monkeypatch.setattr(aside, "_fork", lambda target, args: forked.append(target))
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    start, process = aside.prepare_compiling_aside(config)
    assert isinstance(start, SpaceStart) and process is None and forked == []


def test_the_measures_of_a_rigid_run_in_space_compile_nothing() -> None:
    result = simulate(load_config(TINKERTOY, [STARTED, "simulation.t_end=3.0"]))
    before = _compiled_signatures()
    result.trajectory()
    _ = result.summary, result.steps
    assert _compiled_signatures() == before  # nothing for a second process to compile ahead


def test_a_cold_rigid_run_in_space_checks_its_size_while_the_second_process_compiles(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(aside, "first_callee", lambda: (numba.njit(lambda x: x), (1.0,)))  # compiled: a cold cache
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    monkeypatch.setattr(aside, "flow_share", lambda: ())  # nothing to compile: the process ends at once
    forked = []
    fork = aside._fork
    monkeypatch.setattr(aside, "_fork", lambda target, args: forked.append(fork(target, args)) or forked[-1])
    too_long = load_config(TINKERTOY, ["simulation.t_end=1e9"])
    with pytest.raises(ConfigError, match="budget"):
        aside.prepare_compiling_aside(too_long)  # at once: before the limit cycle's search compiles the step map
    assert len(forked) == 1 and forked[0].daemon
    forked[0].join(10.0)
    assert forked[0].exitcode == 0


@pytest.mark.slow
def test_a_user_error_of_a_cold_rigid_run_in_space_is_one_line(tmp_path: Path) -> None:
    env = {**child_env(), "NUMBA_CACHE_DIR": str(tmp_path / "cache")}  # empty: the second process starts
    args = ["run", str(TINKERTOY), "-q", "--out", str(tmp_path / "run"), "--set", "simulation.t_end=1e9"]
    out = subprocess.run([*CLI, *args], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 2
    assert "budget" in one_line_error(out.stderr)  # no traceback: the second process ended quietly
    assert not (tmp_path / "run").exists()
