"""What a user sees of a walker in space: the lateral step columns (width, heading, sway, bank) of its step table,
steps.csv and trajectory.h5 (docs/guide/outputs.md)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pandas as pd
import pytest

from biped_sim import config_from_dict
from biped_sim.config import load_config
from biped_sim.errors import ConfigError
from biped_sim.measure.steps import LATERAL_STEP_COLUMNS, STEP_COLUMNS
from biped_sim.multibody.dispatch import formulation_of, measures
from biped_sim.simulate import prepare_model, simulate
from tests.conftest import invoke, one_line_error
from tests.test_space_compliant import GAIT, KUO, KUO_GAIT, RIGID_PERIOD, TINKERTOY, tinkertoy

LATERAL = [name for name, _ in LATERAL_STEP_COLUMNS]


def started(gait: dict[str, float]) -> str:
    return "simulation.initial=" + repr(gait).replace("'", '"')


@pytest.mark.slow
def test_a_planar_walker_written_in_space_has_no_width_sway_heading_or_bank(tmp_path: Path) -> None:
    """The Kuo compass with hip width 0 started on its gait's sagittal part: both feet in one plane, two strikes;
    the lateral columns are written to steps.csv and trajectory.h5 after the planar ones."""
    sagittal = dict(KUO_GAIT, heading=0.0, bank=0.0, omega_x=0.0, omega_z=0.0)
    overrides = ["walker.parameters.hip_width=0", "contact.stiffness=1e5", "simulation.t_end=1.6", started(sagittal)]
    result = simulate(load_config(KUO, overrides))
    frame = result.to_pandas()
    assert len(frame) == 2 and list(frame.columns) == [name for name, _ in STEP_COLUMNS] + LATERAL
    assert np.abs(frame[LATERAL].to_numpy()[0]).max() < 1e-12
    assert np.abs(frame[["heading", "bank"]].to_numpy()[1]).max() < 1e-12
    result.write(tmp_path / "run")
    csv = pd.read_csv(tmp_path / "run" / "steps.csv")
    assert list(csv.columns[-4:]) == ["width [m]", "heading [rad]", "sway [m]", "bank [rad]"]
    with h5py.File(tmp_path / "run" / "trajectory.h5") as f:
        assert f["steps/width"].attrs["units"] == "m"
        np.testing.assert_array_equal(f["steps/sway"][:], frame["sway"].to_numpy())


@pytest.mark.slow
def test_the_tinkertoys_lateral_columns_repeat_every_two_steps() -> None:
    """Started on its rigid gait: heading and bank alternate in sign, near the rigid section's (mirrored on the right
    leg's steps), and width and sway repeat after two steps (within the compliant contact's drift)."""
    frame = simulate(tinkertoy("simulation.t_end=4.5")).to_pandas()
    assert len(frame) == 4
    side = np.where(frame["foot"] == 0, 1.0, -1.0)  # foot 0, the left leg, is the rigid section's stance leg
    np.testing.assert_allclose(side * frame["heading"], GAIT["heading"], rtol=0.02)
    np.testing.assert_allclose(side * frame["bank"], GAIT["bank"], rtol=0.15)
    np.testing.assert_allclose(frame["width"][3], frame["width"][1], rtol=1e-2)
    np.testing.assert_allclose(frame["sway"][3], frame["sway"][1], rtol=5e-2)
    assert frame["width"][1] > 0.3624 and frame["sway"][1] > 0.0  # the hip width, splayed by the ring feet


def centre_of_mass(y: np.ndarray, system: Any) -> tuple[np.ndarray, np.ndarray]:
    """(position, velocity) of a spatial state's centre of mass in the slope frame."""
    nb = system.body_mass.shape[0]
    mass = system.body_mass / system.body_mass.sum()
    return mass @ y[: 7 * nb].reshape(nb, 7)[:, :3], mass @ y[7 * nb : 14 * nb].reshape(nb, 7)[:, :3]


def test_a_lateral_push_gives_the_walker_in_space_its_impulse_sideways() -> None:
    """The hinge's impulse is internal and the compliant contact takes none: the centre of mass's velocity jumps by
    the impulse over the walker's mass, all three components, and the joints' velocities still agree."""
    config = tinkertoy("simulation.pushes=[{time: 0.5, impulse: [0.01, -0.02, 0.05]}]")
    model = prepare_model(config)
    system = model.system
    after = formulation_of(system).hip_impulse(model.y0, system, np.array(config.simulation.pushes[0].impulse))
    jump = centre_of_mass(after, system)[1] - centre_of_mass(model.y0, system)[1]
    np.testing.assert_allclose(jump, np.array([0.01, -0.02, 0.05]) / system.body_mass.sum(), rtol=0, atol=1e-15)
    assert max(measures(system).violation(after, system)[:2]) < 1e-13


@pytest.mark.parametrize(
    ("config", "override"),
    [(None, ""), (KUO.parents[1] / "round_foot_walker.yaml", "dynamics=rigid")],
)
def test_a_lateral_push_on_a_planar_walker_is_a_one_line_error_naming_the_field(
    config: Path | None, override: str
) -> None:
    push = "simulation.pushes=[{time: 0.5, impulse: [0.1, 0.0, 0.2]}]"
    with pytest.raises(ConfigError) as caught:
        config_from_dict({}, [push]) if config is None else load_config(config, [override, push])
    assert str(caught.value).startswith("simulation.pushes: a lateral impulse (pz, the third component) needs")


@pytest.mark.slow
def test_a_lateral_push_moves_the_walker_sideways_by_the_impulse_over_its_mass_to_first_order() -> None:
    """The tinkertoy pushed sideways at mid-stance against the same run unpushed: its centre of mass moves sideways
    by (pz / M) dt (1 + O(dt)), the correction the stance foot's friction reacting (measured: -5e-3 at 0.1 ms,
    -5.1e-2 at 1 ms); the run books the push with its three components."""
    pz, at = 0.02, 0.5
    start = ("simulation.t_end=0.502", "output.sample_rate=1e4")
    plain = simulate(tinkertoy(*start))
    pushed = simulate(tinkertoy(*start, f"simulation.pushes=[{{time: {at}, impulse: [0, 0, {pz}]}}]"))
    system = plain.model.system
    errors = []
    for dt in (1e-4, 1e-3):
        k = int(np.argmin(np.abs(plain.run.t - (at + dt))))
        shift = centre_of_mass(pushed.run.y[k], system)[0] - centre_of_mass(plain.run.y[k], system)[0]
        errors.append(shift[2] / (pz / system.body_mass.sum() * dt) - 1.0)
        assert np.abs(shift[:2]).max() < 1e-2 * shift[2]  # sideways only, to first order (2e-3 at 1 ms)
    assert abs(errors[0]) < 1e-2 and errors[1] / errors[0] == pytest.approx(10.0, rel=0.1)
    assert pushed.summary["pushes"][0]["impulse"] == [0.0, 0.0, pz]


@pytest.mark.slow
def test_uncertainty_runs_on_a_walker_in_space_over_a_walker_parameter(tmp_path: Path) -> None:
    """The compliant tinkertoy started on its rigid gait with a hip mass up to 5 % of a leg's: both samples walk, and
    the hip mass reaches the runs (measured steady periods 1.092 at 0.020 and 1.146 at 0.038, against the massless
    gait's 1.007: the start is no longer their gait)."""
    result = invoke(
        "uncertainty", str(TINKERTOY), "--param", "walker.parameters.hip_mass=uniform:0:0.05", "-n", "2", "-j", "1",
        "--set", started(GAIT), "--set", "simulation.t_end=4.5", "--out", str(tmp_path / "u"), "--json",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    statistics = json.loads(result.stdout)["statistics"]
    assert statistics["status_counts"] == {"walking": 2} and statistics["outputs"]["steady_period"]["n"] == 2
    samples = pd.read_csv(tmp_path / "u" / "samples.csv").sort_values("walker.parameters.hip_mass")
    assert (np.diff(samples["steady_period"]) > 0).all() and samples["steady_period"].min() > RIGID_PERIOD


FLAT_ONLY = "a walker in space walks on flat ground only with dynamics: rigid (profiles: dynamics: compliant)"
RIGID_TOY = TINKERTOY.with_name("tinkertoy.yaml")


def test_mfpt_of_a_rigid_walker_in_space_on_random_heights_is_refused_in_one_line_naming_the_ground() -> None:
    """Random ground profiles are not walked by the rigid walker in space (its MFPT walks random slopes)."""
    for start in (["--set", started(GAIT), "-j", "1"], ["-j", "2"]):  # without a start: refused before any worker
        result = invoke("mfpt", str(RIGID_TOY), "--ground", "height", *start, "--seeds", "2", "--roughness", "0.001")
        assert result.exit_code == 2
        assert one_line_error(result.stderr) == f"error: ground.profile: {FLAT_ONLY}"
