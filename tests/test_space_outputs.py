"""What a user sees of a walker in space: the lateral step columns (width, heading, sway, bank) of its step table,
steps.csv and trajectory.h5 (docs/guide/outputs.md)."""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest

from biped_sim.config import load_config
from biped_sim.measure.steps import LATERAL_STEP_COLUMNS, STEP_COLUMNS
from biped_sim.simulate import simulate
from tests.test_space_compliant import GAIT, KUO, KUO_GAIT, tinkertoy

LATERAL = [name for name, _ in LATERAL_STEP_COLUMNS]


def started(gait: dict[str, float]) -> str:
    return "simulation.initial=" + repr(gait).replace("'", '"')


@pytest.mark.slow
def test_a_planar_walker_written_in_space_has_no_width_sway_heading_or_bank(tmp_path: Path) -> None:
    """The Kuo compass with hip width 0 started on its gait's sagittal part: both feet in one plane, two strikes;
    the lateral columns are written to steps.csv and trajectory.h5 after the planar ones."""
    sagittal = dict(KUO_GAIT, heading=0.0, bank=0.0, omega_x=0.0, omega_z=0.0)
    overrides = ["walker.space.hip_width=0", "contact.stiffness=1e5", "simulation.t_end=1.6", started(sagittal)]
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
