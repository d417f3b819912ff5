"""A rigid walker in space's first run compiled on two cores (simulate/space_aside.py, simulate/aside.py): the
stance phase compiled after both shares compiles none of them, the run's measures compile nothing, and a user error
of a cold run is one line."""

from __future__ import annotations

import json
import subprocess
import sys
import time
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
    assert ours == {  # the phase (the accepted step's bookkeeping over both trees inlined), two small shared kernels
        "biped_sim.rigid.space_integration.space_phase_python_entry",
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


@pytest.mark.parametrize("cold_phase", [True, False], ids=["cold stance phase", "warm stance phase"])
def test_a_cold_compliant_run_from_the_rigid_limit_cycle_in_space_splits_the_stance_phase(
    monkeypatch: pytest.MonkeyPatch, cold_phase: bool
) -> None:
    """Its second process compiles the rigid flow's tree first and signals; the run compiles its share of the stance
    phase and seeks the limit cycle only after the signal (a warm stance phase: neither)."""
    monkeypatch.setattr(aside, "_cold_loop", lambda model: True)
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    if cold_phase:
        monkeypatch.setattr(aside, "first_callee", lambda: (numba.njit(lambda x: x), (1.0,)))  # compiled here
    monkeypatch.setattr(aside, "flow_share", lambda: ((_SlowCompile(), ()),))  # the second process signals after it
    monkeypatch.setattr(aside, "measure_stand_in", lambda config, model: None)
    steps: list[object] = []
    monkeypatch.setattr(aside, "_compile_phase_share", lambda: steps.append("phase share"))
    forked = []
    fork = aside._fork
    monkeypatch.setattr(aside, "_fork", lambda target, args: forked.append(args[-1]) or fork(target, args))
    prepare = aside.prepare_model
    monkeypatch.setattr(aside, "prepare_model", lambda config: _flow_done(forked, steps) or prepare(config))
    config = load_config(CONFIGS / "space" / "tinkertoy_compliant.yaml", ["simulation.t_end=0.5"])
    model, process = aside.prepare_compiling_aside(config)
    aside.join(process)
    assert process.exitcode == 0
    assert steps == (["phase share", True] if cold_phase else [None])
    assert model.y0 == pytest.approx(prepare(config).y0, abs=0.0)  # the run's start: the rigid limit cycle


class _SlowCompile:
    """A stand-in of a kernel whose compile takes a second (the flow's tree takes some 6 CPU s)."""

    def compile(self, signature: tuple) -> None:
        time.sleep(1.0)


def _flow_done(forked: list[object], steps: list[object]) -> None:
    """Note in ``steps`` whether the forked process's flow signal is set (None: it was given none); nothing before the
    fork (the draft's build)."""
    if forked:
        steps.append(None if forked[0] is None else forked[0].is_set())  # type: ignore[attr-defined]
