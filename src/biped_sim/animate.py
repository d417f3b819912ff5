"""Animation of a run: the walker walking down its slope, with contact force arrows and a time stamp.

The walker is drawn from trajectory.h5 in its sagittal view: each leg from the hip at its leg
angle, the round feet as arcs (leg length and foot radius from the run's stored config, which
feet belong to which body from the walker builder), for planar and spatial runs alike. The
scene is drawn in the world frame (the slope frame rotated by the slope angle, so the ground
visibly descends) over the ground's profile, and the view follows the hip. Frames are decimated to ``fps`` frames per
second of playback; GIF through Pillow (matplotlib's PillowWriter), MP4 through ffmpeg when it
is on the PATH.
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

from biped_sim.config import InitialState
from biped_sim.contact.profile import profile_arrays, profile_outline
from biped_sim.errors import ArgumentError
from biped_sim.io.output import check_writable_dir
from biped_sim.io.trajectory import RunData
from biped_sim.plots import figure_style
from biped_sim.walkers import build_model

FOOT_ARC_HALF_ANGLE = 0.8  # rad of foot arc drawn on each side of the leg axis
ARROW_LENGTH_PER_WEIGHT = 0.6  # arrow length, in leg lengths, of a force equal to the walker's weight
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


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


class WalkerDrawing:
    """The artists of one frame and how to place them at a sample.

    The drawing is the walker's sagittal view, the same for every formulation: each leg body hangs
    from the hip at its leg angle (planar phi, or the spatial pitch), its foot arc of radius R centred
    on the leg axis at l - R from the hip; the feet of one body (the four-legged walker's pairs)
    coincide in this view.
    """

    def __init__(self, run: RunData, fig: Figure) -> None:
        angles, rates = run.leg_angles()[0], run.leg_rates()[0]
        start = InitialState(stance_angle=angles[0], stance_rate=rates[0], swing_angle=angles[1], swing_rate=rates[1])
        model = build_model(run.config, start)  # the run's own start: the same bodies and feet
        self.run = run
        self.l = model.leg_length
        self.radius = run.config.walker.foot_radius
        self.to_world = _rotation(-run.config.ground.slope)
        self.force_scale = ARROW_LENGTH_PER_WEIGHT * self.l / (model.total_mass * run.config.gravity)
        self.foot_body = model.system.foot_body.astype(int)
        self.angles = run.leg_angles()
        self.hip_track = run.hip[:, :2]
        u = np.linspace(-FOOT_ARC_HALF_ANGLE, FOOT_ARC_HALF_ANGLE, 25)
        self.arc = np.column_stack([np.sin(u), -np.cos(u)])  # unit arc about the leg's axis, hip to foot

        self.ax = fig.add_subplot()
        self.ax.set_aspect("equal")
        self.ax.set_xticks([])
        self.ax.set_yticks([])
        self.ax.grid(False)
        self._draw_ground(run)
        n_bodies = self.angles.shape[1]
        self.legs = [
            self.ax.plot([], [], color=f"C{b}", linewidth=2.0, solid_capstyle="round")[0] for b in range(n_bodies)
        ]
        self.feet = [self.ax.plot([], [], color=f"C{b}", linewidth=2.0)[0] for b in range(n_bodies)]
        (self.hip,) = self.ax.plot([], [], "o", color="k", markersize=6, zorder=5)
        n_feet = len(self.foot_body)
        self.arrows = self.ax.quiver(
            np.zeros(n_feet),
            np.zeros(n_feet),
            np.zeros(n_feet),
            np.zeros(n_feet),
            angles="xy",
            scale_units="xy",
            scale=1.0,
            color="C3",
            width=0.012,
            zorder=6,
        )
        self.stamp = self.ax.text(0.03, 0.95, "", transform=self.ax.transAxes, va="top", family="monospace")

    def _draw_ground(self, run: RunData) -> None:
        """The ground profile under the hip's whole track, filled 2 l deep along the slope normal."""
        vertices, ends = profile_arrays(run.config.ground.profile, run.config.ground.slope)
        x_min, x_max = self.hip_track[:, 0].min() - 2 * self.l, self.hip_track[:, 0].max() + 2 * self.l
        outline = profile_outline(vertices, ends, x_min, x_max).T
        surface = self.to_world @ outline
        depth = self.to_world @ (outline - np.array([[0.0], [2 * self.l]]))
        self.ax.fill(np.r_[surface[0], depth[0, ::-1]], np.r_[surface[1], depth[1, ::-1]], color="0.85", zorder=0)
        self.ax.plot(surface[0], surface[1], color="0.3", linewidth=1.0)

    def draw(self, i: int) -> None:
        """Place every artist at sample ``i``."""
        run, hip = self.run, self.hip_track[i]
        centres = []
        for b, (leg, foot) in enumerate(zip(self.legs, self.feet, strict=True)):
            rotation = _rotation(self.angles[i, b])
            centre = hip + (self.l - self.radius) * (rotation @ np.array([0.0, -1.0]))
            bottom = centre + self.radius * (rotation @ np.array([0.0, -1.0]))
            leg_world = self.to_world @ np.vstack([hip, bottom]).T
            leg.set_data(leg_world[0], leg_world[1])
            arc_world = self.to_world @ (centre + self.radius * self.arc @ rotation.T).T
            foot.set_data(arc_world[0], arc_world[1])
            centres.append(centre)
        offsets, vectors = [], []
        for f, b in enumerate(self.foot_body):
            contact = centres[b] - np.array([0.0, self.radius])
            force = np.array([run.friction_force[i, f], run.normal_force[i, f]]) * self.force_scale
            offsets.append(self.to_world @ contact)
            vectors.append(self.to_world @ force)
        self.arrows.set_offsets(np.array(offsets))
        vectors_arr = np.array(vectors)
        self.arrows.set_UVC(vectors_arr[:, 0], vectors_arr[:, 1])
        hip_world = self.to_world @ hip
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
    check_playback(fps, speed, t_start, t_end)
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
