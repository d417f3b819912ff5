"""The layout of a rigid walker tree's parameter vector, and its points' positions, Jacobians and bias accelerations
(numba; :mod:`biped_sim.rigid.tree_kernels` holds the equations, :mod:`biped_sim.rigid.tree` writes the vector).

Layout of ``p``: the header (P_NQ, P_L the leg length, P_R the stance foot's radius, P_LEAN the locked leg's foot
lean phi, P_GX and P_GY the gravity vector in the slope frame, P_FALL), T_NLOCK, T_NPHASE, T_NPTS, T_RSW (the
landing foot's radius), T_NLIGHT, T_NOFF (the bodies off the legs, a torso), T_NELEM, the offsets T_ROWS ...
T_TRIG; per table: the rolling coordinate, then per row (mass, inertia, coordinate, w (2 n)), heavy rows first;
the hip's and the landing foot's w (2 n each, table 0); per lock (parent, child, limit, sign: +1 upper / -1 lower,
active); per phase (kind, lock); the permutation (n), the shift (n), each table's light flags (n each) and each
coordinate's fall angle (n: a body off the legs its own); per joint element (law, child, other, the law's
parameters); a workspace (the solves); the sines and cosines of the angles last evaluated (2 n).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.lib.stride_tricks import as_strided

from biped_sim.contact.joint_element import N_ELEMENT_PARAMS
from biped_sim.kernel import kernel

P_NQ, P_L, P_R, P_LEAN, P_GX, P_GY, P_FALL, T0 = 0, 1, 2, 3, 4, 5, 6, 7
T_NLOCK, T_NPHASE, T_NPTS, T_RSW, T_NLIGHT = T0, T0 + 1, T0 + 2, T0 + 3, T0 + 4
T_NOFF = T0 + 5  # the bodies off the legs (the last coordinates)
T_NELEM = T0 + 6  # the joint elements (springs, dampers)
# where each part starts (written by layout_offsets): the two tables' first rows, the hip's and landing foot's w,
# the locks, the phases, the permutation, the elements, the workspace, the sines and cosines of the last angles
T_ROWS, T_EXTRA, T_LOCK, T_PHASE, T_PERM = T0 + 7, T0 + 9, T0 + 10, T0 + 11, T0 + 12
T_ELEM, T_WORK, T_TRIG = T0 + 13, T0 + 14, T0 + 15
T_TABLES = T0 + 16
LOCK_FIELDS, PHASE_FIELDS, ROW_HEAD = 5, 2, 3
ELEMENT_HEAD = 3  # an element's law, child coordinate and other coordinate; its law's parameters follow
ELEMENT_FIELDS = ELEMENT_HEAD + N_ELEMENT_PARAMS


def layout_offsets(n: int, n_points: int, n_light: int, n_lock: int, n_phase: int, n_elem: int) -> dict[int, int]:
    """The header's offsets (T_ROWS, T_ROWS + 1, T_EXTRA, ...) and the total length ('size') of a tree's vector."""
    table = 1 + (n_points + n_light) * (ROW_HEAD + 2 * n)
    offsets = {T_ROWS: T_TABLES + 1, T_ROWS + 1: T_TABLES + table + 1, T_EXTRA: T_TABLES + 2 * table}
    offsets[T_LOCK] = offsets[T_EXTRA] + 4 * n
    offsets[T_PHASE] = offsets[T_LOCK] + LOCK_FIELDS * n_lock
    offsets[T_PERM] = offsets[T_PHASE] + PHASE_FIELDS * n_phase
    offsets[T_ELEM] = offsets[T_PERM] + 5 * n  # the permutation, the shift, both tables' light flags, fall angles
    offsets[T_WORK] = offsets[T_ELEM] + ELEMENT_FIELDS * n_elem
    m = n + n_lock
    offsets[T_TRIG] = offsets[T_WORK] + m * m + m + 2 * (n_points + n_light) + 3 * n
    return offsets


@kernel
def block(p: np.ndarray, at: int, rows: int, cols: int) -> np.ndarray:
    """The (rows x cols) row-major block of p that starts at p[at], as a 2-D view: no copy, and none of
    ``reshape``'s checks (an out-of-line call at every evaluation)."""
    return as_strided(p[at:], shape=(rows, cols), strides=(cols * p.strides[0], p.strides[0]))


@kernel
def coords(p: np.ndarray) -> int:
    return int(p[P_NQ])


@kernel
def rolling(p: np.ndarray, t: int) -> int:
    """Table t's rolling coordinate (the pinned foot's body)."""
    return int(p[int(p[T_ROWS + t]) - 1])


@kernel
def row_offset(p: np.ndarray, t: int, i: int) -> int:
    """Offset of row i of table t (mass, inertia, coordinate, w)."""
    return int(p[T_ROWS + t]) + i * (ROW_HEAD + 2 * coords(p))


@kernel
def w_offset(p: np.ndarray, t: int, i: int) -> int:
    """Offset of the w vectors of row i of table t; in table 0, i = T_NPTS is the hip, T_NPTS + 1 the landing foot."""
    npts = int(p[T_NPTS])
    if i < npts:
        return row_offset(p, t, i) + ROW_HEAD
    return int(p[T_EXTRA]) + (i - npts) * 2 * coords(p)


@kernel
def lock_offset(p: np.ndarray, j: int) -> int:
    """Offset of lock j's fields."""
    return int(p[T_LOCK]) + LOCK_FIELDS * j


@kernel
def element_offset(p: np.ndarray, e: int) -> int:
    """Offset of joint element e's fields (law, child, other, the law's parameters)."""
    return int(p[T_ELEM]) + ELEMENT_FIELDS * e


@kernel
def phase_offset(p: np.ndarray, k: int) -> int:
    """Offset of phase k's fields (kind, lock)."""
    return int(p[T_PHASE]) + PHASE_FIELDS * k


@kernel
def perm_offset(p: np.ndarray) -> int:
    return int(p[T_PERM])


@kernel
def light_flags(p: np.ndarray, t: int) -> int:
    """Offset of table t's light flags: p[offset + k] != 0 when no mass, inertia or lock turns with coordinate k,
    only the feet's infinitesimal masses (Garcia's massless swing leg)."""
    return int(p[T_PERM]) + (2 + t) * coords(p)


@kernel
def fall_angle(p: np.ndarray, k: int) -> float:
    """Coordinate k's fall angle from the slope normal (a leg's: simulation.fall_leg_angle; a torso's: its own)."""
    return p[int(p[T_PERM]) + 4 * coords(p) + k]


@kernel
def work_offset(p: np.ndarray) -> int:
    return int(p[T_WORK])


@kernel
def fill_trig(p: np.ndarray, q: np.ndarray) -> None:
    """Store sin and cos of every angle of q: the cached kernels below read them (one evaluation per angle)."""
    o = int(p[T_TRIG])
    for k in range(coords(p)):
        p[o + 2 * k], p[o + 2 * k + 1] = math.sin(q[k]), math.cos(q[k])


@kernel
def point_at(p: np.ndarray, base: int, q: np.ndarray) -> tuple[float, float]:
    """Position of the point whose table-0 w vectors start at p[base] (cached angles: :func:`fill_trig`)."""
    o = int(p[T_TRIG])
    x, y = -p[P_R] * q[rolling(p, 0)], p[P_R]
    for k in range(coords(p)):
        wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
        s, c = p[o + 2 * k], p[o + 2 * k + 1]
        x += c * wx - s * wy
        y += s * wx + c * wy
    return x, y


@kernel
def point(p: np.ndarray, i: int, q: np.ndarray) -> tuple[float, float]:
    """Position of row i of table 0 (slope frame, the stance contact point at x = 0 when its angle is 0)."""
    fill_trig(p, q)
    return point_at(p, w_offset(p, 0, i), q)


def gravity_vector(gravity: float, slope: float) -> tuple[float, float]:
    """(P_GX, P_GY): gravity in the slope frame (x downhill along the slope, y along its normal)."""
    return gravity * math.sin(slope), -gravity * math.cos(slope)


@kernel
def turned(p: np.ndarray, base: int, k: int) -> tuple[float, float]:
    """Rot(theta_k) perp(w_k) of the point whose w vectors start at p[base]: d/dtheta_k of Rot(theta_k) w_k, whose
    rotation by -90 degrees, (y, -x), is Rot(theta_k) w_k itself (cached angles)."""
    wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
    o = int(p[T_TRIG]) + 2 * k
    s, c = p[o], p[o + 1]
    return -s * wx - c * wy, c * wx - s * wy


@kernel
def jacobian_column(p: np.ndarray, t: int, base: int, k: int) -> tuple[float, float]:
    """Column k of the Jacobian of the point whose w vectors start at p[base]: :func:`turned` plus, on the pinned
    foot's body, the rolling (-R, 0) of table t (cached angles)."""
    jx, jy = turned(p, base, k)
    if k == rolling(p, t):
        jx -= p[P_R]
    return jx, jy


@kernel
def velocity_at(p: np.ndarray, t: int, base: int, qd: np.ndarray) -> tuple[float, float]:
    """Velocity of the point whose w vectors start at p[base] (cached angles)."""
    vx = vy = 0.0
    for k in range(coords(p)):
        jx, jy = jacobian_column(p, t, base, k)
        vx += jx * qd[k]
        vy += jy * qd[k]
    return vx, vy


@kernel
def point_velocity(p: np.ndarray, t: int, i: int, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Velocity of row i of table t."""
    fill_trig(p, q)
    return velocity_at(p, t, w_offset(p, t, i), qd)
