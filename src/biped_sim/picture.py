"""Drawing a walker's pose (:mod:`biped_sim.measure.pose`) and its ground on matplotlib axes.

The one drawing of a walker, of any description and either dynamics, shared by the animation
(:mod:`biped_sim.animate`) and the walker figure (:func:`biped_sim.plots.walker_figure`): each body as its
segment (a leg's bodies in that leg's colour, a body off the legs in grey), feet as sectors of their radius about
the body's axis (a rocker: the arc joined to its centre) or as dots (point feet), the hip as a black dot, and
each joint stop as a square at its joint, filled when the joint is at or past its stop. The scene is drawn in the
world frame: the slope frame turned by the slope angle, so that the ground visibly descends.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from biped_sim.config import Config
from biped_sim.contact.profile import profile_arrays, profile_outline
from biped_sim.measure.pose import Pose, Skeleton

FOOT_ARC_HALF_ANGLE = 0.8  # rad of foot arc drawn on each side of the body's axis
OFF_LEG_COLOUR = "0.35"
STOP_COLOUR = "C3"


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
    ax.fill(np.r_[surface[0], bottom[0, ::-1]], np.r_[surface[1], bottom[1, ::-1]], color="0.85", zorder=0)
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
        u = np.linspace(-FOOT_ARC_HALF_ANGLE, FOOT_ARC_HALF_ANGLE, 25)
        self.arc = np.column_stack([np.sin(u), -np.cos(u)])  # a unit arc about a body's -y axis

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
            arc = centre + radius * self.arc @ np.array([[c, s], [-s, c]])
            self._set(line, np.vstack([centre, arc, centre]) if radius > 0 else centre)  # a rocker: a sector
        self._set(self.hip, pose.hip)
        self._set(self.stops_free, pose.joints[~pose.engaged])
        self._set(self.stops_engaged, pose.joints[pose.engaged])
