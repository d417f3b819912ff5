"""Compiled rigid equations of a walker tree built from its description (numba; the slow reference is ``.py_func``).

Coordinates: every body's absolute angle (from the slope normal, + with its distal end downhill), in role order
(the stance leg's bodies hip down, then the swing leg's), the stance foot pinned (a point) or rolling (an arc of
radius R, its centre at (x0 - R theta_f, R)). Every point the equations need (each body's centre of mass, the
hip, the swing foot's centre) is ``C + sum_k Rot(theta_k) w_k``: a constant vector w_k per coordinate, read from
the tree (:mod:`biped_sim.rigid.tree`). So its Jacobian column k is ``Rot(theta_k) perp(w_k)`` (plus the rolling
``(-R, 0)`` on the stance foot's body), its bias acceleration ``-sum_k Rot(theta_k) w_k thetadot_k^2``, and

* the flow is Kane's equations with the locked joint stops as constraints, ``[M A^T; A 0] [qdd; lambda] =
  [sum_i m_i J_i^T (g - Jdot_i qd); 0]``, ``M = sum_i m_i J_i^T J_i + diag(I_i)``, ``A`` the rows
  ``e_child - e_parent`` of the locked joints (their relative angle held at the stop);
* a plastic impact (a stop strike, or the heel strike with both legs' stops locked through it) is the same
  system with velocities: ``[M' A'^T; A' 0] [qd+; Lambda] = [sum_i m_i J_i'^T v_i- + I_i omega_i-; 0]``, the
  primed quantities in the coordinates after it (the legs swapped at a heel strike), v- the bodies' velocities
  before: the impulses act only at the new contact and at the locked joints.

The points are the bodies' centres of mass and the point masses (rows of mass, inertia, the coordinate its
inertia turns with, and w). Two tables hold them: table 0 with the stance foot pinned (the flow), table 1 with
the swing foot pinned, in the same coordinates (the heel strike's Jacobians; its constants do not matter). The
legs being alike, the next step runs on table 0 again after the roles are swapped (checked when built).

Layout of ``p`` after the shared header of :mod:`biped_sim.rigid.kernels` (``P_BODIES`` on): T_NLOCK, T_NPHASE,
T_NPTS, T_RSW (the swing foot's radius); per table: the rolling coordinate, then per row (mass, inertia,
coordinate, w (2 n)); the hip's and the swing foot's w (2 n each, table 0); per lock (parent, child, limit, sign:
+1 upper / -1 lower, active); per phase (kind, lock); the swap permutation (n); a workspace (the solves).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.kernel import kernel

P_NQ, P_L, P_R, P_G, P_SLOPE, P_FALL, T0 = 0, 1, 2, 4, 5, 6, 9
T_NLOCK, T_NPHASE, T_NPTS, T_RSW, T_TABLES = T0, T0 + 1, T0 + 2, T0 + 3, T0 + 4
LOCK_FIELDS, PHASE_FIELDS, ROW_HEAD = 5, 2, 3
STOP, PAST, STRIKE = 0, 1, 2  # phase kinds: a swing stop strikes; the hip passes over the stance foot; heel strike
FALL_HIP_FRACTION = 0.05  # the hip below this fraction of the leg length is a fall (every rigid walker's)


@kernel
def _n(p: np.ndarray) -> int:
    return int(p[P_NQ])


@kernel
def _table(p: np.ndarray, t: int) -> int:
    """Offset of table t (its rolling coordinate; its rows follow)."""
    n, npts = _n(p), int(p[T_NPTS])
    return T_TABLES + t * (1 + npts * (ROW_HEAD + 2 * n))


@kernel
def row_offset(p: np.ndarray, t: int, i: int) -> int:
    """Offset of row i of table t (mass, inertia, coordinate, w)."""
    return _table(p, t) + 1 + i * (ROW_HEAD + 2 * _n(p))


@kernel
def _w(p: np.ndarray, t: int, i: int) -> int:
    """Offset of the w vectors of row i of table t; in table 0, i = T_NPTS is the hip, T_NPTS + 1 the swing foot."""
    npts = int(p[T_NPTS])
    if i < npts:
        return row_offset(p, t, i) + ROW_HEAD
    return _table(p, 2) + (i - npts) * 2 * _n(p)


@kernel
def lock_offset(p: np.ndarray, j: int) -> int:
    """Offset of lock j's fields."""
    return _table(p, 2) + 4 * _n(p) + LOCK_FIELDS * j


@kernel
def phase_offset(p: np.ndarray, k: int) -> int:
    """Offset of phase k's fields (kind, lock)."""
    return lock_offset(p, int(p[T_NLOCK])) + PHASE_FIELDS * k


@kernel
def perm_offset(p: np.ndarray) -> int:
    return phase_offset(p, int(p[T_NPHASE]))


@kernel
def work_offset(p: np.ndarray) -> int:
    return perm_offset(p) + _n(p)


def layout_size(n: int, n_points: int, n_lock: int, n_phase: int) -> tuple[int, int]:
    """(parameter length without workspace, workspace length) of a tree of n coordinates."""
    size = T_TABLES + 2 * (1 + n_points * (ROW_HEAD + 2 * n)) + 4 * n + LOCK_FIELDS * n_lock
    size += PHASE_FIELDS * n_phase + n
    m = n + n_lock
    return size, m * m + m + 2 * n_points + 2 * n


@kernel
def point(p: np.ndarray, i: int, q: np.ndarray) -> tuple[float, float]:
    """Position of row i of table 0 (slope frame, the stance contact point at x = 0 when its angle is 0)."""
    base = _w(p, 0, i)
    x, y = -p[P_R] * q[int(p[_table(p, 0)])], p[P_R]
    for k in range(_n(p)):
        wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
        s, c = math.sin(q[k]), math.cos(q[k])
        x += c * wx - s * wy
        y += s * wx + c * wy
    return x, y


@kernel
def _jacobian(p: np.ndarray, t: int, i: int, q: np.ndarray, k: int) -> tuple[float, float]:
    """Column k of the Jacobian of row i of table t."""
    base = _w(p, t, i)
    wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
    s, c = math.sin(q[k]), math.cos(q[k])
    jx, jy = -s * wx - c * wy, c * wx - s * wy
    if k == int(p[_table(p, t)]):
        jx -= p[P_R]
    return jx, jy


@kernel
def point_velocity(p: np.ndarray, t: int, i: int, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Velocity of row i of table t."""
    vx = vy = 0.0
    for k in range(_n(p)):
        jx, jy = _jacobian(p, t, i, q, k)
        vx += jx * qd[k]
        vy += jy * qd[k]
    return vx, vy


@kernel
def _bias(p: np.ndarray, i: int, q: np.ndarray, qd: np.ndarray) -> tuple[float, float]:
    """Jdot qd of row i of table 0: -sum_k Rot(theta_k) w_k thetadot_k^2."""
    base = _w(p, 0, i)
    bx = by = 0.0
    for k in range(_n(p)):
        wx, wy = p[base + 2 * k], p[base + 2 * k + 1]
        s, c = math.sin(q[k]), math.cos(q[k])
        r2 = qd[k] * qd[k]
        bx -= (c * wx - s * wy) * r2
        by -= (s * wx + c * wy) * r2
    return bx, by


@kernel
def _assemble(p: np.ndarray, t: int, q: np.ndarray, w: int, m: int) -> int:
    """Write M of table t and the active lock rows into the (m x m) matrix at p[w:]; returns the rows used (the
    workspace's last 2 n floats hold a point's Jacobian meanwhile)."""
    n = _n(p)
    jw = w + m * m + m + 2 * int(p[T_NPTS])
    for a in range(m * m):
        p[w + a] = 0.0
    for i in range(int(p[T_NPTS])):
        o = row_offset(p, t, i)
        mass, inertia, own = p[o], p[o + 1], int(p[o + 2])
        p[w + own * m + own] += inertia
        if mass == 0.0:
            continue
        for k in range(n):
            p[jw + 2 * k], p[jw + 2 * k + 1] = _jacobian(p, t, i, q, k)
        for k in range(n):
            for col in range(k, n):
                p[w + k * m + col] += mass * (p[jw + 2 * k] * p[jw + 2 * col] + p[jw + 2 * k + 1] * p[jw + 2 * col + 1])
    for k in range(n):
        for col in range(k + 1, n):
            p[w + col * m + k] = p[w + k * m + col]
    used = n
    for j in range(int(p[T_NLOCK])):
        o = lock_offset(p, j)
        if p[o + 4] != 0.0:
            parent, child = int(p[o]), int(p[o + 1])
            p[w + used * m + parent] = p[w + parent * m + used] = -1.0
            p[w + used * m + child] = p[w + child * m + used] = 1.0
            used += 1
    return used


@kernel
def _solve(p: np.ndarray, w: int, m: int, used: int, r: int) -> None:
    """Solve the leading (used x used) block of the matrix at p[w:] (row stride m) for the vector at p[r:], in
    place (Gaussian elimination with partial pivoting: the constrained system is indefinite)."""
    for col in range(used):
        pivot = col
        for row in range(col + 1, used):
            if abs(p[w + row * m + col]) > abs(p[w + pivot * m + col]):
                pivot = row
        if pivot != col:
            for a in range(used):
                p[w + col * m + a], p[w + pivot * m + a] = p[w + pivot * m + a], p[w + col * m + a]
            p[r + col], p[r + pivot] = p[r + pivot], p[r + col]
        for row in range(col + 1, used):
            factor = p[w + row * m + col] / p[w + col * m + col]
            for a in range(col, used):
                p[w + row * m + a] -= factor * p[w + col * m + a]
            p[r + row] -= factor * p[r + col]
    for col in range(used - 1, -1, -1):
        total = p[r + col]
        for a in range(col + 1, used):
            total -= p[w + col * m + a] * p[r + a]
        p[r + col] = total / p[w + col * m + col]


@kernel
def tree_rhs(p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = dx/dt: Kane's equations with the locked stops as constraints."""
    n = _n(p)
    m = n + int(p[T_NLOCK])
    q, qd = x[:n], x[n:]
    w = work_offset(p)
    r = w + m * m
    used = _assemble(p, 0, q, w, m)
    gx, gy = p[P_G] * math.sin(p[P_SLOPE]), -p[P_G] * math.cos(p[P_SLOPE])
    for a in range(m):
        p[r + a] = 0.0
    for i in range(int(p[T_NPTS])):
        mass = p[row_offset(p, 0, i)]
        if mass == 0.0:
            continue
        bx, by = _bias(p, i, q, qd)
        for k in range(n):
            jx, jy = _jacobian(p, 0, i, q, k)
            p[r + k] += mass * (jx * (gx - bx) + jy * (gy - by))
    _solve(p, w, m, used, r)
    for k in range(n):
        out[k] = qd[k]
        out[n + k] = p[r + k]


@kernel
def tree_energy(p: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """(kinetic, potential) energy of the rows of table 0 (potential zero with every point on the ground line)."""
    n = _n(p)
    q, qd = x[:n], x[n:]
    gx, gy = p[P_G] * math.sin(p[P_SLOPE]), -p[P_G] * math.cos(p[P_SLOPE])
    kinetic = potential = 0.0
    for i in range(int(p[T_NPTS])):
        o = row_offset(p, 0, i)
        mass, inertia, own = p[o], p[o + 1], int(p[o + 2])
        vx, vy = point_velocity(p, 0, i, q, qd)
        px, py = point(p, i, q)
        kinetic += 0.5 * mass * (vx * vx + vy * vy) + 0.5 * inertia * qd[own] * qd[own]
        potential -= mass * (gx * px + gy * py)
    return kinetic, potential


@kernel
def tree_impact(p: np.ndarray, x: np.ndarray, strike: bool, out: np.ndarray) -> None:
    """out = the state after a plastic impact with the active locks: a stop strike (table 0), or the heel strike
    (``strike``: table 1, the new stance foot pinned; then the roles swapped, coordinate k after it being
    coordinate perm[k] before). The right side is each row's momentum just before, m J'^T v- + I omega-."""
    n = _n(p)
    m = n + int(p[T_NLOCK])
    q, qd = x[:n], x[n:]
    w = work_offset(p)
    r, v = w + m * m, w + m * m + m
    t = 1 if strike else 0
    npts = int(p[T_NPTS])
    if strike:  # every stop of both legs locked through the heel strike
        for j in range(int(p[T_NLOCK])):
            p[lock_offset(p, j) + 4] = 1.0
    for i in range(npts):
        p[v + 2 * i], p[v + 2 * i + 1] = point_velocity(p, 0, i, q, qd)
    used = _assemble(p, t, q, w, m)
    for a in range(m):
        p[r + a] = 0.0
    for i in range(npts):
        o = row_offset(p, t, i)
        own = int(p[o + 2])
        p[r + own] += p[o + 1] * qd[own]
        for k in range(n):
            jx, jy = _jacobian(p, t, i, q, k)
            p[r + k] += p[o] * (jx * p[v + 2 * i] + jy * p[v + 2 * i + 1])
    _solve(p, w, m, used, r)
    perm = perm_offset(p)
    for k in range(n):
        src = int(p[perm + k]) if strike else k
        out[k] = q[src]
        out[n + k] = p[r + src]


@kernel
def tree_guard(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """The phase's guard (its downward zero ends it): a stop's margin, the stance foot's lead over the hip, or the
    swing foot's height above the slope."""
    n = _n(p)
    o = phase_offset(p, phase)
    kind = int(p[o])
    if kind == STOP:
        lo = lock_offset(p, int(p[o + 1]))
        return p[lo + 3] * (p[lo + 2] - (x[int(p[lo + 1])] - x[int(p[lo])]))
    npts = int(p[T_NPTS])
    if kind == PAST:
        hip_x, _ = point(p, npts, x[:n])
        return -p[P_R] * x[int(p[_table(p, 0)])] - hip_x
    _, foot_y = point(p, npts + 1, x[:n])
    return foot_y - p[T_RSW]


@kernel
def tree_guard_rate(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """Time derivative of :func:`tree_guard` (positions move with the rates in x)."""
    n = _n(p)
    o = phase_offset(p, phase)
    kind = int(p[o])
    if kind == STOP:
        lo = lock_offset(p, int(p[o + 1]))
        return -p[lo + 3] * (x[n + int(p[lo + 1])] - x[n + int(p[lo])])
    npts = int(p[T_NPTS])
    if kind == PAST:
        vx, _ = point_velocity(p, 0, npts, x[:n], x[n:])
        return -p[P_R] * x[n + int(p[_table(p, 0)])] - vx
    _, vy = point_velocity(p, 0, npts + 1, x[:n], x[n:])
    return vy


@kernel
def begin_step(p: np.ndarray) -> None:
    """At a step's start the stance leg's stops are locked and the swing leg's free (the new swing knee unlocks)."""
    for k in range(int(p[T_NPHASE])):
        o = phase_offset(p, k)
        if int(p[o]) == STOP:
            p[lock_offset(p, int(p[o + 1])) + 4] = 0.0


@kernel
def after_phase(p: np.ndarray, phase: int, x: np.ndarray, out: np.ndarray) -> None:
    """After a swing stop's strike: lock it at its limit (the strike located to round-off, or a fixed step's
    overshoot projected out) and apply the plastic impact to x (in place, through out)."""
    o = phase_offset(p, phase)
    if int(p[o]) != STOP:
        return
    lo = lock_offset(p, int(p[o + 1]))
    p[lo + 4] = 1.0
    x[int(p[lo + 1])] = x[int(p[lo])] + p[lo + 2]
    tree_impact(p, x, False, out)
    x[:] = out


@kernel
def skip_phase(p: np.ndarray, phase: int, x: np.ndarray) -> bool:
    """The hip already past the stance foot (after a late stop strike): that phase has nothing to wait for."""
    return int(p[phase_offset(p, phase)]) == PAST and tree_guard(p, phase, x) <= 0.0


@kernel
def tree_fall(p: np.ndarray, i: int, x: np.ndarray) -> float:
    """Fall function i (positive while standing): 0, 1: the fall angle minus |each leg's hip body's angle|; 2: the
    hip's height minus 0.05 l."""
    if i < 2:
        return p[P_FALL] - abs(x[0 if i == 0 else int(p[perm_offset(p)])])
    _, hip_y = point(p, int(p[T_NPTS]), x[: _n(p)])
    return hip_y - FALL_HIP_FRACTION * p[P_L]


@kernel
def tree_push(p: np.ndarray, x: np.ndarray, px: float, py: float, out: np.ndarray) -> float:
    """out = the state just after an impulse (px, py) on the hip, ``[M A^T; A 0] [dqd; Lambda] = [J_hip^T p; 0]``
    (the stance foot and the locked stops hold); returns the ground's normal impulse (the walker's momentum change
    minus p, normal part: negative when the push would lift the stance foot)."""
    n = _n(p)
    m = n + int(p[T_NLOCK])
    q, qd = x[:n], x[n:]
    w = work_offset(p)
    r = w + m * m
    npts = int(p[T_NPTS])
    used = _assemble(p, 0, q, w, m)
    for a in range(m):
        p[r + a] = 0.0
    for k in range(n):
        jx, jy = _jacobian(p, 0, npts, q, k)
        p[r + k] = jx * px + jy * py
    _solve(p, w, m, used, r)
    normal = -py
    for i in range(npts):
        mass = p[row_offset(p, 0, i)]
        for k in range(n):
            _, jy = _jacobian(p, 0, i, q, k)
            normal += mass * jy * p[r + k]
    for k in range(n):
        out[k] = q[k]
        out[n + k] = qd[k] + p[r + k]
    return normal
