"""Bad numbers and runs that could never end are refused in one line; blow-ups are 'diverged', with a reason."""

from __future__ import annotations

import importlib
import json
import math
import typing
from pathlib import Path

import numpy as np
import pytest
from pydantic import BaseModel
from typer.testing import CliRunner

from biped_sim import config_from_dict, simulate
from biped_sim.cli import app
from biped_sim.config import Config, is_number_annotation
from biped_sim.errors import ConfigError
from biped_sim.integrate import blowup
from biped_sim.integrate.driver import stop_reason
from biped_sim.integrate.recorder import RUNNING, make_recorder
from biped_sim.multibody.dispatch import make_workspace
from biped_sim.simulate import prepare_model
from biped_sim.walkers import build_model

from .conftest import DEFAULT_CONFIG


def number_fields(model: type[BaseModel], prefix: str = "") -> list[str]:
    """Dotted keys of every numeric field of the schema (sub-sections followed)."""
    keys = []
    for name, field in model.model_fields.items():
        annotation = field.annotation
        if typing.get_origin(annotation) is list:  # simulation.pushes: a list of records, tests/test_pushes.py
            continue
        sub = _models(annotation)  # walker: its first member, the default compass
        if sub:
            keys += number_fields(sub[0], f"{prefix}{name}.")
        elif is_number_annotation(annotation):
            keys.append(f"{prefix}{name}")
    return keys


def _models(annotation: typing.Any) -> list[type[BaseModel]]:
    """The models a field's type names (an optional section's, a union's members, Annotated ones unwrapped)."""
    if isinstance(annotation, type):
        return [annotation] if issubclass(annotation, BaseModel) else []
    if typing.get_origin(annotation) is typing.Annotated:
        return _models(typing.get_args(annotation)[0])
    return [model for arg in typing.get_args(annotation) for model in _models(arg)]


NUMBER_FIELDS = number_fields(Config)


def test_the_schema_has_the_number_fields_we_expect() -> None:
    assert {"gravity", "walker.leg_mass", "ground.slope", "simulation.t_end", "simulation.initial.stance_rate"} <= set(
        NUMBER_FIELDS
    )
    assert len(NUMBER_FIELDS) > 30


@pytest.mark.parametrize("key", NUMBER_FIELDS)
@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf", "true"])
def test_every_number_field_refuses_non_finite_values_and_booleans(key: str, value: str) -> None:
    material = {"youngs_modulus": 5e7, "poisson_ratio": 0.45}
    base = {"contact": {"materials": {"foot": dict(material), "ground": dict(material)}}} if "materials" in key else {}
    with pytest.raises(ConfigError) as info:
        config_from_dict(base, [f"{key}={value}"])
    assert info.value.field == key
    assert "finite" in info.value.reason or "expected a number" in info.value.reason


@pytest.mark.parametrize(
    ("overrides", "field", "reason"),
    [
        (["simulation.t_end=1e9"], "output.sample_rate", "GiB"),
        (["output.sample_rate=1e9"], "output.sample_rate", "GiB"),
        (["integrator.max_step=1e-300"], "integrator.max_step", "steps, over the budget"),
        (["integrator.method=rk4", "integrator.dt=1e-13"], "integrator.dt", "steps, over the budget"),
        (["integrator.method=rk4", "integrator.dt=20"], "integrator.dt", "longer than simulation.t_end"),
        (["dynamics=rigid", "walker.kind=simplest", "simulation.t_end=1e9"], "output.sample_rate", "GiB"),
        (["contact.stiffness=10"], "contact.stiffness", "too soft"),
        (["simulation.t_end=0.3", "output.sample_rate=0.1"], "output.sample_rate", "no sample after the start"),
        (["walker.leg_mass=1e7"], "contact.stiffness", "too soft"),
    ],
)
def test_runs_that_would_never_end_or_fit_are_refused_before_they_start(
    overrides: list[str], field: str, reason: str
) -> None:
    with pytest.raises(ConfigError) as info:
        prepare_model(config_from_dict({}, overrides))
    assert info.value.field == field and reason in info.value.reason


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        (["integrator.rtol=1e-300"], "integrator.rtol"),
        (["integrator.rtol=10"], "integrator.rtol"),
        (["gravity=1e300"], "gravity"),
    ],
)
def test_tolerances_and_gravity_that_mean_nothing_are_refused(overrides: list[str], field: str) -> None:
    with pytest.raises(ConfigError) as info:
        config_from_dict({}, overrides)
    assert info.value.field == field


def test_a_directory_or_a_binary_file_as_config_is_one_line_exit_2(tmp_path: Path) -> None:
    binary = tmp_path / "walker.yaml"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    runner = CliRunner()
    for target, reason in ((tmp_path, "is a directory"), (binary, "not a UTF-8 text file")):
        result = runner.invoke(app, ["run", str(target), "--out", str(tmp_path / "out")])
        assert result.exit_code == 2
        assert reason in result.output and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["limit-cycle", "configs/simplest_walker.yaml", "--guess", "[.nan, -0.2, -0.2, -0.04]"], "--guess"),
        (["bifurcation", "configs/simplest_walker.yaml", "--from", "nan"], "--from"),
    ],
)
def test_non_finite_study_options_are_one_line_exit_2(args: list[str], message: str, tmp_path: Path) -> None:
    root = DEFAULT_CONFIG.parents[1]
    args = [str(root / a) if a.startswith("configs/") else a for a in args]
    result = CliRunner().invoke(app, [*args, *(["--out", str(tmp_path / "b")] if args[0] == "bifurcation" else [])])
    assert result.exit_code == 2 and message in result.output
    assert "Traceback" not in result.output


@pytest.mark.parametrize(
    ("overrides", "reason"),
    [
        (["integrator.method=euler", "integrator.dt=1e-3", "contact.stiffness=1e12"], "energy residual"),
        (["integrator.method=euler", "contact.stiffness=1e12"], "energy residual"),  # blows up between 1 kHz samples
        (["integrator.method=rk4", "integrator.dt=3e-3"], "between two checks"),
    ],
)
def test_a_blown_up_integration_is_diverged_whatever_the_sample_rate(overrides: list[str], reason: str) -> None:
    """The checks see the loop's steps, not the samples: the same status, reason and time at 1 kHz and 100 kHz."""
    summaries = [
        simulate(config_from_dict({}, [*overrides, "simulation.t_end=0.3", f"output.sample_rate={rate}"])).summary
        for rate in (1000, 100_000)
    ]
    for summary in summaries:
        assert summary["status"] == "diverged" and reason in summary["status_reason"], summary["status_reason"]
        assert 0.0 < summary["stop_time"] < 0.3
        json.dumps(summary, allow_nan=False)  # valid JSON: null, never NaN
    assert [(s["status_reason"], s["stop_time"]) for s in summaries] == [(summaries[0]["status_reason"],
                                                                       summaries[0]["stop_time"])] * 2  # fmt: skip


def test_a_check_stops_a_state_whose_energy_came_from_nowhere() -> None:
    """What the loops (and the stiff driver, from Python) call at their checks: 2 m g l of work from nowhere."""
    model = build_model(config_from_dict({}))
    rec = make_recorder(len(model.y0), len(model.modes0), 2, 2, 0)
    blowup.start_checks(rec, model.system, model.y0, model.modes0)
    scales = blowup.Scales(model.total_mass * 9.81 * model.leg_length, model.leg_length)
    work = make_workspace(model.system)
    blowup.check(0.5, model.y0, model.system, model.modes0, work, rec.state, scales, False)
    assert rec.state[0].status == RUNNING and rec.state[0].check_residual == 0.0  # the start balances exactly
    y = model.y0.copy()
    y[-1] += 2.0 * scales.energy
    blowup.check(0.5, y, model.system, model.modes0, work, rec.state, scales, False)
    assert rec.state[0].status == RUNNING  # not due: the next check is 1 ms after the last
    blowup.check(0.5 + blowup.CHECK_INTERVAL, y, model.system, model.modes0, work, rec.state, scales, False)
    assert stop_reason(rec.state[0]) == "energy residual 2 m g l: the integration blew up"


def test_fixed_step_runs_that_walk_are_not_called_diverged() -> None:
    result = simulate(config_from_dict({}, ["integrator.method=euler", "integrator.dt=1e-4", "simulation.t_end=1"]))
    assert result.status == "walking" and result.summary["status_reason"] is None
    assert result.summary["n_steps"] >= 2


def test_a_physical_fall_stays_fell_and_says_which_limit_it_passed() -> None:
    result = simulate(config_from_dict({}, ["ground.slope=0.2", "simulation.t_end=2"]))
    assert result.status == "fell" and "simulation.fall_hip_height" in result.summary["status_reason"]
    assert result.summary["energy_residual_max_relative"] < 1e-6


@pytest.mark.parametrize("dynamics", ["compliant", "rigid"])
@pytest.mark.parametrize(
    ("overrides", "reason"),
    [
        (["simulation.fall_leg_angle=0.3"], "a leg past simulation.fall_leg_angle"),
        (["simulation.initial.stance_rate=0.5", "formulation.kind=minimal"], "hip"),
    ],
)
def test_a_fall_names_its_criterion_in_compliant_and_rigid_runs(
    dynamics: str, overrides: list[str], reason: str
) -> None:
    if dynamics == "rigid":
        overrides = [o for o in overrides if not o.startswith("formulation")]
        reason = "a leg past" if reason == "hip" else reason  # the rigid compass topples over its leg first
    summary = simulate(config_from_dict({}, [*overrides, "simulation.t_end=3", f"dynamics={dynamics}"])).summary
    assert summary["status"] == "fell" and reason in summary["status_reason"], summary["status_reason"]


@pytest.mark.parametrize(
    ("overrides", "reason"),
    [  # the wheel balanced on its spoke (hip over the foot) stays there; a riser in the swing foot's way
        (["walker.kind=rimless_wheel", "ground.slope=0.01", "simulation.initial.stance_angle=0.01",
          "simulation.initial.stance_rate=0"], "no heel strike within 20 sqrt(l / g)"),
        (["ground.profile={kind: steps, steps: [{at: 0.2, height: 0.05}]}"], "the swing foot met the ground profile"),
    ],
)  # fmt: skip
def test_a_rigid_stall_or_trip_is_a_fall_that_says_so(overrides: list[str], reason: str) -> None:
    summary = simulate(config_from_dict({}, ["dynamics=rigid", "simulation.t_end=20", *overrides])).summary
    assert summary["status"] == "fell" and reason in summary["status_reason"], summary["status_reason"]


def test_a_rigid_run_past_its_wall_time_budget_ends_with_status_timeout() -> None:
    config = config_from_dict(
        {}, ["dynamics=rigid", "walker.kind=simplest", "ground.slope=0.009", "simulation.max_wall_time=1e-9"]
    )
    result = simulate(config)
    assert result.status == "timeout"
    assert result.summary["stop_time"] is not None and math.isfinite(result.summary["t_end"])
    assert "max_wall_time" in result.summary["status_reason"]


def test_run_on_a_full_disk_is_one_line_exit_1_and_leaves_no_run(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import errno

    def no_space(self: Path, data: bytes) -> int:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_bytes", no_space)
    out = tmp_path / "run"
    result = CliRunner().invoke(
        app, ["run", str(DEFAULT_CONFIG), "--set", "simulation.t_end=0.2", "--out", str(out), "-q"]
    )
    assert result.exit_code == 1
    assert "trajectory.h5: No space left on device" in result.output and "Traceback" not in result.output
    assert not (out / "summary.json").exists() and not list(out.glob(".*tmp"))


@pytest.mark.parametrize("command", ["run", "validate", "bifurcation"])
def test_an_output_location_under_a_file_is_refused_before_computing(tmp_path: Path, command: str, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    module, name = {
        "run": ("biped_sim.cli.run_commands", "prepare_compiling_aside"),
        "validate": ("biped_sim.studies.validation", "run_validation"),
        "bifurcation": ("biped_sim.studies.bifurcation", "bifurcation_diagram"),
    }[command]
    monkeypatch.setattr(importlib.import_module(module), name, lambda *a, **k: pytest.fail("computed first"))
    config = str(
        DEFAULT_CONFIG.parent / ("simplest_walker.yaml" if command == "bifurcation" else "round_foot_walker.yaml")
    )
    args = {"run": ["run", config], "validate": ["validate"], "bifurcation": ["bifurcation", config]}[command]
    result = CliRunner().invoke(app, [*args, "--out", str(blocker / "out")])
    assert result.exit_code == 2 and "a_file is a file" in result.output


def test_a_rewritten_run_directory_says_what_it_replaced_and_drops_old_figures(tmp_path: Path) -> None:
    out = tmp_path / "run"
    base = ["run", str(DEFAULT_CONFIG), "--out", str(out), "-q", "--set", "simulation.t_end=0.2"]
    assert CliRunner().invoke(app, base).exit_code == 0
    (out / "figures").mkdir()
    (out / "figures" / "old.png").write_bytes(b"old")
    result = CliRunner().invoke(app, [*base, "--set", "ground.slope=0.018"])
    assert result.exit_code == 0 and "replaced the run of config" in result.output
    assert not (out / "figures").exists()


def test_a_reference_file_that_lists_itself_is_one_line(tmp_path: Path) -> None:
    ref = tmp_path / "ref.yaml"
    ref.write_text(
        "experiment: x\ncitation: {authors: [A B], title: T, year: 2000}\nsource: {kind: table}\n"
        "quantity: {name: step_period, unit: s}\nvalues: [0.5, 0.5]\npublished_errors: [ref.yaml]\n"
    )
    from biped_sim.io.references import load_reference

    with pytest.raises(ConfigError, match="a cycle"):
        load_reference(ref)


@pytest.mark.parametrize(("option", "value"), [("--fps", "nan"), ("--speed", "0"), ("--end", "-1")])
def test_animation_options_must_be_finite(tmp_path: Path, option: str, value: str) -> None:
    result = CliRunner().invoke(app, ["animate", str(tmp_path), "--out", str(tmp_path / "a.gif"), option, value])
    assert result.exit_code == 2 and option in result.output


def test_a_nan_step_size_ends_the_run_as_diverged() -> None:
    """A NaN never compares below the minimum step: the control must still stop (it once looped for ever)."""
    from biped_sim.integrate.explicit import _control
    from biped_sim.integrate.recorder import DIVERGED, DIVERGENCE_REASONS, LOOP_STATE, NONFINITE

    state = np.zeros(1, dtype=LOOP_STATE).view(np.recarray)
    accepted, _ = _control.py_func(math.inf, False, 0.25, math.nan, 4, state[0])
    assert not accepted and state[0].status == DIVERGED and state[0].reason == NONFINITE
    assert state[0].stop_time == 0.25 and DIVERGENCE_REASONS[NONFINITE] == "non-finite state"


@pytest.mark.parametrize("method", ["dopri5", "radau"])
def test_a_compliant_run_past_its_wall_time_budget_ends_with_status_timeout(method: str) -> None:
    config = config_from_dict({}, [f"integrator.method={method}", "simulation.max_wall_time=0.05"])
    result = simulate(config)
    assert result.status == "timeout" and result.summary["status_reason"] == "simulation.max_wall_time reached"
    assert result.summary["stop_time"] == result.summary["t_end"] < config.simulation.t_end


@pytest.mark.slow  # 200000 tiny steps: about 5 s
def test_a_step_size_control_that_cannot_make_progress_ends_as_diverged() -> None:
    result = simulate(config_from_dict({}, ["integrator.atol=1e-300", "simulation.t_end=2"]))
    assert result.status == "diverged" and "step-size control is stuck" in result.summary["status_reason"]
