"""Animation of a run: the walker walking down its slope, with contact force arrows and a time stamp.

The walker is drawn from its run directory by :mod:`biped_sim.picture`, at the poses of
:mod:`biped_sim.measure.pose`: every walker from its description (each body as its segment, its feet as arcs
or points, its joint stops marked), compliant runs (planar, minimal and spatial, in the sagittal view) and rigid
runs alike; a compliant run's feet carry their contact force as an arrow. A walker in space is drawn twice, in
its sagittal view and in 3D axes (:class:`SpaceDrawing`). The view follows the hip over the
ground's profile. Frames are decimated to ``fps`` frames per second of playback; GIF through Pillow
(matplotlib's PillowWriter), MP4 through ffmpeg when it is on the PATH.
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import animation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from biped_sim.errors import ArgumentError
from biped_sim.io.output import check_writable_dir
from biped_sim.io.trajectory import RunData
from biped_sim.measure.pose import run_poses
from biped_sim.measure.space_pose import space_poses
from biped_sim.picture import SpaceWalkerPicture, WalkerPicture, draw_ground, draw_space_ground, space_world
from biped_sim.plots import figure_style

ARROW_LENGTH_PER_WEIGHT = 0.6  # arrow length, in walker heights, of a force equal to the walker's weight
FORMATS = (".gif", ".mp4")


def check_output(out: Path) -> None:
    """Reject an unsupported file type (or .mp4 without ffmpeg) or an unusable location before any work is done."""
    if out.is_dir():
        raise ArgumentError("out", f"{out} is a directory; give a file name ending in .gif or .mp4")
    if out.suffix.lower() not in FORMATS:
        raise ArgumentError("out", f"unsupported animation type {out.suffix or '(none)'!r}; use .gif or .mp4")
    if out.suffix.lower() == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise ArgumentError("out", ".mp4 needs ffmpeg on the PATH; install it or write a .gif")
    check_writable_dir(out.parent)


def check_playback(fps: float, speed: float, t_start: float, t_end: float | None) -> None:
    """ArgumentError naming the first of ``fps``, ``speed``, ``t_start``, ``t_end`` that cannot be played back."""
    for name, value in (("fps", fps), ("speed", speed)):
        if not (math.isfinite(value) and value > 0):
            raise ArgumentError(name, f"must be a finite number > 0, got {value}")
    if not (math.isfinite(t_start) and t_start >= 0):
        raise ArgumentError("t_start", f"must be a finite time >= 0, got {t_start}")
    if t_end is not None and not (math.isfinite(t_end) and t_end > t_start):
        raise ArgumentError("t_end", f"must be a finite time after the start ({t_start}), got {t_end}")


def frame_indices(time: np.ndarray, fps: float, speed: float, t_start: float, t_end: float | None) -> np.ndarray:
    """Sample indices of the frames: one frame every ``speed / fps`` simulated seconds."""
    stop = time[-1] if t_end is None else min(t_end, time[-1])
    if stop < t_start:
        raise ArgumentError("t_start", f"after the end of the run ({time[-1]:.3f} s)")
    frame_times = np.arange(t_start, stop + 1e-12, speed / fps)
    return np.unique(np.clip(np.searchsorted(time, frame_times), 0, len(time) - 1))


class WalkerDrawing:
    """The artists of one frame (ground, walker, force arrows, time stamp) and how to place them at a sample."""

    def __init__(self, run: RunData, fig: Figure) -> None:
        self.run, self.poses = run, run_poses(run)
        first = self.poses.at(0)
        points = np.vstack([*first.segments, first.foot_centres])[:, 1] - first.hip[1]
        bottoms = first.foot_centres[:, 1] - self.poses.skeleton.foot_radius - first.hip[1]
        self.height = float(-bottoms.min()) if bottoms.min() < 0 else 1.0  # hip over the lowest foot
        self.top = max(0.3 * self.height, float(points.max()) + 0.15 * self.height)  # room for a torso or spokes
        weight = self.poses.skeleton.total_mass * run.config.gravity
        self.force_scale = ARROW_LENGTH_PER_WEIGHT * self.height / weight if weight > 0 else 0.0
        self.ax = fig.add_subplot()
        self.ax.set_aspect("equal")
        self.ax.set_xticks([])
        self.ax.set_yticks([])
        self.ax.grid(False)
        hip_x = self.poses.hip[:, 0]
        draw_ground(self.ax, run.config, hip_x.min() - 2 * self.height, hip_x.max() + 2 * self.height, self.height)
        self.walker = WalkerPicture(self.ax, self.poses.skeleton, run.config.ground.slope)
        n_feet = run.normal_force.shape[1]  # a rigid run has no contact channels: no arrows
        zeros = np.zeros(n_feet)
        self.arrows = self.ax.quiver(zeros, zeros, zeros, zeros, angles="xy", scale_units="xy", scale=1.0,
                                     color="C3", width=0.012, zorder=7)  # fmt: skip
        self.stamp = self.ax.text(0.03, 0.95, "", transform=self.ax.transAxes, va="top", family="monospace")
        nondimensional = run.summary.get("units", {}).get("time", "s") != "s"  # the simplest walker's (g = l = 1)
        self.time_unit = "" if nondimensional else " s"

    def draw(self, i: int) -> None:
        """Place every artist at sample ``i``."""
        run, pose, world = self.run, self.poses.at(i), self.walker.world
        self.walker.place(pose)
        n_feet = run.normal_force.shape[1]
        if n_feet:
            bottoms = pose.foot_centres[:n_feet] - np.column_stack([np.zeros(n_feet), self.poses.skeleton.foot_radius])
            forces = np.column_stack([run.friction_force[i], run.normal_force[i]]) * self.force_scale
            self.arrows.set_offsets((world @ bottoms.T).T)
            vectors = world @ forces.T
            self.arrows.set_UVC(vectors[0], vectors[1])
        hip = world @ pose.hip
        self.ax.set_xlim(hip[0] - 0.9 * self.height, hip[0] + 0.9 * self.height)
        self.ax.set_ylim(hip[1] - 1.25 * self.height, hip[1] + self.top)
        self.stamp.set_text(f"t = {run.time[i]:6.3f}{self.time_unit}")


class SpaceDrawing:
    """A walker in space's frame: its sagittal view beside its 3D view, both following the hip, and a time stamp."""

    def __init__(self, run: RunData, fig: Figure) -> None:
        self.run, self.poses = run, space_poses(run)
        slope, self.height = run.config.ground.slope, run.config.walker.space.leg_length()  # type: ignore[union-attr]
        self.sagittal, self.ax3d = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2, projection="3d")
        self.sagittal.set_aspect("equal")
        self.sagittal.set_xticks([])
        self.sagittal.set_yticks([])
        x = self.poses.hip[:, 0]
        draw_ground(self.sagittal, run.config, float(x.min()) - 2 * self.height, float(x.max()) + 2 * self.height, 1.0)
        self.ground: Any = None
        self.ax3d.set_box_aspect((1.0, 1.0, 1.0))
        self.ax3d.set_axis_off()
        self.walker = SpaceWalkerPicture(self.ax3d, self.sagittal, slope)
        self.stamp = self.sagittal.text(0.03, 0.95, "", transform=self.sagittal.transAxes, va="top", family="monospace")

    def draw(self, i: int) -> None:
        """Place every artist at sample ``i`` and the views around the hip."""
        self.walker.place(self.poses, i)
        slope, (x, _, z), h = self.run.config.ground.slope, self.poses.hip[i], self.height
        if self.ground is not None:
            self.ground.remove()
        self.ground = draw_space_ground(self.ax3d, slope, (x - 0.6 * h, x + 0.6 * h), (z - 0.6 * h, z + 0.6 * h))
        hip = space_world(slope, self.poses.hip[i])
        self.sagittal.set_xlim(hip[0] - 0.9 * h, hip[0] + 0.9 * h)
        self.sagittal.set_ylim(hip[2] - 1.25 * h, hip[2] + 0.3 * h)
        for axis, centre in zip("xyz", (hip[0], hip[1], hip[2] - 0.5 * h), strict=True):
            getattr(self.ax3d, f"set_{axis}lim")(centre - 0.75 * h, centre + 0.75 * h)
        self.stamp.set_text(f"t = {self.run.time[i]:6.3f} s")


@contextlib.contextmanager
def _temporary_beside(out: Path) -> Iterator[Path]:
    """A temporary name beside ``out`` with the same suffix (writers pick the format from it), renamed on success.

    The writer creates the file itself, so it gets the usual permissions (umask), unlike mkstemp's 0600.
    """
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp_path = out.with_name(f".{out.stem}.{os.getpid()}.partial{out.suffix}")
    try:
        yield tmp_path
        os.replace(tmp_path, out)
    finally:
        tmp_path.unlink(missing_ok=True)


def animate_run(
    run: RunData,
    out: Path,
    *,
    fps: float = 25.0,
    speed: float = 1.0,
    t_start: float = 0.0,
    t_end: float | None = None,
    dpi: int = 100,
) -> int:
    """Write the animation of ``run`` to ``out`` (.gif or .mp4); returns the number of frames."""
    check_output(out)
    check_playback(fps, speed, t_start, t_end)
    frames = frame_indices(run.time, fps, speed, t_start, t_end)
    with figure_style():
        space = run.config.in_space
        fig = Figure(figsize=(8.0, 3.2) if space else (4.0, 3.2))
        FigureCanvasAgg(fig)
        fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.99)
        drawing = SpaceDrawing(run, fig) if space else WalkerDrawing(run, fig)
        if out.suffix.lower() == ".mp4":
            writer: animation.AbstractMovieWriter = animation.FFMpegWriter(fps=fps)
        else:
            writer = animation.PillowWriter(fps=fps)
        with _temporary_beside(out) as tmp, writer.saving(fig, str(tmp), dpi):
            for i in frames:
                drawing.draw(int(i))
                writer.grab_frame()
    return len(frames)
