"""The compiled measure loops against the same loops run as plain Python (a Python call per sample), bit for bit.

Run as plain Python (``.py_func``), a loop calls each formulation's per-sample measure through the registry's
Python route, the route every channel took before the loops: the reference, on every formulation.
"""

from __future__ import annotations

import numpy as np
import pytest

from biped_sim.config import derive
from biped_sim.measure import loops
from biped_sim.measure.channels import attitude_channels, constraint_drift, contact_channels, hip_position
from biped_sim.measure.energy import energy_audit
from biped_sim.multibody.dispatch import measures
from biped_sim.simulate import CompliantRunResult, RigidRunResult, compliant, simulate
from biped_sim.studies.fit.problem import simulate_outcome
from biped_sim.studies.uncertainty.samples import sample_outputs
from biped_sim.testing import default_walker

FORMULATIONS = ("planar", "minimal", "spatial")


@pytest.fixture(scope="module", params=FORMULATIONS)
def run(request: pytest.FixtureRequest) -> CompliantRunResult:
    """0.7 s of the default walker (its first heel strike: both feet loaded) in one formulation."""
    config = derive(default_walker(), {"formulation.kind": request.param, "simulation.t_end": 0.7})
    result = simulate(config)
    assert isinstance(result, CompliantRunResult) and len(result.steps.strike_time) >= 1
    return result


def _plain(loop, *args) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The loop run as plain Python into a buffer shaped like ``args[-1]`` (nan-filled: every entry is written)."""
    out = np.full_like(args[-1], np.nan)
    loop.py_func(*args[:-1], out)
    return out


def _same(a: np.ndarray, b: np.ndarray) -> None:
    assert a.shape == b.shape and a.tobytes() == b.tobytes()


def test_contact_channels_are_the_per_sample_route(run: CompliantRunResult) -> None:
    model, integration = run.model, run.run
    channels = contact_channels(model, integration)
    names = measures(model.system).contact_names
    compiled = np.stack([channels[name] for name in names])
    _same(compiled, _plain(loops.contact_loop, integration.y, integration.modes, model.system, compiled))
    assert np.max(channels["normal_force"]) > 0.0  # the run touched the ground


def test_energy_drift_and_hip_are_the_per_sample_route(run: CompliantRunResult) -> None:
    model, integration = run.model, run.run
    audit = energy_audit(model, integration)
    terms = np.column_stack([audit.kinetic, audit.potential, audit.elastic])
    _same(terms, _plain(loops.energy_loop, integration.y, integration.modes, model.system, terms))
    drift = constraint_drift(model, integration)
    _same(drift, _plain(loops.violation_loop, integration.y, model.system, drift))
    hip = hip_position(model, integration)
    _same(hip, _plain(loops.hip_loop, integration.y, model.system, hip))


def test_attitude_is_the_per_sample_route(run: CompliantRunResult) -> None:
    model, integration = run.model, run.run
    attitude = attitude_channels(model, integration)
    if measures(model.system).attitude is None:
        assert attitude == {}
        return
    values = np.stack([attitude[name] for name in ("pitch", "roll", "yaw", "pitch_rate")], axis=-1)
    _same(values, _plain(loops.attitude_loop, integration.y, model.system, values))


def test_rigid_energy_and_hip_are_the_walkers() -> None:
    result = simulate(derive(default_walker(), {"dynamics": "rigid", "simulation.t_end": 2.0}))
    assert isinstance(result, RigidRunResult) and len(result.steps.strike_time) >= 2
    walker = result.walker
    energy = np.array([walker.energy(x) for x in result.state])
    hip = np.array([walker.hip(x[: walker.n_q]) for x in result.state])
    compiled = np.empty_like(energy), np.empty_like(hip)
    loops.rigid_loop(walker.params, result.state, walker.n_points, *compiled)
    _same(compiled[0], energy)
    _same(compiled[1], hip)
    assert result.energy.kinetic.tobytes() == energy[:, 0].tobytes()


MEASURED = {"contact", "energy", "violation", "hip", "attitude", "summary"}  # a compliant run's lazy measures
CHANNELS = ("energy_audit", "constraint_drift", "hip_position", "attitude_channels")


def _refuse(monkeypatch: pytest.MonkeyPatch, names: tuple[str, ...]) -> None:
    def refused(*_: object) -> None:
        raise AssertionError("a measure the study does not read was computed")

    for name in names:
        monkeypatch.setattr(compliant, name, refused)


def test_a_run_measures_its_channels_when_asked() -> None:
    config = derive(default_walker(), {"formulation.kind": "minimal", "simulation.t_end": 0.7})
    result = simulate(config)
    assert isinstance(result, CompliantRunResult) and not MEASURED & set(vars(result))
    assert result.peak_normal_force() == result.summary["peak_normal_force"]
    assert result.energy_dissipated() == result.summary["energy_dissipated"]
    assert MEASURED - {"hip", "attitude"} <= set(vars(result))


def test_a_study_computes_only_what_it_reads(monkeypatch: pytest.MonkeyPatch) -> None:
    config = derive(default_walker(), {"formulation.kind": "minimal", "simulation.t_end": 0.7})
    reference = simulate(config).summary
    _refuse(monkeypatch, (*CHANNELS, "contact_channels"))
    outcome = simulate_outcome(config.model_dump(mode="json"))  # a fit evaluation: the strikes
    assert outcome.status == reference["status"] and outcome.t_reached == reference["t_end"]
    monkeypatch.undo()
    _refuse(monkeypatch, CHANNELS)
    sample = sample_outputs(config)  # an uncertainty sample: its steps, the dissipated work and the normal force
    assert sample["status"] == "walking" and sample["peak_normal_force"] == reference["peak_normal_force"]
