"""Drawing a walker's pose (:mod:`biped_sim.measure.pose`) and its ground on matplotlib axes.

The one drawing of a walker, of any description and either dynamics, shared by the animation
(:mod:`biped_sim.animate`) and the walker figure (:func:`biped_sim.plots.walker_figure`): each body as its
segment (a leg's bodies in that leg's colour, a body off the legs in grey), feet as sectors of the arc they roll on
in the sagittal plane about the body's axis (a rocker: the arc joined to its centre, as wide as
:func:`~biped_sim.measure.pose.foot_arc_half_angle` draws a foot, at most 0.8 rad on each side) or as dots (point
feet), the hip as a black dot, and each joint stop as a square at its joint, filled when the joint is at or past its
stop. The scene is drawn in the world frame: the slope frame turned by the slope angle, so that the ground visibly
descends. A walker in space (:class:`SpaceWalkerPicture`) is drawn in matplotlib's 3D axes (x downhill, y to the
walker's left, z up) and, on 2D axes beside them, in its sagittal view: each leg from the hinge to its hip point, its
centre of mass and its foot centre, each foot as the shape its contact rolls on (:mod:`biped_sim.measure.space_pose`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from biped_sim.config import Config
from biped_sim.contact.profile import profile_arrays, profile_outline
from biped_sim.io.trajectory import RunData
from biped_sim.measure.pose import Pose, Skeleton
from biped_sim.measure.space_pose import SpacePoses, space_poses

OFF_LEG_COLOUR = "0.35"
STOP_COLOUR = "C3"
GROUND_COLOUR = "0.85"  # the ground's fill, planar and in 3D: a pale grey under the walker's lines


def to_world(slope: float) -> np.ndarray:
    """(2, 2): the slope frame to the world frame (turned by -slope: downhill to the right, and down)."""
    c, s = math.cos(slope), math.sin(slope)
    return np.array([[c, s], [-s, c]])


def draw_ground(ax: Axes, config: Config, x_min: float, x_max: float, depth: float) -> None:
    """The ground profile over [x_min, x_max] along the slope, filled ``depth`` deep along its normal."""
    vertices, ends = profile_arrays(config.ground.profile, config.ground.slope)
    outline = profile_outline(vertices, ends, x_min, x_max).T
    world = to_world(config.ground.slope)
    surface = world @ outline
    bottom = world @ (outline - np.array([[0.0], [depth]]))
    ax.fill(np.r_[surface[0], bottom[0, ::-1]], np.r_[surface[1], bottom[1, ::-1]], color=GROUND_COLOUR, zorder=0)
    ax.plot(surface[0], surface[1], color="0.3", linewidth=1.0)


def body_colour(sk: Skeleton, body: int) -> str:
    """A leg's bodies share its colour (C0, C1, ...); a body off the legs is grey."""
    leg = int(sk.leg_of[body])
    return OFF_LEG_COLOUR if leg < 0 else f"C{leg % 10}"


class WalkerPicture:
    """The artists of one walker on ``ax``, placed at a pose by :meth:`place` (again and again for an animation)."""

    def __init__(self, ax: Axes, sk: Skeleton, slope: float, alpha: float = 1.0, linewidth: float = 2.0) -> None:
        self.sk, self.world = sk, to_world(slope)
        style = {"alpha": alpha, "solid_capstyle": "round"}
        self.bodies = [ax.plot([], [], color=body_colour(sk, b), linewidth=linewidth, **style)[0] for b in
                       range(len(sk.names))]  # fmt: skip
        self.feet: list[Line2D] = []
        for b, radius in zip(sk.foot_body, sk.foot_radius, strict=True):
            marker = {} if radius > 0 else {"marker": "o", "markersize": 2.5 * linewidth}
            self.feet.append(ax.plot([], [], color=body_colour(sk, int(b)), linewidth=linewidth, **style, **marker)[0])
        (self.hip,) = ax.plot([], [], "o", color="k", markersize=2.5 * linewidth, alpha=alpha, zorder=5)
        marker = {"marker": "s", "linestyle": "none", "markersize": 2.0 * linewidth, "alpha": alpha, "zorder": 6}
        (self.stops_free,) = ax.plot([], [], markerfacecolor="white", markeredgecolor=STOP_COLOUR, **marker)
        (self.stops_engaged,) = ax.plot([], [], color=STOP_COLOUR, **marker)
        u = np.linspace(-1.0, 1.0, 25)[None, :] * sk.foot_half_angle[:, None]
        self.arcs = np.stack([np.sin(u), -np.cos(u)], axis=-1)  # (nf, 25, 2): each foot's unit arc about its body's -y

    def _set(self, line: Line2D, points: np.ndarray) -> None:
        """Place ``line`` through slope-frame ``points`` (k, 2)."""
        world = self.world @ np.asarray(points, dtype=float).reshape(-1, 2).T
        line.set_data(world[0], world[1])

    def place(self, pose: Pose) -> None:
        """Every artist at ``pose``."""
        for line, segment in zip(self.bodies, pose.segments, strict=True):
            self._set(line, segment)
        for f, (line, b) in enumerate(zip(self.feet, self.sk.foot_body, strict=True)):
            radius, angle = self.sk.foot_radius[f], pose.angles[b]
            c, s = math.cos(angle), math.sin(angle)
            centre = pose.foot_centres[f]
            arc = centre + radius * self.arcs[f] @ np.array([[c, s], [-s, c]])
            self._set(line, np.vstack([centre, arc, centre]) if radius > 0 else centre)  # a rocker: a sector
        self._set(self.hip, pose.hip)
        self._set(self.stops_free, pose.joints[~pose.engaged])
        self._set(self.stops_engaged, pose.joints[pose.engaged])


def space_world(slope: float, points: np.ndarray) -> np.ndarray:
    """(..., 3) slope-frame points (x downhill, y normal, z right) in the 3D axes' frame (x, left, up), the slope
    turned so that the ground descends."""
    world = points[..., :2] @ to_world(slope).T
    return np.stack([world[..., 0], -points[..., 2], world[..., 1]], axis=-1)


class SpaceWalkerPicture:
    """The artists of a walker in space on 3D axes (and its sagittal view on 2D ones), placed by :meth:`place`."""

    def __init__(self, ax3d: Axes, sagittal: Axes | None, slope: float, alpha: float = 1.0, lw: float = 2.0) -> None:
        self.slope, self.sagittal = slope, sagittal
        style = {"alpha": alpha, "linewidth": lw, "solid_capstyle": "round"}
        ax3d.computed_zorder = False  # type: ignore[attr-defined]  # the walker over the ground, always
        colours = [f"C{k % 2}" for k in range(4)] + ["C2"]  # the legs and feet, then a torso
        self.lines3d = [ax3d.plot([], [], [], color=c, zorder=2, **style)[0] for c in colours]
        self.lines2d = [sagittal.plot([], [], color=c, **style)[0] for c in colours] if sagittal else []

    def place(self, poses: SpacePoses, i: int) -> None:
        """Every artist at sample ``i`` of ``poses``: each leg's polyline, then each foot's curves, then a torso's
        line (NaN, not drawn, without one)."""
        shapes = [poses.legs[i, 0], poses.legs[i, 1], poses.feet[i, 0], poses.feet[i, 1], poses.torso[i]]
        for k, points in enumerate(shapes):
            world = space_world(self.slope, points)
            self.lines3d[k].set_data_3d(world[:, 0], world[:, 1], world[:, 2])  # type: ignore[attr-defined]
            if self.lines2d:
                self.lines2d[k].set_data(world[:, 0], world[:, 2])


def draw_space_ground(ax3d: Axes, slope: float, x: tuple[float, float], z: tuple[float, float]) -> Any:
    """The slope plane over x (downhill) and z (lateral, to the right) ranges, as a patch of the planar ground's
    colour on the 3D axes (3D axes do not clip: the patch is the view's extent); returns its artist. Unshaded:
    plot_surface's light source would darken the pale grey of a plane tilted away from it to a dark one."""
    corners = np.array([[x[0], 0.0, z[0]], [x[1], 0.0, z[0]], [x[1], 0.0, z[1]], [x[0], 0.0, z[1]]])
    world = space_world(slope, corners)
    grid = world[[0, 1, 3, 2]].reshape(2, 2, 3)
    return ax3d.plot_surface(grid[..., 0], grid[..., 1], grid[..., 2], color=GROUND_COLOUR, shade=False,  # type: ignore
                             linewidth=0, zorder=0)  # fmt: skip


def draw_space_walker(sagittal: Axes, ax3d: Axes, run: RunData, samples: np.ndarray) -> None:
    """A walker in space at ``samples`` of ``run`` (the earlier paler): its sagittal view over the ground on
    ``sagittal``, its 3D view over the slope plane on ``ax3d``."""
    poses, slope = space_poses(run), run.config.ground.slope
    for i, alpha in zip(samples, np.linspace(0.3, 1.0, len(samples)), strict=True):
        SpaceWalkerPicture(ax3d, sagittal, slope, float(alpha), 1.2).place(poses, int(i))
    points = np.concatenate([getattr(poses, name)[samples].reshape(-1, 3) for name in ("legs", "feet", "torso")])
    low, high = np.nanmin(points, axis=0), np.nanmax(points, axis=0)  # NaN: the break between two curves of a foot
    reach = float(np.max(high - low))
    draw_ground(sagittal, run.config, float(low[0]) - 0.2 * reach, float(high[0]) + 0.2 * reach, 0.1 * reach)
    draw_space_ground(ax3d, slope, (low[0] - 0.2 * reach, high[0] + 0.2 * reach), (low[2] - 0.2 * reach,
                      high[2] + 0.2 * reach))  # fmt: skip
    sagittal.set_aspect("equal")
    sagittal.axis("off")
    sagittal.relim()  # the walker's lines were placed after they were made
    sagittal.autoscale_view()
    world = space_world(slope, points)
    for axis, k in zip("xyz", range(3), strict=True):
        centre = 0.5 * (np.nanmin(world[:, k]) + np.nanmax(world[:, k]))
        getattr(ax3d, f"set_{axis}lim")(centre - 0.6 * reach, centre + 0.6 * reach)
    ax3d.set_box_aspect((1.0, 1.0, 1.0))  # type: ignore[arg-type]
    ax3d.set_axis_off()
