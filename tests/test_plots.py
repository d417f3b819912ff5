"""`biped-sim plot` and `biped-sim animate` on the shared short run directory (2 s of the default walker)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib import animation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from biped_sim.animate import WalkerDrawing, frame_indices
from biped_sim.io.trajectory import load_run
from biped_sim.plots import RUN_FIGURES

from .conftest import invoke, one_line_error


def test_plot_writes_every_single_run_figure(short_run_dir: Path) -> None:
    result = invoke("plot", str(short_run_dir))
    assert result.exit_code == 0, result.output
    assert f"{len(RUN_FIGURES)} figures" in result.stdout
    for name in RUN_FIGURES:
        with Image.open(short_run_dir / "figures" / f"{name}.png") as image:
            assert round(image.info["dpi"][0]) == 200 and image.size[0] == 700
        assert "<svg" in (short_run_dir / "figures" / f"{name}.svg").read_text()
    n = len(RUN_FIGURES)
    assert sorted(p.suffix for p in (short_run_dir / "figures").iterdir()) == [".png"] * n + [".svg"] * n


def test_animate_writes_a_gif_with_one_frame_per_interval(short_run_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "walk.gif"
    result = invoke("animate", str(short_run_dir), "--out", str(out), "--fps", "10", "--end", "0.5")
    assert result.exit_code == 0, result.output
    assert "6 frames" in result.stdout
    with Image.open(out) as image:
        assert image.format == "GIF" and image.n_frames == 6 and image.size == (400, 320)
    assert [p.name for p in tmp_path.iterdir()] == ["walk.gif"]  # no temporary file left


def test_frame_indices_decimate_to_the_frame_rate() -> None:
    time = np.arange(0, 1001) * 1e-3
    assert list(frame_indices(time, fps=25, speed=1.0, t_start=0.0, t_end=None)) == list(range(0, 1001, 40))
    assert list(frame_indices(time, fps=10, speed=2.0, t_start=0.5, t_end=None)) == [500, 700, 900]


def test_walker_drawing_puts_the_stance_foot_on_the_ground(short_run_dir: Path) -> None:
    data = load_run(short_run_dir)
    fig = Figure()
    FigureCanvasAgg(fig)
    drawing = WalkerDrawing(data, fig)
    drawing.draw(0)
    # back to the slope frame: the stance foot's lowest arc point is at the ground (to within the penetration)
    to_slope = drawing.walker.world.T
    lowest = min(float((to_slope @ np.vstack(line.get_data()))[1].min()) for line in drawing.walker.feet)
    assert abs(lowest) < 2e-3
    hip = to_slope @ np.array([drawing.walker.hip.get_xdata()[0], drawing.walker.hip.get_ydata()[0]])
    np.testing.assert_allclose(hip, data.hip[0], atol=1e-12)
    walker = data.config.walker
    for line in drawing.walker.bodies:  # each leg reaches from the hip to its foot's centre
        leg = to_slope @ np.vstack(line.get_data())
        np.testing.assert_allclose(leg[:, 0], data.hip[0], atol=1e-9)
        assert np.hypot(*(leg[:, 1] - leg[:, 0])) == pytest.approx(walker.leg_length - walker.foot_radius, rel=1e-9)
    arrows = drawing.arrows.U, drawing.arrows.V
    assert np.hypot(*arrows).max() > 0  # the stance foot carries a force
    assert drawing.stamp.get_text() == "t =  0.000 s"


@pytest.mark.parametrize(
    ("out", "expected"),
    [
        ("walk.avi", "--out: unsupported animation type '.avi'; use .gif or .mp4"),
        ("walk.mp4", "--out: .mp4 needs ffmpeg on the PATH"),
    ],
)
def test_animate_bad_output_is_one_line_exit_2(short_run_dir: Path, tmp_path: Path, out: str, expected: str) -> None:
    if out.endswith(".mp4") and animation.writers.is_available("ffmpeg"):
        pytest.skip("ffmpeg is installed: .mp4 is supported here")
    result = invoke("animate", str(short_run_dir), "--out", str(tmp_path / out))
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith(f"error: {expected}")
    assert list(tmp_path.iterdir()) == []


def test_plot_on_a_directory_without_a_run(tmp_path: Path) -> None:
    result = invoke("plot", str(tmp_path))
    assert result.exit_code == 2
    assert result.stderr.strip() == f"error: {tmp_path}: not a finished run directory (no summary.json)"
    assert list(tmp_path.iterdir()) == []
