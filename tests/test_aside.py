"""A first run's measures compiled in a second process (simulate/aside.py): the stand-in compiles what a run
measures, and the process starts only on a cold compile cache."""

from __future__ import annotations

import gc
import json
import os
import signal
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numba
import pytest
from numba.core.dispatcher import Dispatcher

from biped_sim.config import Config, derive, load_config
from biped_sim.measure.steps import step_table
from biped_sim.simulate import aside, prepare_model
from biped_sim.simulate.compliant import CompliantRunResult, integrate_config
from tests.conftest import CONFIGS


def _compiled_signatures() -> set[tuple[str, str]]:
    """Every (function, signature) this process has compiled or loaded from the cache, twins included."""
    return {
        (f"{d.py_func.__module__}.{d.py_func.__qualname__}", str(signature))
        for d in gc.get_objects()
        if issubclass(type(d), Dispatcher)  # not isinstance: a dead weak proxy among the objects raises on it
        for signature in d.signatures
    }


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
    prepare_model(config)  # whatever its build compiles is now in this process
    model, process = aside.prepare_compiling_aside(config)
    assert process is None
    assert (model.y0 == prepare_model(config).y0).all()


@pytest.mark.slow
def test_a_cold_build_compiles_the_measures_in_a_process_that_ignores_ctrl_c(monkeypatch: pytest.MonkeyPatch) -> None:
    def build_compiling(config: Config) -> object:  # a build that compiles something: a cold cache
        numba.njit(lambda x: x + 1)(1)
        return prepare_model(config)

    monkeypatch.setattr(aside, "prepare_model", build_compiling)
    monkeypatch.setattr(aside, "available_cores", lambda: 2)
    _, process = aside.prepare_compiling_aside(Config())
    assert process is not None and process.daemon
    os.kill(process.pid, signal.SIGINT)
    aside.join(process)
    assert process.exitcode == 0


_LOOP_AFTER_ITS_CALLEES = """
import json
from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config, derive
from biped_sim.simulate import aside, prepare_model
from biped_sim.simulate.compliant import integrate_config
config = derive(Config(), {"simulation.t_end": 0.01})
model = prepare_model(config)
aside.compile_loop_callees(config, model)
with recording_compilations() as compiled:
    integrate_config(config, model)
callees = [f"{k.py_func.__module__}.{k.py_func.__qualname__}" for k, _ in aside.loop_callees(config, model)]
print(json.dumps([callees, compiled]))
"""


@pytest.mark.slow
def test_the_loop_compiled_after_its_callees_finds_them_all_in_the_cache(tmp_path: Path) -> None:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}  # empty: the loop and its callees compile
    out = subprocess.run([sys.executable, "-c", _LOOP_AFTER_ITS_CALLEES], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    callees, compiled = json.loads(out.stdout.strip().splitlines()[-1])
    assert "biped_sim.integrate.explicit.advance_python_entry" in compiled  # the loop was compiled here
    assert "biped_sim.multibody.planar.fall_overload" in callees  # the formulation's fall, as the loop's overload
    assert len(callees) == 9 and not set(callees) & set(compiled)  # ... but none of its callees
