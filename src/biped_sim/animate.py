"""Animation of a run: the walker walking down its slope, with contact force arrows and a time stamp.

The walker is drawn from trajectory.h5: each leg from its body state (x, y, phi), the hip
joint, the round feet as arcs, using the geometry of the model rebuilt from the run's stored
config (one source for the geometry: the walker builder). The scene is drawn in the world frame
(the slope frame rotated by the slope angle, so the ground visibly descends), and the view
follows the hip. Frames are decimated to ``fps`` frames per second of playback; GIF through
Pillow (matplotlib's PillowWriter), MP4 through ffmpeg when it is on the PATH.
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from matplotlib import animation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from biped_sim.errors import ConfigError
from biped_sim.io.trajectory import RunData
from biped_sim.plots import figure_style
from biped_sim.walkers import build_model

FOOT_ARC_HALF_ANGLE = 0.8  # rad of foot arc drawn on each side of the leg axis
ARROW_LENGTH_PER_WEIGHT = 0.6  # arrow length, in leg lengths, of a force equal to the walker's weight
FORMATS = (".gif", ".mp4")


def check_output(out: Path) -> None:
    """Reject an unsupported file type (or .mp4 without ffmpeg) before any work is done."""
    if out.suffix.lower() not in FORMATS:
        raise ConfigError("--out", f"unsupported animation type {out.suffix or '(none)'!r}; use .gif or .mp4")
    if out.suffix.lower() == ".mp4" and not animation.writers.is_available("ffmpeg"):
        raise ConfigError("--out", ".mp4 needs ffmpeg on the PATH; install it or write a .gif")


def frame_indices(time: np.ndarray, fps: float, speed: float, t_start: float, t_end: float | None) -> np.ndarray:
    """Sample indices of the frames: one frame every ``speed / fps`` simulated seconds."""
    stop = time[-1] if t_end is None else min(t_end, time[-1])
    if stop < t_start:
        raise ConfigError("--start", f"after the end of the run ({time[-1]:.3f} s)")
    frame_times = np.arange(t_start, stop + 1e-12, speed / fps)
    return np.unique(np.clip(np.searchsorted(time, frame_times), 0, len(time) - 1))


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


class WalkerDrawing:
    """The artists of one frame and how to place them at a sample."""

    def __init__(self, run: RunData, fig: Figure) -> None:
        model = build_model(run.config)
        system = model.system
        self.run = run
        self.l = model.leg_length
        self.to_world = _rotation(-run.config.ground.slope)
        self.force_scale = ARROW_LENGTH_PER_WEIGHT * self.l / (model.total_mass * run.config.gravity)
        self.foot_body = system.foot_body.astype(int)
        self.foot_center = np.array(system.foot_center)
        self.foot_radius = np.array(system.foot_radius)
        # each leg: from its hip point (joint 0, one side per body) to the bottom of its foot arc
        self.leg_points = []
        for b in range(model.n_bodies):
            side = 0 if system.joint_bodies[0, 0] == b else 2
            foot = int(np.flatnonzero(self.foot_body == b)[0])
            bottom = self.foot_center[foot] + np.array([0.0, -self.foot_radius[foot]])
            self.leg_points.append(np.vstack([system.joint_points[0, side : side + 2], bottom]))
        u = np.linspace(-FOOT_ARC_HALF_ANGLE, FOOT_ARC_HALF_ANGLE, 25)
        self.arc = np.column_stack([np.sin(u), -np.cos(u)])  # unit arc about the body's -y axis

        self.ax = fig.add_subplot()
        self.ax.set_aspect("equal")
        self.ax.set_xticks([])
        self.ax.set_yticks([])
        self.ax.grid(False)
        ground_x = np.array([run.hip[:, 0].min() - 2 * self.l, run.hip[:, 0].max() + 2 * self.l])
        ground = self.to_world @ np.vstack([ground_x, np.zeros(2)])
        self.ax.fill_between(ground[0], ground[1], ground[1] - 2 * self.l, color="0.85", zorder=0)
        self.ax.plot(ground[0], ground[1], color="0.3", linewidth=1.0)
        self.legs = [
            self.ax.plot([], [], color=f"C{b}", linewidth=2.0, solid_capstyle="round")[0] for b in range(model.n_bodies)
        ]
        self.feet = [self.ax.plot([], [], color=f"C{b}", linewidth=2.0)[0] for b in self.foot_body]
        (self.hip,) = self.ax.plot([], [], "o", color="k", markersize=6, zorder=5)
        self.arrows = self.ax.quiver(
            np.zeros(len(self.foot_body)),
            np.zeros(len(self.foot_body)),
            np.zeros(len(self.foot_body)),
            np.zeros(len(self.foot_body)),
            angles="xy",
            scale_units="xy",
            scale=1.0,
            color="C3",
            width=0.012,
            zorder=6,
        )
        self.stamp = self.ax.text(0.03, 0.95, "", transform=self.ax.transAxes, va="top", family="monospace")

    def _body_points(self, y: np.ndarray, b: int, points: np.ndarray) -> np.ndarray:
        """Slope-frame positions of body-frame ``points`` (k, 2) of body b."""
        return y[3 * b : 3 * b + 2] + points @ _rotation(y[3 * b + 2]).T

    def draw(self, i: int) -> None:
        """Place every artist at sample ``i``."""
        run, y = self.run, self.run.state[i]
        for b, line in enumerate(self.legs):
            leg = self.to_world @ self._body_points(y, b, self.leg_points[b]).T
            line.set_data(leg[0], leg[1])
        offsets, vectors = [], []
        for f, line in enumerate(self.feet):
            b = self.foot_body[f]
            arc = self._body_points(y, b, self.foot_center[f] + self.foot_radius[f] * self.arc)
            world = self.to_world @ arc.T
            line.set_data(world[0], world[1])
            centre = self._body_points(y, b, self.foot_center[f][None, :])[0]
            contact = np.array([centre[0], centre[1] - self.foot_radius[f]])
            force = np.array([run.friction_force[i, f], run.normal_force[i, f]]) * self.force_scale
            offsets.append(self.to_world @ contact)
            vectors.append(self.to_world @ force)
        self.arrows.set_offsets(np.array(offsets))
        vectors_arr = np.array(vectors)
        self.arrows.set_UVC(vectors_arr[:, 0], vectors_arr[:, 1])
        hip_world = self.to_world @ run.hip[i]
        self.hip.set_data([hip_world[0]], [hip_world[1]])
        self.ax.set_xlim(hip_world[0] - 0.9 * self.l, hip_world[0] + 0.9 * self.l)
        self.ax.set_ylim(hip_world[1] - 1.25 * self.l, hip_world[1] + 0.3 * self.l)
        self.stamp.set_text(f"t = {run.time[i]:6.3f} s")


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
    if fps <= 0:
        raise ConfigError("--fps", "must be > 0")
    if speed <= 0:
        raise ConfigError("--speed", "must be > 0")
    frames = frame_indices(run.time, fps, speed, t_start, t_end)
    with figure_style():
        fig = Figure(figsize=(4.0, 3.2))
        FigureCanvasAgg(fig)
        fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.99)
        drawing = WalkerDrawing(run, fig)
        if out.suffix.lower() == ".mp4":
            writer: animation.AbstractMovieWriter = animation.FFMpegWriter(fps=fps)
        else:
            writer = animation.PillowWriter(fps=fps)
        with _temporary_beside(out) as tmp, writer.saving(fig, str(tmp), dpi):
            for i in frames:
                drawing.draw(int(i))
                writer.grab_frame()
    return len(frames)
