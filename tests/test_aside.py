"""A first run's measures compiled in a second process (simulate/aside.py): the stand-in compiles what a run
measures, and the process starts only on a cold compile cache."""

from __future__ import annotations

import gc
import importlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import pytest
from numba.core.dispatcher import Dispatcher

from biped_sim.config import Config, InitialState, derive, load_config
from biped_sim.config.space_description import SPACE_STATE_KEYS
from biped_sim.contact.response import ARMED
from biped_sim.errors import ConfigError
from biped_sim.measure.steps import step_table
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import compile_walker, rigid_step
from biped_sim.rigid.start import RigidStart
from biped_sim.simulate import aside, prepare_model, simulate
from biped_sim.simulate.compliant import CompliantRunResult, integrate_config
from biped_sim.walkers import BuiltModel
from biped_sim.walkers.model import start_modes_deferred
from tests.conftest import CONFIGS


def _compiled_signatures() -> set[tuple[str, str]]:
    """Every (function, signature) this process has compiled or loaded from the cache, twins included."""
    return {
        (f"{d.py_func.__module__}.{d.py_func.__qualname__}", str(signature))
        for d in gc.get_objects()
        if issubclass(type(d), Dispatcher)  # not isinstance: a dead weak proxy among the objects raises on it
        for signature in d.signatures
    }


simulate_module = importlib.import_module("biped_sim.simulate")  # the package, not the function it exports


def _types(model: BuiltModel) -> list[object]:
    """numba's types of what a model gives the loop: its state, its modes and its system."""
    return [numba.typeof(x) for x in (model.y0, model.modes0, model.system)]


def _with_knee_stops() -> Config:
    """The compliant kneed walker (its stops add mode rows), for a short run."""
    return load_config(CONFIGS / "kneed_walker_compliant.yaml")


@pytest.mark.parametrize(
    "walker", [Config, pytest.param(_with_knee_stops, marks=pytest.mark.slow)], ids=["default", "knee stops"]
)
def test_the_stand_in_compiles_every_measure_of_a_run(walker: Callable[[], Config]) -> None:
    config = derive(walker(), {"simulation.t_end": 0.05})
    model = prepare_model(config)
    aside.measure_stand_in(config, model)
    run = integrate_config(config, model)
    before = _compiled_signatures()
    result = CompliantRunResult(config=config, model=model, run=run, steps=step_table(model, run), wall_time_s=0.0)
    result.trajectory()
    _ = result.summary
    assert _compiled_signatures() - before == set()


def test_the_stand_in_has_the_run_s_types_and_its_start_state() -> None:
    model = prepare_model(Config())
    run = aside.stand_in(model)
    assert run.status == "walking"
    assert run.y.shape == run.strike_y.shape == (aside.STAND_IN_SAMPLES, len(model.y0))
    assert (run.y == model.y0).all() and (run.modes == model.modes0).all()


def test_a_warm_cache_starts_no_process() -> None:
    config = Config()
    built = prepare_model(config)
    aside.compile_for(aside.events.system_is_leading, (built.y0, built.system, 0))  # the cold probe's: loaded
    model, process = aside.prepare_compiling_aside(config)
    assert process is None
    assert (model.y0 == built.y0).all() and (model.modes0 == built.modes0).all()


@pytest.mark.parametrize("name", ["round_foot_walker", "kneed_walker_compliant", "four_legged_walker"])
def test_a_draft_model_has_the_run_s_types_and_start(name: str) -> None:
    config = load_config(CONFIGS / f"{name}.yaml")
    with start_modes_deferred():
        draft = prepare_model(config)
    model = prepare_model(config)
    assert isinstance(draft, BuiltModel) and isinstance(model, BuiltModel)
    assert _types(draft) == _types(model)
    assert (draft.y0 == model.y0).all() and draft.modes0.shape == model.modes0.shape


@pytest.mark.parametrize("name", ["round_foot_walker", "space/tinkertoy_compliant"])
def test_a_draft_of_a_limit_cycle_start_solves_none_and_has_the_run_s_types(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = derive(load_config(CONFIGS / f"{name}.yaml"), {"simulation.initial": "rigid_limit_cycle"})
    given = prepare_model(derive(config, {"simulation.initial": _start(name)}))  # the walker, its start given
    monkeypatch.setattr(simulate_module, "rigid_limit_cycle_initial", _no_limit_cycle)
    monkeypatch.setattr(importlib.import_module("biped_sim.simulate.space_rigid"), "space_limit_cycle", _no_limit_cycle)
    draft = aside._draft(config)
    assert isinstance(draft, BuiltModel) and isinstance(given, BuiltModel)
    assert _types(draft) == _types(given)


COMPLIANT_CONFIGS = (
    "round_foot_walker", "compass_goswami", "torso_walker", "kneed_walker_compliant", "four_legged_walker",
)  # fmt: skip
VARIATIONS = (
    ["formulation.kind=minimal"],
    ["formulation.kind=spatial"],
    ["ground.profile={kind: steps, steps: [{at: 0.45, height: -0.005}]}"],
    ["simulation.initial=rigid_limit_cycle"],
    ["integrator.method=rk4", "integrator.dt=1e-4"],
    ["contact.model=hunt_crossley", "friction.model=lugre"],
)


@pytest.mark.slow
def test_drafts_of_random_variations_of_the_bundled_configs_have_their_runs_types() -> None:
    rng = np.random.default_rng(20261204)  # cases drawn, not chosen: a config and up to two variations
    checked, refused = 0, 0
    for _ in range(12):
        name = COMPLIANT_CONFIGS[rng.integers(len(COMPLIANT_CONFIGS))]
        picked = rng.choice(len(VARIATIONS), size=rng.integers(3), replace=False)
        try:
            config = load_config(CONFIGS / f"{name}.yaml", [o for k in picked for o in VARIATIONS[k]])
            model = prepare_model(config)
        except ConfigError:  # a variation the walker does not take (a formulation it has no model in)
            refused += 1
            continue
        draft = aside._draft(config)
        assert isinstance(draft, BuiltModel) and isinstance(model, BuiltModel), (name, picked)
        assert _types(draft) == _types(model), (name, picked)
        checked += 1
    assert checked >= 8, refused


def _no_limit_cycle(config: Config) -> None:
    raise AssertionError("a draft solved a limit cycle")


def _start(name: str) -> dict[str, float]:
    """A given start of the config ``name`` (the planar defaults, or a walker in space upright)."""
    return InitialState().model_dump() if name == "round_foot_walker" else dict.fromkeys(SPACE_STATE_KEYS, 0.0)


def test_a_draft_leaves_out_only_the_start_s_mode_update_and_only_inside_its_block() -> None:
    config = derive(Config(), {"simulation.initial.swing_angle": 0.3})  # the swing foot ahead: the update arms it
    with start_modes_deferred():
        draft = prepare_model(config)
    model = prepare_model(config)
    assert (draft.modes0[0] == model.modes0[0]).all()  # the stance foot, as the start sets it
    assert draft.modes0[1, ARMED] == 0.0 and model.modes0[1, ARMED] == 1.0


def test_a_rigid_run_on_a_warm_cache_starts_no_process() -> None:
    config = load_config(CONFIGS / "simplest_walker.yaml")  # its start given: no limit cycle, no step yet
    start = prepare_model(config)
    assert isinstance(start, RigidStart)
    rigid_step(start.walker, start.state)  # the step map, compiled or loaded
    again, process = aside.prepare_compiling_aside(config)
    assert process is None
    assert isinstance(again, RigidStart) and (again.state == start.state).all()


def test_the_rigid_measure_twins_have_the_types_a_run_measures_with() -> None:
    config = derive(load_config(CONFIGS / "simplest_walker.yaml"), {"simulation.t_end": 10.0})
    start = prepare_model(config)
    assert isinstance(start, RigidStart)
    twins = aside.measure_twins(compile_walker(start.walker))
    for twin, args in twins:
        twin.entry_for(*args)
    compiled = {twin.py_func.__qualname__: set(twin.python_entry.signatures) for twin, _ in twins}
    result = simulate(config, model=start)
    result.trajectory()
    _ = result.summary
    assert {twin.py_func.__qualname__: set(twin.python_entry.signatures) for twin, _ in twins} == compiled


@pytest.mark.slow
def test_a_cold_build_compiles_the_measures_in_a_process_that_ignores_ctrl_c(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(aside, "_cold_loop", lambda model: True)
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    model, process = aside.prepare_compiling_aside(Config())
    assert (model.modes0 == prepare_model(Config()).modes0).all()  # the real start, not the draft's
    assert process is not None and process.daemon
    os.kill(process.pid, signal.SIGINT)
    aside.join(process)
    assert process.exitcode == 0


class _NoSemaphores:
    """multiprocessing's fork context on a system without shared semaphores (a container without /dev/shm)."""

    def Event(self) -> None:  # noqa: N802 (multiprocessing's name)
        raise OSError(38, "Function not implemented")


def test_a_cold_run_without_shared_semaphores_compiles_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(aside, "_cold_loop", lambda model: True)
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    monkeypatch.setattr(aside, "get_context", lambda method: _NoSemaphores())
    model, process = aside.prepare_compiling_aside(Config())
    assert process is None and (model.modes0 == prepare_model(Config()).modes0).all()


_SECOND_DIES_AT_ONCE = """
import os
from biped_sim.config import Config
from biped_sim.simulate import aside, prepare_model
aside._cold_loop = lambda model: True
aside.available_cores = lambda: 2
aside._compile_quietly = lambda config, model, rhs_typed, flow_done: os._exit(3)  # dies before its right-hand side
model, process = aside.prepare_compiling_aside(Config())
aside.join(process)
print(process.exitcode, (model.modes0 == prepare_model(Config()).modes0).all())
"""


def test_a_run_whose_second_process_died_before_its_right_hand_side_goes_on() -> None:
    out = subprocess.run([sys.executable, "-c", _SECOND_DIES_AT_ONCE], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["3", "True"]  # not waiting for the right-hand side forever; the model is the run's


def _raise_on_sigterm(signum: int, frame: object) -> None:  # as the CLI's handler (cli.common)
    raise KeyboardInterrupt


@pytest.mark.parametrize("delay", [0.0, 0.2], ids=["at once", "in its target"])
def test_a_second_process_terminated_by_a_run_that_ended_first_says_nothing(
    capfd: pytest.CaptureFixture[str], delay: float
) -> None:
    """Terminated at once (a user error found before the process runs a line of its own) or later, it ends silently,
    and the run's own handler is back in place after the fork."""
    previous = signal.signal(signal.SIGTERM, _raise_on_sigterm)  # the run's handler, not inherited at the fork
    try:
        process = aside._fork(time.sleep, (60.0,))
        assert signal.getsignal(signal.SIGTERM) is _raise_on_sigterm
    finally:
        signal.signal(signal.SIGTERM, previous)
    time.sleep(delay)
    process.terminate()  # what multiprocessing does to a daemon at exit (a run ended by an error or Ctrl-C)
    process.join(10.0)
    assert process.exitcode == -signal.SIGTERM
    assert "Traceback" not in capfd.readouterr().err


@pytest.mark.slow
def test_a_cold_rigid_run_compiles_the_phase_integration_in_a_second_process_ended_before_the_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(aside, "begin_step", numba.njit(lambda tree: None))  # compiled here: a cold cache
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    forked = []
    fork = aside._fork
    monkeypatch.setattr(aside, "_fork", lambda target, args: forked.append(fork(target, args)) or forked[-1])
    start, process = aside.prepare_compiling_aside(load_config(CONFIGS / "simplest_walker.yaml"))
    assert isinstance(start, RigidStart) and process is None  # nothing left to wait for
    assert len(forked) == 1 and forked[0].daemon and forked[0].exitcode == 0


def test_an_unchecked_rigid_walker_has_the_checked_one_s_kernel_types(tmp_path: Path) -> None:
    text = (CONFIGS / "kneed_walker.yaml").read_text().replace("{name: thigh_2, mass: 0.5", "{name: thigh_2, mass: 0.6")
    (tmp_path / "unlike.yaml").write_text(text)
    config = load_config(tmp_path / "unlike.yaml")
    with pytest.raises(ConfigError, match="two alike legs"):
        rigid_walker(config)  # what the run's process checks while the second compiles
    unchecked = rigid_walker(config, checked=False)  # the second process's walker: only its types matter
    ours = rigid_walker(load_config(CONFIGS / "kneed_walker.yaml"))
    assert numba.typeof(compile_walker(unchecked)) == numba.typeof(compile_walker(ours))


_LOOP_AFTER_ITS_CALLEES = """
import json
from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config, derive
from biped_sim.simulate import aside, prepare_model, simulate
from biped_sim.simulate.compliant import integrate_config
config = derive(Config(), {"simulation.t_end": 0.01})
model = prepare_model(config)
loop = aside.loop_callees(config, model)
callees = loop.rhs + loop.check + loop.shared
aside.compile_all(callees)
with recording_compilations() as compiled:
    integrate_config(config, model)
callees = [f"{k.py_func.__module__}.{k.py_func.__qualname__}" for k, _ in callees]
print(json.dumps([callees, compiled]))
"""


@pytest.mark.slow
def test_the_loop_compiled_after_its_callees_finds_them_all_in_the_cache(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # empty: the loop and its callees compile
    out = subprocess.run([sys.executable, "-c", _LOOP_AFTER_ITS_CALLEES], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    callees, compiled = json.loads(out.stdout.strip().splitlines()[-1])
    assert "biped_sim.integrate.explicit.advance_python_entry" in compiled  # the loop was compiled here
    assert "biped_sim.multibody.planar.rhs_overload" in callees  # the formulation's right-hand side and fall, ...
    assert "biped_sim.multibody.planar.fall_overload" in callees  # ... as the loop's overloads
    assert len(callees) == 10 and not set(callees) & set(compiled)  # ... but none of its callees


_STIFF_RUN_AFTER_ITS_CALLEES = """
import json
from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config, derive
from biped_sim.simulate import aside, prepare_model
from biped_sim.simulate.compliant import integrate_config
config = derive(Config(), {"simulation.t_end": 0.05, "integrator.method": "bdf"})
model = prepare_model(config)
stiff = aside.loop_callees(config, model)
callees = stiff.rhs + stiff.check + stiff.shared
aside.compile_all(callees)
with recording_compilations() as compiled:
    run = integrate_config(config, model)
callees = [f"{k.py_func.__module__}.{k.py_func.__qualname__}" for k, _ in callees]
print(json.dumps([callees, compiled, run.rhs_evals, stiff.signal_at_lowering]))
"""


@pytest.mark.slow
def test_a_stiff_run_after_its_callees_compiles_nothing(tmp_path: Path) -> None:
    """scipy's driver calls the compiled right-hand side and Jacobian, the events, the recorder and the checks from
    Python: compiled aside for the draft's types (:func:`aside.stiff_callees`), the run finds every one in the cache,
    and the second process signals once the right-hand side is in the cache, not when its lowering starts."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # empty: the callees compile
    out = subprocess.run([sys.executable, "-c", _STIFF_RUN_AFTER_ITS_CALLEES], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    callees, compiled, rhs_evals, signal_at_lowering = json.loads(out.stdout.strip().splitlines()[-1])
    assert callees[0] == "biped_sim.integrate.stiff.stiff_derivatives_python_entry" and rhs_evals > 0
    assert compiled == [] and not signal_at_lowering


_STEP_AFTER_ITS_CALLEES = """
import json
from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import load_config
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import compile_walker, rigid_step
from biped_sim.simulate import aside
from tests.conftest import CONFIGS
config = load_config(CONFIGS / "simplest_walker.yaml")
walker = rigid_walker(config)
cw = compile_walker(walker)
callees = (*aside.step_callees(cw), aside.phase_integration(cw))
for function, args in callees:
    aside.compile_for(function, args)
state = walker.state_from_legs(config.simulation.initial.model_dump())
with recording_compilations() as compiled:
    rigid_step(walker, state, sample_rate=100.0, cw=cw)  # a run's step: samples
names = [f"{k.py_func.__module__}.{k.py_func.__qualname__}" for k, _ in callees]
print(json.dumps([names, compiled]))
"""


@pytest.mark.slow
def test_the_rigid_step_compiled_after_its_callees_finds_them_all_in_the_cache(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # empty: the step map and its callees compile
    out = subprocess.run([sys.executable, "-c", _STEP_AFTER_ITS_CALLEES], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    callees, compiled = json.loads(out.stdout.strip().splitlines()[-1])
    assert "biped_sim.rigid.compiled.step_kernel_python_entry" in compiled  # the step was compiled here
    assert "biped_sim.rigid.integration.stretch" in callees  # the second process's share
    assert len(callees) == 12 and not set(callees) & set(compiled)  # ... but none of its callees


_COLD_PROBE = """
import json
from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config
from biped_sim.kernel import compile_for
from biped_sim.simulate import aside
draft = aside._draft(Config())
with recording_compilations() as compiled:
    cold = aside._cold_loop(draft)
compile_for(aside.events.system_is_leading, (draft.y0, draft.system, 0))
print(json.dumps([cold, compiled]))
"""


@pytest.mark.slow
def test_the_cold_cache_probe_looks_the_loop_up_without_compiling_it(tmp_path: Path) -> None:
    """On an empty cache the probe says cold and compiles nothing (the second process starts at once); once another
    process has compiled the probed callee, it says warm, loading nothing either."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    runs = []
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", _COLD_PROBE], env=env, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    assert runs == [[True, []], [False, []]]
