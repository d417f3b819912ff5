"""A rigid walker tree as its compiled kernels read it, in named, typed records (:class:`RigidTree`), and its
points' positions, Jacobians and bias accelerations (numba; :mod:`biped_sim.rigid.tree_kernels` holds the
equations, :mod:`biped_sim.rigid.tree_build` fills the records).

A NamedTuple of scalars and arrays, its per-item tables numpy record arrays (``np.recarray``: one array each,
its fields read by name, ``tree.locks[j].limit``, compiled and as plain Python alike): a kernel called from
Python unboxes every array of its arguments at each call, so a table is one array, not one per field. The
points of each table: its rows (each body's centre of mass with its point masses folded in, of mass, inertia
and the coordinate its inertia turns with), then the hip and the landing foot (table 0's, copied in table 1),
then the light rows (the feet's infinitesimal masses); each point's w vectors (2 per coordinate).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from biped_sim.kernel import kernel

ROW = np.dtype([("mass", np.float64), ("inertia", np.float64), ("own", np.int64)])
# a joint stop held (active 1, or RELEASED through the heel strike) or free (0): sign +1 upper, -1 lower
LOCK = np.dtype(
    [("parent", np.int64), ("child", np.int64), ("limit", np.float64), ("sign", np.float64), ("active", np.float64)]
)
PHASE = np.dtype([("kind", np.int64), ("lock", np.int64)])  # a phase's kind and, a stop strike's, its lock
# per coordinate: the heel strike's relabelling (coordinate k after it is perm[k] before plus shift[k]), whether it
# is light in the stance (table 0) and in the landing foot's table (1), its fall angle from the slope normal
COORD = np.dtype(
    [("perm", np.int64), ("shift", np.float64), ("stance_light", np.bool_), ("landing_light", np.bool_),
     ("fall_angle", np.float64)]
)  # fmt: skip
ELEMENT = np.dtype([("law", np.int64), ("child", np.int64), ("other", np.int64)])  # a joint element's torque pair


class RigidTree(NamedTuple):
    """A rigid walker tree's parameters (:func:`~biped_sim.rigid.tree_build.tree_params`) and the kernels'
    workspace (``locks['active']``, ``matrix``, ``work``, ``jacobian``, ``trig``: per thread of work, :meth:`copy`)."""

    n: int  # coordinates
    leg_length: float  # the hip's height above the stance foot's contact, the leg locked and upright
    radius: float  # the stance foot's
    landing_radius: float  # the landing foot's
    lean: float  # the locked leg's foot centre's angle from its hip body's axis (phi)
    gx: float  # gravity in the slope frame (x downhill along the slope, y along its normal)
    gy: float
    fall: float  # simulation.fall_leg_angle
    n_points: int  # rows of mass or inertia per table
    n_light: int  # light rows per table (0, or the two feet)
    n_off: int  # bodies off the legs (a torso): the last coordinates
    rolling: tuple[int, int]  # each table's pinned foot's body
    rows: np.ndarray  # (2, points) ROW
    w: np.ndarray  # (2, points, n, 2)
    columns: np.ndarray  # (2, points, n) int64: the coordinates of each point's nonzero Jacobian columns, descending
    n_columns: np.ndarray  # (2, points) int64: how many (a point's w vectors nonzero, or the rolling foot's body)
    locks: np.ndarray  # LOCK
    phases: np.ndarray  # PHASE
    coords: np.ndarray  # (n,) COORD
    elements: np.ndarray  # ELEMENT: the law, the child coordinate and the other
    element_params: np.ndarray  # (elements, N_ELEMENT_PARAMS) each element's law's parameters
    matrix: np.ndarray  # (m, m) the solves' matrix, m = n + locks
    work: np.ndarray  # the solves' right side (m), the rows' velocities (2 per point), the light system's (n)
    jacobian: np.ndarray  # (n, 2) a row's Jacobian
    trig: np.ndarray  # (n, 2) sin and cos of the angles last evaluated

    def copy(self) -> RigidTree:
        """A copy with arrays of its own (the kernels write the workspace and the locks' state)."""
        return RigidTree(*(v.copy() if isinstance(v, np.ndarray) else v for v in self))


def workspace_size(n: int, n_points: int, n_light: int, n_lock: int) -> int:
    """The length of ``work``: the right side (m = n + n_lock), the rows' velocities (2 per point), the light
    system's right side (n)."""
    return n + n_lock + 2 * (n_points + n_light) + n


@kernel
def hip(tree: RigidTree) -> int:
    """The hip's point index (the landing foot's is the next)."""
    return tree.n_points


@kernel
def landing(tree: RigidTree) -> int:
    """The landing foot's point index (its centre's w vectors, table 0's)."""
    return tree.n_points + 1


@kernel
def light_row(tree: RigidTree, j: int) -> int:
    """Light row j's point index (foot j: the stance foot, then the landing one)."""
    return tree.n_points + 2 + j


@kernel
def light(tree: RigidTree, t: int, k: int) -> bool:
    """Whether no mass, inertia or lock turns with coordinate k in table t, only the feet's infinitesimal masses
    (Garcia's massless swing leg)."""
    return tree.coords[k].stance_light if t == 0 else tree.coords[k].landing_light


@kernel
def fill_trig(tree: RigidTree, q: np.ndarray) -> None:
    """Store sin and cos of every angle of q: the cached kernels below read them (one evaluation per angle)."""
    trig = tree.trig
    for k in range(tree.n):
        trig[k, 0], trig[k, 1] = math.sin(q[k]), math.cos(q[k])


@kernel
def point_at(tree: RigidTree, w: np.ndarray, q: np.ndarray) -> tuple[float, float]:
    """Position of the point whose table-0 w vectors are w (cached angles: :func:`fill_trig`)."""
    trig = tree.trig
    x, y = -tree.radius * q[tree.rolling[0]], tree.radius
    for k in range(tree.n):
        wx, wy = w[k, 0], w[k, 1]
        s, c = trig[k, 0], trig[k, 1]
        x += c * wx - s * wy
        y += s * wx + c * wy
    return x, y


@kernel
def point(tree: RigidTree, i: int, q: np.ndarray) -> tuple[float, float]:
    """Position of point i of table 0 (slope frame, the stance contact point at x = 0 when its angle is 0)."""
    fill_trig(tree, q)
    return point_at(tree, tree.w[0, i], q)


def gravity_vector(gravity: float, slope: float) -> tuple[float, float]:
    """(gx, gy): gravity in the slope frame (x downhill along the slope, y along its normal)."""
    return gravity * math.sin(slope), -gravity * math.cos(slope)


@kernel
def lever(tree: RigidTree, w: np.ndarray, k: int) -> tuple[float, float]:
    """Rot(theta_k) w_k of the point whose w vectors are w: its lever turning with coordinate k (cached angles)."""
    wx, wy = w[k, 0], w[k, 1]
    s, c = tree.trig[k, 0], tree.trig[k, 1]
    return c * wx - s * wy, s * wx + c * wy


@kernel
def turned(tree: RigidTree, w: np.ndarray, k: int) -> tuple[float, float]:
    """Rot(theta_k) perp(w_k) = perp(Rot(theta_k) w_k) of the point whose w vectors are w: d/dtheta_k of its
    :func:`lever` (cached angles)."""
    lx, ly = lever(tree, w, k)
    return -ly, lx


@kernel
def jacobian_column(tree: RigidTree, t: int, w: np.ndarray, k: int) -> tuple[float, float]:
    """Column k of the Jacobian of the point whose w vectors are w: :func:`turned` plus, on the pinned foot's body,
    the rolling (-R, 0) of table t (cached angles)."""
    jx, jy = turned(tree, w, k)
    if k == tree.rolling[t]:
        jx -= tree.radius
    return jx, jy


@kernel
def velocity_at(tree: RigidTree, t: int, w: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Velocity of the point whose w vectors are w (cached angles)."""
    vx = vy = 0.0
    for k in range(tree.n):
        jx, jy = jacobian_column(tree, t, w, k)
        vx += jx * qd[k]
        vy += jy * qd[k]
    return vx, vy


@kernel
def point_velocity(tree: RigidTree, t: int, i: int, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Velocity of point i of table t."""
    fill_trig(tree, q)
    return velocity_at(tree, t, tree.w[t, i], qd)
