"""A first run's measures and the loop's late callees compiled in a second process, while this one compiles the loop
(a rigid run's: the phase's integration, while this one compiles the step map's other callees).

On an empty compile cache a run compiles one function at a time (numba's compiler lock holds a process to one
thread): the integration loop first, then, after the integration, its measures (the step table and every channel of
its files: the measure loops and the twins Python calls). The measures do not depend on the integration, only on the
types of its arrays, so :func:`prepare_compiling_aside` forks a process that writes to the on-disk cache, on a
second core while this process compiles the loop: first the loop's right-hand side (with the contact forces below
it: the largest callee the loop's compile reaches early), then the loop's other callees (:func:`loop_callees`), then
the measures of a stand-in of the run (:func:`stand_in`: two samples and two heel strikes of the model in its start
state). The loop's compile and the run's measures then load them from the cache (:func:`join` waits for the process
before the run is measured). The process is forked before the model's start is settled, with a draft of the model
(its types: the start's mode update, a compile, left out); this process compiles the loop's fall check and that
update, then the loop's small late callees until only the right-hand side's own lowering remains (its callees
cached), and only then the loop, whose compile reaches it later and loads it. It does so only on a cold cache for
the run's formulation and ground (a loop callee compiled rather than loaded) and when the process may use more than
one core; on a warm cache the run starts no process. A fork, not a new interpreter: the process starts at once, with
the model, rather than some 2.5 CPU s of imports later.

A planar rigid run compiles its step map (:func:`~biped_sim.rigid.compiled.step_kernel`'s Python twin), whose
compile is half the phase's integration (:func:`phase_integration`: DOP853 over the flow, its events and samples).
When the step's first callee had to be compiled (a cold cache), a second process forked before the walker is even
checked compiles the integration, while this one checks the walker (the flow's twin), compiles the step's other
callees (:func:`step_callees`) and the twins the run's measures call (:func:`measure_twins`), then waits for it:
the step, compiled last, finds every callee in the cache. The step itself cannot go aside: it is the twin Python
calls, compiled where it is called. A rigid run in space splits its stance phase's callees between the two processes
alike (:mod:`biped_sim.simulate.space_aside`), and so does a compliant run in space that starts on the rigid limit
cycle, whose second process compiles the flow's tree before the loop's right-hand side.
"""

from __future__ import annotations

import signal
from collections.abc import Callable
from multiprocessing import get_context
from multiprocessing.process import BaseProcess
from multiprocessing.synchronize import Event
from typing import NamedTuple

import numpy as np
from numba.core.dispatcher import Dispatcher

from biped_sim._compiled_cache import in_cache, recording_compilations, signalling_lowering
from biped_sim.config import Config, derive
from biped_sim.config.space_description import SPACE_STATE_KEYS
from biped_sim.errors import ConfigError
from biped_sim.integrate import blowup, dense, recorder, stepper
from biped_sim.integrate.driver import STIFF_METHODS, Integration, explicit_loop, finish_integration
from biped_sim.integrate.recorder import COMPLETED, make_recorder
from biped_sim.kernel import Kernel, compile_for, overload_implementation
from biped_sim.measure.loops import rigid_loop
from biped_sim.measure.steps import step_table
from biped_sim.multibody import events
from biped_sim.multibody.dispatch import contact_buffers, formulation_of, make_workspace
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import CompiledWalker, compile_walker
from biped_sim.rigid.ground import clearance, riser_hit, tree_swing_foot
from biped_sim.rigid.integration import stretch
from biped_sim.rigid.kernels import guard, guard_rate, n_phases
from biped_sim.rigid.start import RigidStart
from biped_sim.rigid.tree_kernels import (
    after_phase,
    begin_step,
    skip_phase,
    tree_energy,
    tree_guard,
    tree_impact,
    tree_push,
)
from biped_sim.rigid.tree_layout import point
from biped_sim.simulate import SpaceStart, prepare_model
from biped_sim.simulate.compliant import CompliantRunResult
from biped_sim.simulate.space_aside import Callee, clearance_twin, events_share, first_callee, flow_share
from biped_sim.simulate.space_rigid import check_space_run_size
from biped_sim.simulate.warmup import available_cores
from biped_sim.walkers import BuiltModel, describe
from biped_sim.walkers.model import start_modes_deferred

STAND_IN_SAMPLES = 2  # samples and heel strikes of the stand-in: a step between two strikes, a sample interval
RHS_POLL_S = 0.05  # [s] how often a run waiting for the second process's signal looks whether it died


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


Compiles = tuple[Callee, ...]  # kernels with arguments of the types callers pass


class LoopCallees(NamedTuple):
    """The explicit loop's callees with arguments of the types it calls them with (:func:`loop_callees`); a stiff run's
    alike (:func:`stiff_callees`)."""

    rhs: Compiles  # the second process's, first: the right-hand side, then the starting step's norm
    check: Compiles  # the run's process's, first: the loop's fall check
    shared: Compiles  # the run's process from the front, the second from the back
    signal_at_lowering: bool = True  # the event is set when the right-hand side's own lowering starts, not after it


def loop_callees(config: Config, model: BuiltModel) -> LoopCallees:
    """The explicit loop's callees (a stiff method's: :func:`stiff_callees`); the arguments come from the driver's
    constructor (:func:`~biped_sim.integrate.driver.explicit_loop`).

    The right-hand side (the overload implementation the loop's ``system_rhs`` compiles, with the contact forces below
    it: the costliest callee) and the starting step's norm are the second process's; the loop's compile reaches them
    a few CPU s after its start. The loop's fall check (some 2 CPU s, reached soon after) is the run's process's,
    compiled before the model's build: the run's share is compiled until the right-hand side is typed, and a compile
    stops only between two callees. The shared ones are small, those the loop reaches last first: the formulation's
    fall, the event update, the dense output, the recorder's."""
    if config.integrator.method in STIFF_METHODS:
        return stiff_callees(model)
    y, modes = np.array(model.y0, dtype=np.float64), np.array(model.modes0, dtype=np.float64)
    loop = explicit_loop(model.system, y, modes, config.integrator.method, make_recorder(len(y), len(modes), 1, 1, 0))
    system, work, sc, rec = loop.system, loop.work, loop.sc, loop.rec
    formulation = formulation_of(system)
    return LoopCallees(
        rhs=(
            (overload_implementation(formulation.rhs), (0.0, y, system, modes, work, sc.k[0])),
            (stepper.rms_norm, (y, sc.y_dense)),  # the loop's starting step calls it
        ),
        check=((blowup.fall, (0.0, y, system, modes, work, rec.state, blowup.NO_CHECKS, 1)),),
        shared=(
            (overload_implementation(formulation.fall), (y, system)),
            (events.system_update_modes, (0.0, y, system, modes, loop.contact)),
            (dense.dense_coefficients, (loop.tab, 0.0, y, sc)),
            (dense.dense_eval, (loop.tab, 0.0, 0.0, y, sc, sc.y_new)),
            (events.system_is_leading, (y, system, 0)),
            (recorder.has_room, (rec, len(modes))),
            (recorder.record_sample, (rec, 0.0, y, modes)),
        ),
    )


def stiff_callees(model: BuiltModel) -> LoopCallees:
    """What a stiff run's driver (:mod:`~biped_sim.integrate.stiff`, scipy's Radau or BDF) calls from Python, with
    arguments of the types it passes: the kernels' twins and the jitted functions. The second process's: the
    right-hand side with its Jacobian (:func:`~biped_sim.integrate.stiff.stiff_derivatives`, the costliest), after
    which the event is set (the driver calls it at once). The run's, before the model's build: the event update and
    the blow-up check. Shared: the start's energy, the samples' recorder, the event functions, the formulation's
    fall."""
    from biped_sim.integrate.stiff import stiff_derivatives  # here: scipy.integrate adds 0.3 s to every start-up

    system = model.system
    y, modes = np.array(model.y0, dtype=np.float64), np.array(model.modes0, dtype=np.float64)
    work, rec = make_workspace(system), make_recorder(len(y), len(modes), 1, 1, 0)
    touching = np.zeros(modes.shape[0])
    return LoopCallees(
        rhs=((stiff_derivatives.twin(), (0.0, y, system, modes, work, y, np.empty((len(y), len(y))), False)),),
        check=(
            (recorder.apply_events, (0.0, y, system, modes, contact_buffers(system), rec, touching, 0)),
            (blowup.check, (0.0, y, system, modes, work, rec.state, blowup.NO_CHECKS, True)),
        ),
        shared=(
            (blowup.energy_reference, (y, system, modes)),
            (recorder.record_sample.twin(), (rec, 0.0, y, modes)),
            (events.system_event_functions.twin(), (y, system, np.empty(events.event_count(system)))),
            (formulation_of(system).fall.twin(), (y, system)),  # system_fall, from Python
        ),
        signal_at_lowering=False,
    )


def compile_all(compiles: Compiles, until: Callable[[], bool] = lambda: False) -> None:
    """Compile (and cache) each kernel for its arguments' types, in order, unless ``until()`` before it."""
    for function, args in compiles:
        if until():
            return
        compile_for(function, args)


def step_callees(cw: CompiledWalker) -> Compiles:
    """The rigid step map's callees but the phase's integration (:func:`~biped_sim.rigid.compiled.step_kernel`'s,
    compiled in the run's process while the second compiles :func:`phase_integration`), with arguments of the types
    it calls them with, those the integration calls too first (the second process then finds them in the cache): the
    phase count, the guard, the swing foot and its clearance above a profile; then a phase's skip, the phase's end and
    the impact solve below it (a stop strike's, the heel strike's too), the polish's guard rate, a riser's hit, a
    push, the energy."""
    p, plan, x = cw.params, cw.plan, np.zeros(cw.sc.y_new.shape[0])
    return (
        (n_phases, (p,)),
        (guard, (p, 0, x)),
        (tree_swing_foot, (p, x, 0.0, 0.0)),
        (clearance, (0.0, 0.0, plan.vertices, plan.ends)),
        (skip_phase, (p, 0, x)),
        (after_phase, (p, 0, x, x)),
        (tree_impact, (p, x, True, x)),
        (guard_rate, (p, 0, x, x)),
        (riser_hit, (0.0, 0.0, plan.vertices, 0.0)),
        (tree_push, (p, x, 0.0, 0.0, x)),
        (tree_energy, (p, x)),
    )


def phase_integration(cw: CompiledWalker) -> Callee:
    """The phase's integration :func:`~biped_sim.rigid.integration.stretch` (DOP853 over the flow, its events and
    samples: half the step map's compile), with arguments of the types the step calls it with."""
    x = np.zeros(cw.sc.y_new.shape[0])
    return stretch, (cw, 0, 0, 0.0, 0.0, x, np.zeros(2, dtype=np.int64))


def measure_twins(cw: CompiledWalker) -> tuple[tuple[Kernel, tuple[object, ...]], ...]:
    """The kernels a planar rigid run's measures call from Python (their twins, compiled after the walk), with
    arguments of the types they are called with: a point (the hip, a foot), a phase's guard (the fall's reason), the
    energy (the strikes' losses) and the loop over the samples."""
    p, x = cw.params, np.zeros(cw.sc.y_new.shape[0])
    samples, columns = np.zeros((STAND_IN_SAMPLES, x.shape[0])), np.zeros((STAND_IN_SAMPLES, 2))
    return (
        (point, (p, 0, x[: x.shape[0] // 2])),
        (tree_guard, (p, 0, x)),
        (tree_energy, (p, x)),
        (rigid_loop, (p, samples, 0, columns, columns)),
    )


def _compile_each_quietly(callees: Compiles) -> None:
    """Each of ``callees`` compiled for its arguments' types in the second process of a rigid run, which exits
    without a word if one fails: the run then compiles it itself (and reports any error of its own)."""
    try:
        compile_all(callees)
    except Exception:  # the run compiles it for real and reports what went wrong
        raise SystemExit(1) from None


def _fork(target: Callable[..., None], args: tuple[object, ...]) -> BaseProcess:
    """A forked daemon process running ``target(*args)``, started. It inherits, from its first instruction, Ctrl-C
    ignored (the run's own handling reports it) and SIGTERM's default action rather than the run's handler (the CLI's
    raises, which would print a traceback): a run that ends before the process, on a user error or an interrupt,
    terminates it at exit, silently, even before it has run a line of its own."""
    process = get_context("fork").Process(target=target, args=args, daemon=True)
    interrupt = signal.signal(signal.SIGINT, signal.SIG_IGN)
    terminate = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        process.start()
    finally:
        signal.signal(signal.SIGINT, interrupt)
        signal.signal(signal.SIGTERM, terminate)
    return process


def _prepare_rigid(config: Config) -> BuiltModel | RigidStart | SpaceStart:
    """A planar rigid run's :func:`~biped_sim.simulate.prepare_model` (the limit cycle's Newton on the step map
    compiles it). On a cold cache (the step map's first kernel compiled) and more than one core, a second process
    compiles the phase's integration (:func:`phase_integration`) while this one checks the walker (the flow's
    Python twin) and compiles the step's other callees (:func:`step_callees`) and the measures' twins
    (:func:`measure_twins`); the step is compiled once that process has ended (it then finds the integration in
    the cache)."""
    cw = compile_walker(rigid_walker(config, checked=False))  # the kernels' argument types, before any check
    if _compiled(begin_step, (cw.params,)) and available_cores() >= 2:  # the step's first callee: a warm cache loads it
        process = _fork(_compile_each_quietly, ((phase_integration(cw),),))
        rigid_walker(config)  # its legs checked alike: a ConfigError here ends the second process with this one
        compile_all(step_callees(cw))
        for twin, args in measure_twins(cw):
            twin.entry_for(*args)
        join(process)
    return prepare_model(config)


def _prepare_space(config: Config) -> BuiltModel | RigidStart | SpaceStart:
    """A rigid run in space's :func:`~biped_sim.simulate.prepare_model` (the limit cycle's search compiles the stance
    phase). On a cold cache (the phase's first callee compiled, :func:`.space_aside.first_callee`) and more than one
    core, a second process compiles the flow's tree (:func:`.space_aside.flow_share`) while this one checks the run's
    size and compiles its share of the phase (:func:`_compile_phase_share`); the phase is compiled once that process
    has ended (it then finds both trees in the cache)."""
    if _compiled(*first_callee()) and available_cores() >= 2:
        process = _fork(_compile_each_quietly, (flow_share(),))
        check_space_run_size(config)  # a ConfigError here ends the second process with this one
        _compile_phase_share()
        join(process)
    return prepare_model(config)


def _compile_phase_share() -> None:
    """The run's process's share of a rigid stance phase in space while a second compiles the flow's tree: the
    events' tree (:func:`.space_aside.events_share`) and the clearance's twin (the limit cycle's section calls it)."""
    compile_all(events_share())
    twin, args = clearance_twin()
    twin.entry_for(*args)


def measure_stand_in(config: Config, model: BuiltModel) -> None:
    """Everything a run of ``model`` measures (its file's channels and its summary), over :func:`stand_in`."""
    run = stand_in(model)
    result = CompliantRunResult(config=config, model=model, run=run, steps=step_table(model, run), wall_time_s=0.0)
    result.trajectory()
    _ = result.summary


def _compile_quietly(config: Config, model: BuiltModel, rhs_typed: Event, flow_done: Event | None) -> None:
    """In the second process: with ``flow_done`` (a start on the rigid limit cycle in space, cold) first the rigid
    flow's tree (:func:`.space_aside.flow_share`), then set; the loop's right-hand side (``rhs_typed`` is set once its
    callees are in the cache and only its own lowering remains, about a CPU s, less than the loop's compile takes to
    reach it; a stiff run's once it is in the cache), the starting step's norm, the shared callees, those the loop
    reaches first first (the run's process takes them from the other end meanwhile), the fall check (compiled by the
    run's process by then: loaded), then :func:`measure_stand_in`; it exits without a word if it fails: the run then
    compiles them itself (and reports any error of its own)."""
    try:
        if flow_done is not None:
            compile_all(flow_share())
            flow_done.set()
        callees = loop_callees(config, model)
        signalling = callees.rhs[0][0].py_func.__qualname__ if callees.signal_at_lowering else ""
        with signalling_lowering(signalling, rhs_typed.set):
            compile_all(callees.rhs[:1])
        rhs_typed.set()  # also when it was loaded from the cache (nothing lowered)
        compile_all(callees.rhs[1:] + callees.shared[::-1] + callees.check)
        measure_stand_in(config, model)
    except Exception:  # the run measures for real and reports what went wrong
        raise SystemExit(1) from None


def prepare_compiling_aside(config: Config) -> tuple[BuiltModel | RigidStart | SpaceStart, BaseProcess | None]:
    """:func:`~biped_sim.simulate.prepare_model` of ``config``, and the process that compiles what the run reaches
    late: a compliant run's measures and its loop's late callees (None on a warm cache, for a rigid run, or on one
    core: a planar rigid run's process has ended when this returns); pass it to :func:`join` before the run is
    measured.

    The process ignores Ctrl-C (the run's own handling reports it) and ends with this one (a daemon).
    """
    if config.dynamics == "rigid":
        return (_prepare_space(config) if config.in_space else _prepare_rigid(config)), None
    return _prepare_compliant(config)


def _cold_loop(model: BuiltModel) -> bool:
    """Whether the compile cache lacks ``model``'s loop (for its formulation and ground): one of the loop's small
    callees, :func:`~biped_sim.multibody.events.system_is_leading`, missing from it (looked up, not compiled: the
    second process starts at once, and whichever process reaches it first compiles it)."""
    return not in_cache(events.system_is_leading, (model.y0, model.system, 0))


def _compiled(function: Dispatcher, args: tuple[object, ...]) -> bool:
    """Compile ``function`` for the types of ``args`` or load it from the cache; whether it was compiled (something
    of it was missing from the cache: a first run's, which a second process is worth starting for)."""
    with recording_compilations() as compiled:
        compile_for(function, args)
    return bool(compiled)


def _prepare_compliant(config: Config) -> tuple[BuiltModel | RigidStart | SpaceStart, BaseProcess | None]:
    """A compliant run's :func:`~biped_sim.simulate.prepare_model`, and the second process of a cold cache
    (:func:`_cold_loop`) on more than one core. The process is forked with a draft of the model (:func:`_draft`)
    and compiles the loop's right-hand side first; meanwhile this process compiles the loop's fall check, resolves
    the start (a limit cycle: the rigid step map compiled), builds the model (compiling the start's mode update),
    then compiles the loop's small late callees (:func:`loop_callees`) until only the right-hand side's own
    lowering remains (or waits for it), so that its loop's compile, next, loads it when it reaches it. A start on
    the rigid limit cycle in space (:func:`_cold_space_cycle`) splits the stance phase's compile as a rigid run in
    space does: the process compiles the flow's tree before the right-hand side, this one its share after the fall
    check, and waits for the flow's tree before it seeks the limit cycle."""
    draft = _draft(config)
    rhs_typed = _shared_event() if draft is not None and _cold_loop(draft) and available_cores() >= 2 else None
    if draft is None or rhs_typed is None:
        return prepare_model(config), None
    flow_done = _shared_event() if _cold_space_cycle(config) else None
    process = _fork(_compile_quietly, (config, draft, rhs_typed, flow_done))
    callees = loop_callees(config, draft)
    compile_all(callees.check)
    if flow_done is not None:
        _compile_phase_share()
        _wait(flow_done, process)
    model = prepare_model(config)
    compile_all(callees.shared, until=lambda: rhs_typed.is_set() or not process.is_alive())
    _wait(rhs_typed, process)
    return model, process


def _cold_space_cycle(config: Config) -> bool:
    """Whether ``config`` starts on the rigid limit cycle of a walker in space whose stance phase the cache lacks
    (:func:`.space_aside.first_callee` compiled rather than loaded)."""
    return config.in_space and config.simulation.initial == "rigid_limit_cycle" and _compiled(*first_callee())


def _wait(event: Event, process: BaseProcess) -> None:
    """Wait until ``event`` is set or ``process`` has died (it then sets nothing: this process compiles alone)."""
    while process.is_alive() and not event.wait(RHS_POLL_S):
        pass


def _shared_event() -> Event | None:
    """An event both processes of a fork see, or None where the system has no shared semaphores (a container
    without /dev/shm): the run then compiles alone, as on one core."""
    try:
        return get_context("fork").Event()
    except OSError:
        return None


def _draft(config: Config) -> BuiltModel | None:
    """A model of ``config`` whose build compiles nothing, only for its types: every check of the build, the start's
    mode update left out (:func:`~biped_sim.walkers.model.start_modes_deferred`), and in place of a
    ``rigid_limit_cycle`` start (a Newton solve on the rigid step map, compiled) a stand-in with the gait's keys, the
    walker upright at rest; None when the stand-in does not build."""
    if config.simulation.initial == "rigid_limit_cycle":
        keys = SPACE_STATE_KEYS if config.in_space else describe(config).state_keys()
        config = derive(config, {"simulation.initial": dict.fromkeys(keys, 0.0)})
    try:
        with start_modes_deferred():
            draft = prepare_model(config)
    except ConfigError:
        return None  # the stand-in's own: the run's build reports the config's
    return draft if isinstance(draft, BuiltModel) else None


def join(process: BaseProcess | None) -> None:
    """Wait for the process of :func:`prepare_compiling_aside` to end (nothing to wait for: None)."""
    if process is not None:
        process.join()
