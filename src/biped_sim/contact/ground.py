"""The ground's shape in the slope frame, compiled: a foot arc against a polyline profile (issue 12).

A profile is one polyline of vertices (x_k, h_k) in the slope frame (x along the slope, downhill
positive; h along the slope normal), x non-decreasing: two consecutive vertices at the same x are a
step's riser, a vertical segment. Beyond the first and the last vertex the ground goes on as two rays
of slopes dh/dx ``ends`` = (left, right). No vertex at all is the plane h = 0 (the flat default).
:mod:`biped_sim.contact.profile` builds these arrays from the config.

A foot is a circle (arc centre C, radius R; R = 0 is a point foot). Its features are the segments
(the two rays included) whose projection of C falls inside them, with the signed distance
s = (C - A).n along the outward normal n, and the convex corners whose normal cone holds C, with
s = |C - V| and n = (C - V) / s; concave corners are covered by their two segments. The
penetration of a feature is delta = R - s and its contact point P = C - R n. The contact features
are those with s >= 0 in contact (delta > 0), at most two, deepest first (a foot on a step's riser
and its tread); a centre inside the ground (s < 0, a point foot) touches only the nearest surface.
Every function is compiled and allocation-free; features are searched by bisection on x within R
of C.

The formulations' systems hold the ground as a typed object: :class:`FlatGround` (the default, no
arrays) or :class:`ProfileGround` (the arrays above). Functions of a ground, such as
:func:`ground_clearance` and :mod:`.response`'s ``arc_contact`` and ``arc_forces``, are resolved by
numba at compile time from its type (:func:`~biped_sim.contact.registry.by_type`): a flat run
compiles the plane's arithmetic alone, a profile run its own specialisation of the same kernels.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.contact.registry import by_type
from biped_sim.kernel import kernel

FLAT_VERTICES = np.zeros((0, 2))  # the flat ground: no vertex, the plane h = 0
FLAT_ENDS = np.zeros(2)


class FlatGround(NamedTuple):
    """The plane h = 0 of the slope, as a system's ``ground`` (no arrays: nothing to pass or count)."""


class ProfileGround(NamedTuple):
    """A profile as a system's ``ground``: the polyline ``vertices`` (n >= 1, 2) and the slopes ``ends`` beyond it."""

    vertices: np.ndarray
    ends: np.ndarray


FLAT_GROUND = FlatGround()
Ground = FlatGround | ProfileGround


@kernel
def _first_at_or_after(vertices: np.ndarray, x: float) -> int:
    """Index of the first vertex with x_k >= x (the vertex count when there is none)."""
    lo, hi = 0, vertices.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if vertices[mid, 0] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@kernel
def ground_height(x: float, vertices: np.ndarray, ends: np.ndarray) -> float:
    """Height h(x) of the profile along the slope normal at slope coordinate x [m].

    At a step's riser (x equal to the step's position) it is the level after the step. The rigid
    models' heel strike and the drawing read it.
    """
    n = vertices.shape[0]
    if n == 0:
        return 0.0
    if x < vertices[0, 0]:
        return vertices[0, 1] + ends[0] * (x - vertices[0, 0])
    if x >= vertices[n - 1, 0]:
        return vertices[n - 1, 1] + ends[1] * (x - vertices[n - 1, 0])
    k = _first_at_or_after(vertices, x)  # x_{k-1} < x <= x_k
    if vertices[k, 0] == x:
        while k + 1 < n and vertices[k + 1, 0] == x:
            k += 1
        return vertices[k, 1]
    x0, h0, x1, h1 = vertices[k - 1, 0], vertices[k - 1, 1], vertices[k, 0], vertices[k, 1]
    return h0 + (h1 - h0) * (x - x0) / (x1 - x0)


@kernel
def _segment(vertices: np.ndarray, ends: np.ndarray, j: int) -> tuple[float, float, float, float, float, float]:
    """Segment j (-1: the left ray, n - 1: the right ray): (A_x, A_y, d_x, d_y, t_min, t_max).

    A point A, the unit direction d (x increasing, or along a riser) and the range of t = (C - A).d
    where the projection of C falls on it.
    """
    n = vertices.shape[0]
    if j < 0 or j >= n - 1:
        slope = ends[0] if j < 0 else ends[1]
        norm = math.sqrt(1.0 + slope * slope)
        k = 0 if j < 0 else n - 1
        t_min, t_max = (-math.inf, 0.0) if j < 0 else (0.0, math.inf)
        return vertices[k, 0], vertices[k, 1], 1.0 / norm, slope / norm, t_min, t_max
    ax, ay = vertices[j, 0], vertices[j, 1]
    ex, ey = vertices[j + 1, 0] - ax, vertices[j + 1, 1] - ay
    length = math.sqrt(ex * ex + ey * ey)
    return ax, ay, ex / length, ey / length, 0.0, length


@kernel
def _turn(vertices: np.ndarray, ends: np.ndarray, k: int) -> float:
    """d_(k-1) x d_k at vertex k: < 0 a convex corner (a ridge), > 0 a concave one (a valley), 0 straight."""
    _, _, ix, iy, _, _ = _segment(vertices, ends, k - 1)
    _, _, ox, oy, _, _ = _segment(vertices, ends, k)
    return ix * oy - iy * ox


@kernel
def _feature(
    s: float, nx: float, ny: float, cx: float, cy: float, radius: float, sign: float = 1.0
) -> tuple[float, float, float, float, float, float]:
    """(delta, P_x, P_y, n_x, n_y, sign) of a feature at signed distance s along the normal n."""
    return radius - s, cx - radius * nx, cy - radius * ny, nx, ny, sign


@kernel
def _towards(
    cx: float, cy: float, vx: float, vy: float, radius: float, sign: float
) -> tuple[float, float, float, float, float, float]:
    """The feature of a point (vx, vy) of the profile: s = |C - V| along n = (C - V) / s."""
    rx, ry = cx - vx, cy - vy
    s = math.sqrt(rx * rx + ry * ry)
    return _feature(s, rx / s, ry / s, cx, cy, radius, sign)


_NONE = (-math.inf, 0.0, 0.0, 0.0, 1.0, 1.0)  # not a feature of this centre


@kernel
def ground_feature(
    cx: float, cy: float, radius: float, vertices: np.ndarray, ends: np.ndarray, first: int, f: int
) -> tuple[float, float, float, float, float, float]:
    """Feature ``f`` of the window from segment ``first`` (:func:`ground_window`): (delta, P_x, P_y, n_x, n_y, sign).

    Even f: segment j = first + f // 2, when C projects inside it (half-open: a point over a vertex
    belongs to one segment) and lies on its outer side. Odd f: the corner k = j + 1 between segments
    j and j + 1. A convex corner is a feature (sign +1) when its normal cone holds C: it hands over
    continuously to the segments at the cone's edges. A concave corner is a feature to subtract
    (sign -1) when C projects inside both its segments, with s = |C - V|: inclusion-exclusion, so
    that the part of the foot's overlap near the corner that both faces count is counted once (a
    shallow valley pushes like a plane, a step's riser and its tread push each with its own force),
    and it cancels its faces' terms at the edges of its region, so the sum is continuous.
    delta = -inf: no feature.
    """
    n = vertices.shape[0]
    if n == 0:
        return _feature(cy, 0.0, 1.0, cx, cy, radius)
    j = first + f // 2
    if f % 2 == 1:
        k = j + 1
        turn = _turn(vertices, ends, k) if k < n else 0.0
        if turn == 0.0:
            return _NONE
        _, _, ix, iy, _, _ = _segment(vertices, ends, k - 1)
        _, _, ox, oy, _, _ = _segment(vertices, ends, k)
        rx, ry = cx - vertices[k, 0], cy - vertices[k, 1]
        if turn < 0.0 and rx * ix + ry * iy >= 0.0 and rx * ox + ry * oy < 0.0:  # in the convex corner's cone
            return _towards(cx, cy, vertices[k, 0], vertices[k, 1], radius, 1.0)
        if turn > 0.0 and rx * ix + ry * iy < 0.0 and rx * ox + ry * oy >= 0.0:  # over both faces of a valley
            return _towards(cx, cy, vertices[k, 0], vertices[k, 1], radius, -1.0)
        return _NONE
    ax, ay, dx, dy, t_min, t_max = _segment(vertices, ends, j)
    t = (cx - ax) * dx + (cy - ay) * dy
    s = (cx - ax) * (-dy) + (cy - ay) * dx
    return _feature(s, -dy, dx, cx, cy, radius) if t_min <= t < t_max and s >= 0.0 else _NONE


@kernel
def _nearest_surface(
    cx: float, cy: float, radius: float, vertices: np.ndarray, ends: np.ndarray, first: int, count: int
) -> tuple[float, float, float, float, float, float]:
    """The feature of a centre inside the ground (a point foot): the segment whose surface is nearest above it.

    Without one (under a ridge beyond every segment's projection): the vertical depth, normal (0, 1).
    """
    best = _NONE
    best_s = -math.inf
    for f in range(0, count, 2):
        ax, ay, dx, dy, t_min, t_max = _segment(vertices, ends, first + f // 2)
        t = (cx - ax) * dx + (cy - ay) * dy
        s = (cx - ax) * (-dy) + (cy - ay) * dx
        if t_min <= t < t_max and best_s < s < 0.0:
            best, best_s = _feature(s, -dy, dx, cx, cy, radius), s
    if best_s == -math.inf:
        return _feature(cy - ground_height(cx, vertices, ends), 0.0, 1.0, cx, cy, radius)
    return best


@kernel
def ground_window(cx: float, radius: float, vertices: np.ndarray) -> tuple[int, int]:
    """(first, count): the features f in range(count) of :func:`ground_feature` that can touch the circle.

    They are the segments (and the corners after them) from segment ``first`` (-1: the left ray) that
    reach within R of C along x, found by bisection; the flat ground has one feature, the plane.
    """
    n = vertices.shape[0]
    if n == 0:
        return 0, 1
    first = _first_at_or_after(vertices, cx - radius) - 1
    stop = _first_at_or_after(vertices, np.nextafter(cx + radius, math.inf))
    return first, 2 * (stop - first)


@kernel
def ground_contacts(
    cx: float, cy: float, radius: float, vertices: np.ndarray, ends: np.ndarray, first: int, count: int, f: int
) -> tuple[float, float, float, float, float, float]:
    """Contact feature f of the window (first, count) of :func:`ground_window`: (delta, P_x, P_y, n_x, n_y, sign).

    A foot's contact force is the sum over these features of sign times the force of each that
    penetrates (delta > 0), and its contact energy the same sum of their energies. A centre inside
    the ground (below the surface: a point foot) touches only the nearest surface, feature 0.
    """
    if vertices.shape[0] > 0 and cy < ground_height(cx, vertices, ends):
        return _nearest_surface(cx, cy, radius, vertices, ends, first, count) if f == 0 else _NONE
    return ground_feature(cx, cy, radius, vertices, ends, first, f)


@kernel
def ground_contact(
    cx: float, cy: float, radius: float, vertices: np.ndarray, ends: np.ndarray
) -> tuple[float, float, float, float, float]:
    """The deepest (added) feature of a circle against the profile: (delta, P_x, P_y, n_x, n_y).

    Its penetration is the foot's (the event function, negative in the air: R - distance within R of
    the profile, beyond that R minus the vertical clearance) and P its contact point. On the flat
    ground (no vertex) it is the plane: delta = R - C_y, P = (C_x, C_y - R), n = (0, 1).
    """
    if vertices.shape[0] == 0:
        return radius - cy, cx - radius * 0.0, cy - radius * 1.0, 0.0, 1.0
    first, count = ground_window(cx, radius, vertices)
    best = _NONE
    for f in range(count):
        feature = ground_contacts(cx, cy, radius, vertices, ends, first, count, f)
        if feature[5] > 0.0 and feature[0] > best[0]:
            best = feature
    if best[0] == -math.inf:
        best = _feature(cy - ground_height(cx, vertices, ends), 0.0, 1.0, cx, cy, radius)
    return best[0], best[1], best[2], best[3], best[4]


def ground_height_at(x: float | np.ndarray, vertices: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """:func:`ground_height` at each of ``x`` (Python side: drawing, the rigid models, tests)."""
    xs = np.atleast_1d(np.asarray(x, dtype=float))
    return np.array([ground_height(float(v), vertices, ends) for v in xs])


@kernel
def _flat_clearance(x: float, y: float, ground: FlatGround) -> float:
    return y


@kernel
def _profile_clearance(x: float, y: float, ground: ProfileGround) -> float:
    return y - ground_height(x, ground.vertices, ground.ends)


ground_clearance = by_type(
    "ground_clearance", "ground", {FlatGround: _flat_clearance, ProfileGround: _profile_clearance}
)
ground_clearance.__doc__ = (
    """Height of the point (x, y) of the slope frame above ``ground`` (the fall check's hip height)."""
)
