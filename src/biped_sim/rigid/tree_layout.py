"""The layout of a rigid walker tree's parameter vector, and its points' positions, Jacobians and bias accelerations
(numba; :mod:`biped_sim.rigid.tree_kernels` holds the equations, :mod:`biped_sim.rigid.tree` writes the vector).

Layout of ``p``: the header (P_NQ, P_L the leg length, P_R the stance foot's radius, P_LEAN the locked leg's foot
lean phi, P_G, P_SLOPE, P_FALL), T_NLOCK, T_NPHASE, T_NPTS, T_RSW (the landing foot's radius), T_NLIGHT; per table:
the rolling coordinate, then per row (mass, inertia, coordinate, w (2 n)), heavy rows first; the hip's and the
landing foot's w (2 n each, table 0); per lock (parent, child, limit, sign: +1 upper / -1 lower, active); per phase
(kind, lock); the permutation (n), the shift (n) and each table's light flags (n each); a workspace (the solves).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.kernel import kernel

P_NQ, P_L, P_R, P_LEAN, P_G, P_SLOPE, P_FALL, T0 = 0, 1, 2, 3, 4, 5, 6, 7
T_NLOCK, T_NPHASE, T_NPTS, T_RSW, T_NLIGHT, T_TABLES = T0, T0 + 1, T0 + 2, T0 + 3, T0 + 4, T0 + 5
LOCK_FIELDS, PHASE_FIELDS, ROW_HEAD = 5, 2, 3


@kernel
def coords(p: np.ndarray) -> int:
    return int(p[P_NQ])


@kernel
def table_offset(p: np.ndarray, t: int) -> int:
    """Offset of table t (its rolling coordinate; its rows follow, the light ones last)."""
    n, rows = coords(p), int(p[T_NPTS]) + int(p[T_NLIGHT])
    return T_TABLES + t * (1 + rows * (ROW_HEAD + 2 * n))


@kernel
def row_offset(p: np.ndarray, t: int, i: int) -> int:
    """Offset of row i of table t (mass, inertia, coordinate, w)."""
    return table_offset(p, t) + 1 + i * (ROW_HEAD + 2 * coords(p))


@kernel
def w_offset(p: np.ndarray, t: int, i: int) -> int:
    """Offset of the w vectors of row i of table t; in table 0, i = T_NPTS is the hip, T_NPTS + 1 the swing foot."""
    npts = int(p[T_NPTS])
    if i < npts:
        return row_offset(p, t, i) + ROW_HEAD
    return table_offset(p, 2) + (i - npts) * 2 * coords(p)


@kernel
def lock_offset(p: np.ndarray, j: int) -> int:
    """Offset of lock j's fields."""
    return table_offset(p, 2) + 4 * coords(p) + LOCK_FIELDS * j


@kernel
def phase_offset(p: np.ndarray, k: int) -> int:
    """Offset of phase k's fields (kind, lock)."""
    return lock_offset(p, int(p[T_NLOCK])) + PHASE_FIELDS * k


@kernel
def perm_offset(p: np.ndarray) -> int:
    return phase_offset(p, int(p[T_NPHASE]))


@kernel
def light_flag(p: np.ndarray, t: int, k: int) -> bool:
    """Whether coordinate k is light in table t: no mass, inertia or lock turns with it, only the feet's
    infinitesimal masses (Garcia's massless swing leg)."""
    return p[perm_offset(p) + 2 * coords(p) + t * coords(p) + k] != 0.0


@kernel
def work_offset(p: np.ndarray) -> int:
    return perm_offset(p) + 4 * coords(p)


def layout_size(n: int, n_points: int, n_light: int, n_lock: int, n_phase: int) -> tuple[int, int]:
    """(parameter length without workspace, workspace length) of a tree of n coordinates."""
    size = T_TABLES + 2 * (1 + (n_points + n_light) * (ROW_HEAD + 2 * n)) + 4 * n + LOCK_FIELDS * n_lock
    size += PHASE_FIELDS * n_phase + 4 * n  # the permutation, the shift and the light flags of both tables
    m = n + n_lock
    return size, m * m + m + 2 * (n_points + n_light) + 2 * n


@kernel
def point(p: np.ndarray, i: int, q: np.ndarray) -> tuple[float, float]:
    """Position of row i of table 0 (slope frame, the stance contact point at x = 0 when its angle is 0)."""
    base = w_offset(p, 0, i)
    x, y = -p[P_R] * q[int(p[table_offset(p, 0)])], p[P_R]
    for k in range(coords(p)):
        wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
        s, c = math.sin(q[k]), math.cos(q[k])
        x += c * wx - s * wy
        y += s * wx + c * wy
    return x, y


@kernel
def jacobian(p: np.ndarray, t: int, i: int, q: np.ndarray, k: int) -> tuple[float, float]:
    """Column k of the Jacobian of row i of table t."""
    return jacobian_column(p, t, w_offset(p, t, i), q, k)


@kernel
def jacobian_column(p: np.ndarray, t: int, base: int, q: np.ndarray, k: int) -> tuple[float, float]:
    """Column k of the Jacobian of the point whose w vectors start at p[base] (table t's rolling term)."""
    wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
    s, c = math.sin(q[k]), math.cos(q[k])
    jx, jy = -s * wx - c * wy, c * wx - s * wy
    if k == int(p[table_offset(p, t)]):
        jx -= p[P_R]
    return jx, jy


@kernel
def point_velocity(p: np.ndarray, t: int, i: int, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Velocity of row i of table t."""
    vx = vy = 0.0
    for k in range(coords(p)):
        jx, jy = jacobian(p, t, i, q, k)
        vx += jx * qd[k]
        vy += jy * qd[k]
    return vx, vy


@kernel
def bias(p: np.ndarray, base: int, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Jdot qd of the point whose w vectors start at p[base]: -sum_k Rot(theta_k) w_k thetadot_k^2."""
    bx = by = 0.0
    for k in range(coords(p)):
        wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
        s, c = math.sin(q[k]), math.cos(q[k])
        r2 = qd[k] * qd[k]
        bx -= (c * wx - s * wy) * r2
        by -= (s * wx + c * wy) * r2
    return bx, by
