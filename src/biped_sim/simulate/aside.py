"""A first run's measures compiled in a second process, while this one compiles the integration loop.

On an empty compile cache a run compiles one function at a time (numba's compiler lock holds a process to one
thread): the integration loop first, then, after the integration, its measures (the step table and every channel
of its files: the measure loops and the twins Python calls). The measures do not depend on the integration, only
on the types of its arrays, so :func:`prepare_compiling_aside` starts a process that measures a stand-in of the
run (:func:`stand_in`: two samples and two heel strikes of the model in its start state) and writes what it
compiles to the on-disk cache, on a second core while this process compiles the loop; the run then loads its
measures from the cache (:func:`join`). It does so only when building the model compiled something (a cold
cache for the run's group) and the process may use more than one core; on a warm cache the run starts no process.
"""

from __future__ import annotations

import signal
from multiprocessing import get_context
from multiprocessing.process import BaseProcess

from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config
from biped_sim.integrate.driver import Integration, finish_integration
from biped_sim.integrate.recorder import COMPLETED, make_recorder
from biped_sim.measure.steps import step_table
from biped_sim.rigid.start import RigidStart
from biped_sim.simulate import SpaceStart, prepare_model
from biped_sim.simulate.compliant import CompliantRunResult
from biped_sim.simulate.warmup import available_cores
from biped_sim.walkers import BuiltModel

STAND_IN_SAMPLES = 2  # samples and heel strikes of the stand-in: a step between two strikes, a sample interval


def stand_in(model: BuiltModel) -> Integration:
    """An integration of ``model`` that stays in its start state: the array types of a real run's (which its
    measures compile for), without integrating."""
    n = STAND_IN_SAMPLES
    rec = make_recorder(len(model.y0), len(model.modes0), n, n, 0)  # a mode row per foot and joint stop
    rec.sample_t[:] = rec.strike_t[:] = range(n)
    rec.sample_y[:] = rec.strike_y[:] = model.y0
    rec.sample_modes[:] = rec.strike_modes[:] = model.modes0
    state = rec.state[0]
    state.status, state.time, state.n_samples, state.n_strikes = COMPLETED, n - 1, n, n
    return finish_integration(rec, 1.0)


def measure_stand_in(config: Config, model: BuiltModel) -> None:
    """Everything a run of ``model`` measures (its file's channels and its summary), over :func:`stand_in`."""
    run = stand_in(model)
    result = CompliantRunResult(config=config, model=model, run=run, steps=step_table(model, run), wall_time_s=0.0)
    result.trajectory()
    _ = result.summary


def _measure_quietly(config: Config, model: BuiltModel) -> None:
    """:func:`measure_stand_in` in the second process, which exits without a word if it fails: the run then
    compiles its measures itself (and reports any error of its own)."""
    try:
        measure_stand_in(config, model)
    except Exception:  # the run measures for real and reports what went wrong
        raise SystemExit(1) from None


def prepare_compiling_aside(config: Config) -> tuple[BuiltModel | RigidStart | SpaceStart, BaseProcess | None]:
    """:func:`~biped_sim.simulate.prepare_model` of ``config``, and the process that compiles its measures (None
    on a warm cache, for a rigid run, or on one core); pass it to :func:`join` before the run is measured.

    The process ignores Ctrl-C (the run's own handling reports it) and ends with this one (a daemon).
    """
    with recording_compilations() as compiled:
        model = prepare_model(config)
    if not compiled or not isinstance(model, BuiltModel) or available_cores() < 2:
        return model, None
    process = get_context("spawn").Process(target=_measure_quietly, args=(config, model), daemon=True)
    interrupt = signal.signal(signal.SIGINT, signal.SIG_IGN)  # inherited: the new interpreter ignores Ctrl-C
    try:
        process.start()
    finally:
        signal.signal(signal.SIGINT, interrupt)
    return model, process


def join(process: BaseProcess | None) -> None:
    """Wait for the process of :func:`prepare_compiling_aside` to end (nothing to wait for: None)."""
    if process is not None:
        process.join()
