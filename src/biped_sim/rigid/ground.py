"""The rigid heel strike on a ground profile (``ground.profile``: steps, slope_change, polyline, random).

The rigid models keep a flat local ground under the stance foot: it rolls (round feet) or pivots (point
feet) on the level of its own contact point, a line of the slope's direction, as on the plane. The profile
enters at the heel strike only: once the swing foot has left its mid-stance scuff (which the rigid models
ignore: :mod:`biped_sim.rigid.compiled`), the step ends when the lowest point of the swing foot's arc (the
foot point when R = 0) comes down to the profile's height at its x,

    clearance = level + (l - R)(cos theta_st - cos theta_sw) - h(x_swing),
    x_swing = O - R theta_st + (l - R)(sin theta_sw - sin theta_st),

where the stance contact point is at x = O - R theta_st (``Footing.origin`` O) on the level ``Footing.level``.
The new stance foot then stands on the level of that point. For point feet this is exact (a point foot does
not roll); a round foot on a sloped part of the profile (slope_change, polyline) rolls on the level line
through its contact point instead of along the profile: an approximation of the rigid model, stated here.

A riser (a step up, two profile vertices at one x) is hit when the swing foot's lowest point reaches its x
below its top: the rigid model cannot say what happens to a foot stubbed against a wall, so the step ends
as ``tripped`` (the run counts it as a fall). So does a swing foot already below the profile when the strike
is first sought (it crossed a riser during the mid-stance swing, whose scuffing the rigid model ignores). Only
the lowest point is checked: the front of a round foot's arc may graze a riser unnoticed.

The compiled step map reads them from the kernels below: the swing foot (:func:`tree_swing_foot`), its
clearance (:func:`clearance`) and the riser test (:func:`riser_hit`); :class:`ProfileStrike`, the scipy
reference's view, calls the same clearance and riser kernels.

The impact is the walker's own map (angular momentum about the new contact point and of the trailing leg
about the hip), which holds for any leg angles (Garcia's published map for the simplest walker assumes the
symmetric strike of flat ground; the tree's limit of infinitesimal foot masses is its general form).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from biped_sim.config import Config
from biped_sim.contact.ground import ground_height
from biped_sim.contact.profile import FlatProfile, profile_arrays
from biped_sim.kernel import kernel
from biped_sim.rigid.tree import RigidWalker
from biped_sim.rigid.tree_layout import RigidTree, landing, point

RISER_TOLERANCE = 1e-9  # a strike this close to a riser's x and below its top is a trip [leg lengths]


@kernel
def tree_swing_foot(tree: RigidTree, x: np.ndarray, origin: float, level: float) -> tuple[float, float]:
    """(x, height) of the swing foot's lowest point, the stance contact at (origin - R theta, level)."""
    foot_x, foot_y = point(tree, landing(tree), x)
    return origin + foot_x, level + foot_y - tree.landing_radius


@kernel
def clearance(foot_x: float, foot_y: float, vertices: np.ndarray, ends: np.ndarray) -> float:
    """Height of a foot point above the profile below it: the strike guard on a profile."""
    return foot_y - ground_height(foot_x, vertices, ends)


@kernel
def riser_hit(foot_x: float, foot_y: float, vertices: np.ndarray, tolerance: float) -> bool:
    """The foot point is within ``tolerance`` of a riser's x (a step up: consecutive vertices at one x, rising) and
    more than ``tolerance`` below its top: it hit the riser, not the tread."""
    for i in range(1, vertices.shape[0]):
        x, top = vertices[i, 0], vertices[i, 1]
        riser = x == vertices[i - 1, 0] and top > vertices[i - 1, 1]
        if riser and abs(x - foot_x) <= tolerance and top > foot_y + tolerance:
            return True
    return False


@dataclass(frozen=True)
class RigidGround:
    """A compiled profile (:func:`biped_sim.contact.profile.profile_arrays`)."""

    vertices: np.ndarray
    ends: np.ndarray


def rigid_ground(config: Config) -> RigidGround | None:
    """The config's profile for the rigid heel strike; None for flat ground (the strike of the plain models)."""
    profile = config.ground.profile
    if isinstance(profile, FlatProfile):
        return None
    return RigidGround(*profile_arrays(profile, config.ground.slope))


@dataclass(frozen=True)
class Footing:
    """Where the stance foot stands: contact point at x = origin - R theta_st, on the level ``level``."""

    origin: float
    level: float


@dataclass(frozen=True)
class ProfileStrike:
    """The heel strike of one step of ``walker`` on ``ground`` from ``footing``."""

    walker: RigidWalker
    ground: RigidGround
    footing: Footing

    def swing_foot(self, x: np.ndarray) -> tuple[float, float]:
        """(x, height) of the lowest point of the swing foot's arc (the next spoke's tip for the wheel)."""
        return self.walker.swing_foot(x, self.footing.origin, self.footing.level)

    def clearance(self, x: np.ndarray) -> float:
        """Height of the swing foot's lowest point above the profile below it: the strike guard."""
        foot_x, foot_y = self.swing_foot(x)
        return float(clearance(foot_x, foot_y, self.ground.vertices, self.ground.ends))

    def tripped(self, x: np.ndarray) -> bool:
        """The swing foot is at a riser's x below its top: it hit the riser, not the tread."""
        foot_x, foot_y = self.swing_foot(x)
        return bool(riser_hit(foot_x, foot_y, self.ground.vertices, RISER_TOLERANCE * self.walker.leg_length))

    def impact(self, x_minus: np.ndarray) -> np.ndarray:
        """The post-impact state (general leg angles)."""
        return self.walker.impact(x_minus)

    def after(self, x_minus: np.ndarray, x_plus: np.ndarray) -> ProfileStrike:
        """The next step's strike: the new stance foot stands where the swing foot landed."""
        foot_x, foot_y = self.swing_foot(x_minus)
        footing = Footing(foot_x - float(self.walker.contact_point(x_plus[: self.walker.n_q])[0]), foot_y)
        return ProfileStrike(self.walker, self.ground, footing)
