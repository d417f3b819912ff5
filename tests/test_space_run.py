"""A rigid run of a walker in space (a described walker in space, dynamics: rigid): its step map walked, measured
and written as a planar rigid run is, pushed sideways, and its falls and bad starts."""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest

from biped_sim.config import derive, load_config
from biped_sim.io.references import Reference, ReferenceSpec
from biped_sim.io.trajectory import load_run
from biped_sim.measure.space_pose import space_poses
from biped_sim.simulate import SpaceRunResult, simulate, warmup
from biped_sim.studies import space_basin
from biped_sim.studies.basin import CONVERGED, FELL, BasinSpec, map_basin, parse_axis
from biped_sim.studies.fit.evaluate import Evaluator
from biped_sim.studies.fit.optimize import run_fit
from biped_sim.studies.fit.parameters import parse_parameter
from biped_sim.studies.fit.problem import FitProblem
from biped_sim.studies.fit.stats import summarize
from biped_sim.studies.fit.synthetic import synthetic_reference_data
from biped_sim.walkers.space_geometry import TO_SPATIAL
from biped_sim.walkers.space_walker import BODY_NAMES
from tests.conftest import invoke, one_line_error
from tests.test_space_compliant import GAIT, RIGID_PERIOD

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
TINKERTOY = CONFIGS / "space" / "tinkertoy.yaml"
RIGID_LENGTH = 0.46483907  # docs/guide/rigid.md, the toy's gait
STARTED = "simulation.initial=" + repr(GAIT).replace("'", '"')


def toy(*overrides: str) -> SpaceRunResult:
    """The toy's rigid run from its gait's post-strike state (given: the search takes a minute), 10 samples a second."""
    result = simulate(load_config(TINKERTOY, [STARTED, "output.sample_rate=10", *overrides]))
    assert isinstance(result, SpaceRunResult)
    return result


def pushed(impulse: str, *overrides: str) -> SpaceRunResult:
    return toy(f"simulation.pushes=[{{time: 1.5, impulse: {impulse}}}]", *overrides)


def test_the_toys_run_walks_its_limit_cycle_and_writes_its_steps(tmp_path: Path) -> None:
    """Period and length the gait's (to its 8 digits), heading and bank the section's mirrored on the right leg's
    steps, width and sway repeating, energy balanced; steps.csv, trajectory.h5 (state in the run's frame, hip in 3D)
    and the loaded run agree, and the 3D drawing reads it."""
    result = toy("simulation.max_steps=4")
    frame = result.to_pandas()
    assert result.status == "walking" and len(frame) == 4 and list(frame["foot"]) == [1, 0, 1, 0]
    np.testing.assert_allclose(result.step_periods, RIGID_PERIOD, atol=1e-6)
    np.testing.assert_allclose(result.step_lengths, RIGID_LENGTH, atol=1e-6)
    side = np.where(frame["foot"] == 0, 1.0, -1.0)
    np.testing.assert_allclose(side * frame["heading"], GAIT["heading"], atol=1e-6)
    np.testing.assert_allclose(side * frame["bank"], GAIT["bank"], atol=1e-6)
    np.testing.assert_allclose(frame["width"][:2], frame["width"][2], rtol=1e-5)
    np.testing.assert_allclose(frame["sway"][:2], frame["sway"][2], rtol=1e-5)
    assert result.summary["energy_residual_max_relative"] < 1e-9
    assert result.summary["energy_dissipated"]["impact"] > 0.0
    result.write(tmp_path / "run")
    csv = pd.read_csv(tmp_path / "run" / "steps.csv")
    assert list(csv.columns[-4:]) == ["width [m]", "heading [rad]", "sway [m]", "bank [rad]"]
    with h5py.File(tmp_path / "run" / "trajectory.h5") as f:
        assert f.attrs["dynamics"] == "rigid" and f["hip"].shape == (len(result.time), 3)
        assert list(f["attitude"].attrs["bodies"]) == BODY_NAMES  # the compliant model's bodies, as RunData reads
        contacts = f["strikes/post_impact"][:, 8:]  # each strike's new contact point, the run's frame
    np.testing.assert_allclose(np.linalg.norm(np.diff(contacts, axis=0), axis=1), result.step_lengths, rtol=1e-12)
    run = load_run(tmp_path / "run")
    assert run.dynamics == "rigid" and run.state.shape == (len(result.time), 10)
    np.testing.assert_array_equal(run.steps["bank"], frame["bank"].to_numpy())
    drawn = space_poses(run)  # the 3D drawing's legs: the hinge's midpoint where the run put the hip
    np.testing.assert_allclose(drawn.hip, run.hip, atol=1e-12)
    first = run.time < result.heel_strike_times[0]  # the left foot on the ground, drawn down to its contact point
    left = drawn.feet[first, 0]
    lowest = left[np.arange(len(left)), np.nanargmin(left[:, :, 1], axis=1)]
    contact = np.column_stack([run.state[first, 8:10], np.zeros(len(left))]) @ TO_SPATIAL.T
    np.testing.assert_allclose(lowest, contact, rtol=0, atol=1e-15)
    at_strikes = np.searchsorted(run.time, result.heel_strike_times)  # the legs' attitudes, as a spatial run's
    landing = run.leg_angles()[at_strikes, frame["foot"].to_numpy()]
    assert run.body_names == BODY_NAMES == ["left", "right"]
    np.testing.assert_allclose(landing, frame["stance_angle"], atol=1e-12)


@pytest.mark.slow
def test_the_toys_run_from_its_rigid_limit_cycle_repeats_its_period_and_length_to_the_newton_tolerance() -> None:
    """``simulation.initial: rigid_limit_cycle`` (the search without a guess, about 20 CPU s): every step the same
    to 1e-10, the gait's documented period and length to their 8 digits."""
    result = simulate(load_config(TINKERTOY, ["simulation.max_steps=4", "output.sample_rate=10"]))
    assert np.ptp(result.step_periods) < 1e-10 and np.ptp(result.step_lengths) < 1e-10
    np.testing.assert_allclose(result.step_periods, RIGID_PERIOD, atol=5e-9)
    np.testing.assert_allclose(result.step_lengths, RIGID_LENGTH, atol=5e-9)


def test_a_sideways_push_changes_the_steps_and_the_toy_recovers() -> None:
    """A lateral push (pz, to the walker's right) of 0.005 at t = 1.5 changes the periods by up to 2 % and they
    come back to the gait's (the multipliers' moduli 0.84: 1e-4 after 45 steps); pushes alike to either side do
    alike; the energy balance holds the push's work."""
    result = pushed("[0.0, 0.0, 0.005]", "simulation.max_steps=50", "simulation.t_end=60")
    deviation = np.abs(result.step_periods - RIGID_PERIOD)
    assert deviation.max() > 1e-2 and deviation[-5:].max() < 2e-4
    push = result.summary["pushes"][0]
    assert push["impulse"] == [0.0, 0.0, 0.005] and push["work"] != 0.0
    assert result.summary["energy_residual_max_relative"] < 1e-9


def test_a_hard_sideways_push_is_a_fall_with_its_reason() -> None:
    result = pushed("[0.0, 0.0, 0.3]")
    assert result.status == "fell" and result.status_reason.startswith("the hip within 0.05 leg lengths")
    assert result.stop_time == result.t_final < 5.0 and len(result.heel_strike_times) == 2
    assert np.isfinite(result.summary["energy_residual_max_relative"])


def test_a_run_in_space_without_its_start_is_one_line_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = invoke("run", str(TINKERTOY), "--set", "simulation.initial={}", "--out", str(out))
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith("error: simulation.initial")
    assert not out.exists()


@pytest.mark.slow
def test_the_toys_basin_on_its_section_holds_its_gait_and_loses_the_starts_far_from_it() -> None:
    """Nine cells around the gait over bank and roll rate (+-0.02, +-0.04), 10 steps: the gait's own cell converges,
    the others fall within 3 steps (the toy's basin is narrow sideways)."""
    spec = BasinSpec(
        load_config(TINKERTOY, [STARTED]), parse_axis("x", "bank=-0.0292:0.0108:3"),
        parse_axis("y", "omega_x=-0.106:-0.026:3"), steps=10, tolerance=1e-2,
    )  # fmt: skip
    basin = map_basin(spec, None)
    expected = np.full((3, 3), FELL)
    expected[1, 1] = CONVERGED
    np.testing.assert_array_equal(basin.outcome, expected)
    assert basin.steps[1, 1] == 10 and basin.steps[basin.outcome == FELL].max() <= 3


def test_a_basin_in_space_from_a_given_start_takes_the_gait_near_it_without_the_search(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The start given (the gait's keys): its gait comes from Newton there (the search, 10-20 CPU s, patched to
    fail), the gait's own cell converges and the cells 0.1 rad further banked fall."""

    def no_search(*_: object) -> None:
        raise AssertionError("the search without a guess ran")

    monkeypatch.setattr(space_basin, "space_limit_cycle", no_search)
    spec = BasinSpec(
        load_config(TINKERTOY, [STARTED]), parse_axis("x", "bank=-0.00924861:0.09075139:2"),
        parse_axis("y", "omega_x=-0.06623178:-0.05623178:2"), steps=10, tolerance=1e-2,
    )  # fmt: skip
    basin = map_basin(spec, None)
    assert basin.fixed_point is not None and basin.cycle is not None and basin.cycle.converged
    assert max(abs(basin.fixed_point[key] - value) for key, value in GAIT.items()) < 1e-7
    assert basin.outcome[0, 0] == CONVERGED and (basin.outcome[:, 1] == FELL).all()


@pytest.mark.parametrize(
    ("config", "axis", "message"),
    [
        (
            "tinkertoy.yaml",
            "swing_angle=0.2:0.3:3",
            "error: --x: swing_angle is not a key of simulation.initial (heading,",
        ),
        ("tinkertoy_compliant.yaml", "bank=-0.02:0.02:3", "error: dynamics: a basin of a walker in space walks its"),
    ],
)
def test_a_basin_in_space_off_its_section_or_compliant_is_one_line(config: str, axis: str, message: str) -> None:
    """The hinge angle is no section coordinate (the trailing foot on the ground fixes it); a compliant walker in
    space has no step map to walk."""
    result = invoke("basin", str(TINKERTOY.with_name(config)), "--x", axis, "--y", "omega_x=-0.1:0.1:3")
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith(message)


@pytest.mark.slow
def test_a_fit_recovers_the_toys_hidden_hip_width_from_its_step_periods() -> None:
    """The toy's first five step periods from its gait's start at hip width 0.34 (the config's 0.3624), rounded to
    1e-6 with the rounding's std: the fit finds 0.34 within three standard errors, converged (about 70 runs)."""
    start = load_config(TINKERTOY, [STARTED, "simulation.t_end=8"])
    data = synthetic_reference_data(derive(start, {"walker.parameters.hip_width": 0.34}), 5, 0.0, 0, decimals=6)
    data["std"] = [1e-6 / math.sqrt(12.0)] * 5
    reference = Reference(Path("synthetic"), ReferenceSpec.model_validate(data))
    problem = FitProblem(start, reference, (parse_parameter("walker.parameters.hip_width=0.30:0.42", start),))
    evaluator = Evaluator(problem, None)
    (estimate,) = summarize(run_fit(evaluator), evaluator).estimates
    assert estimate.standard_error is not None and abs(estimate.value - 0.34) < 3.0 * estimate.standard_error < 1e-5


def test_a_rigid_run_in_space_is_a_warm_up_group_of_its_own_in_warmup_all() -> None:
    """Its flow is not the planar step map's: a planar rigid warm-up does not compile it."""
    group = warmup.group_of(load_config(TINKERTOY))
    assert group == (*warmup.RIGID_SPACE, "flat") != warmup.group_of(load_config(CONFIGS / "simplest_walker.yaml"))
    assert group in {warmup.group_of(config) for config in warmup.warm_up_configs(True)}
