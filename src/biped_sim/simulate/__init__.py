"""The Python API: one run of a config, simulated, measured and (with :func:`run`) written.

    from biped_sim import load_config, simulate
    result = simulate(load_config("configs/round_foot_walker.yaml"))
    print(result.status, result.step_periods)

:func:`prepare_model` turns a config into what the integrator needs, and is where every start is resolved
and checked (``simulation.initial: rigid_limit_cycle`` by a Newton solve on the rigid step map): the
compliant model (a :class:`~biped_sim.walkers.BuiltModel`) or, for ``dynamics: rigid``, the rigid walker
and its start. :func:`simulate` returns a :class:`RunResult` of either kind; :func:`run` also writes
``trajectory.h5``, ``summary.json``, ``steps.csv`` and ``config.yaml``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from biped_sim.config import Config, InitialState
from biped_sim.errors import ConfigError
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.rigid.limit_cycle import rigid_limit_cycle_initial
from biped_sim.rigid.start import RigidStart, rigid_start
from biped_sim.simulate.budget import check_run_size
from biped_sim.simulate.compliant import CompliantRunResult, simulate_compliant
from biped_sim.simulate.result import RunResult
from biped_sim.simulate.rigid import RigidRunResult, simulate_rigid
from biped_sim.simulate.space_rigid import (
    SpaceRunResult,
    SpaceStart,
    check_space_run_size,
    simulate_space_rigid,
    space_initial,
    space_start,
)
from biped_sim.walkers import BuiltModel, build_model

__all__ = [
    "CompliantRunResult",
    "RigidRunResult",
    "RigidStart",
    "RunResult",
    "SpaceRunResult",
    "SpaceStart",
    "initial_state",
    "prepare_model",
    "run",
    "simulate",
    "study_formulation",
]


def study_formulation(config: Config) -> str:
    """The formulation a study's runs use: minimal coordinates for a planar compliant config (the same walker, the
    same equations, fewer coordinates and no constraint drift, so each of a study's many runs is cheaper), else
    the config's own."""
    kind = config.formulation.kind
    return "minimal" if kind == "planar" and config.dynamics == "compliant" else kind


def initial_state(config: Config) -> InitialState | dict[str, float]:
    """The compliant run's initial leg state: as configured, or the rigid model's limit cycle (a walker in space:
    its own rigid model's post-strike fixed point), keyed by the walker's state keys (a kneed walker's or a torso's
    too: an :class:`InitialState` holds a compass's only)."""
    initial = config.simulation.initial
    if config.in_space:
        return space_initial(config)  # type: ignore[return-value]
    if initial == "rigid_limit_cycle":
        point = rigid_limit_cycle_initial(config)
        return InitialState(**point) if set(point) == set(InitialState.model_fields) else point
    return initial


def prepare_model(config: Config) -> BuiltModel | RigidStart | SpaceStart:
    """Build and validate what :func:`simulate` needs (ConfigError naming the field): the compliant model, or
    for ``dynamics: rigid`` the rigid walker (a walker in space: its model) and its resolved initial state."""
    if config.dynamics == "rigid" and config.in_space:
        check_space_run_size(config)  # before the start's limit cycle is sought
        return space_start(config)
    if config.dynamics == "rigid":
        start = rigid_start(config)
        check_run_size(config, 2 * len(start.state) + 4)  # state, hip, energy terms
        return start
    model = build_model(config, initial_state(config))
    formulation = formulation_of(model.system)
    if config.simulation.pushes and formulation.hip_impulse is None:
        raise ConfigError("simulation.pushes", f"the {formulation.name} formulation has no push model")
    check_run_size(config, 2 * len(model.y0) + 12 * model.n_feet + 16)  # state, modes, channels, energy
    return model


def simulate(
    config: Config,
    *,
    model: BuiltModel | RigidStart | SpaceStart | None = None,
    progress: Callable[[float], None] | None = None,
) -> RunResult:
    """Simulate ``config`` and measure the gait; writes nothing.

    ``model`` is :func:`prepare_model`'s result when the caller has built it already; ``progress(t)`` reports
    the simulated time.
    """
    model = model if model is not None else prepare_model(config)
    if isinstance(model, RigidStart | SpaceStart) != (config.dynamics == "rigid"):
        raise TypeError(f"simulate: the model given does not match dynamics: {config.dynamics}")
    if isinstance(model, SpaceStart):
        return simulate_space_rigid(config, model, progress)
    if isinstance(model, RigidStart):
        return simulate_rigid(config, model, progress)
    return simulate_compliant(config, model, progress)


def run(config: Config, out_dir: str | Path, *, progress: Callable[[float], None] | None = None) -> RunResult:
    """Simulate and write the run directory ``out_dir`` (every file atomically, summary.json last)."""
    result = simulate(config, progress=progress)
    result.write(Path(out_dir))
    return result
