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
* a plastic impact (a stop strike, or the heel strike with both legs' stops locked through it, the RELEASED ones
  aside) is the same system with velocities: ``[M' A'^T; A' 0] [qd+; Lambda] = [sum_i m_i J_i'^T v_i- + I_i
  omega_i-; 0]``, the primed quantities in the coordinates after it (the legs swapped at a heel strike), v- the
  bodies' velocities before: the impulses act only at the new contact and at the locked joints.

The points are the bodies' centres of mass and the point masses (rows of mass, inertia, the coordinate its
inertia turns with, and w). Two tables hold them: table 0 with the stance foot pinned (the flow), table 1 with
the landing foot pinned, in the same coordinates (the heel strike's Jacobians; its constants do not matter). The
legs being alike (or the wheel's spokes evenly spaced), the next step runs on table 0 again after the heel strike
relabels the coordinates: coordinate k after it is coordinate perm[k] before plus shift[k] (the legs swap; the
wheel's one angle moves on by the spoke spacing).

A coordinate that no mass, inertia or lock turns with (Garcia's massless swing leg, whose foot mass is
infinitesimal) is light: the heavy equations leave it out, and the feet's infinitesimal masses (light rows of unit
weight) give its equations in the limit, their momentum balance across it with the heavy accelerations (or rate
jumps) known (:func:`_light_tier`). The energy and every heavy equation see only the heavy rows.
"""

from __future__ import annotations

import numpy as np

from biped_sim.kernel import kernel
from biped_sim.multibody.bodies import add_body_terms, body_energy, mirror_upper
from biped_sim.rigid.tree_elements import element_forces, tree_element_energy
from biped_sim.rigid.tree_layout import (
    P_GX,
    P_GY,
    P_LEAN,
    P_R,
    ROW_HEAD,
    T_NLIGHT,
    T_NLOCK,
    T_NPHASE,
    T_NPTS,
    block,
    coords,
    fill_trig,
    jacobian_column,
    light_flags,
    lock_offset,
    perm_offset,
    phase_offset,
    point,
    point_at,
    point_velocity,
    rolling,
    row_offset,
    turned,
    velocity_at,
    w_offset,
    work_offset,
)

STOP, PAST, STRIKE = 0, 1, 2  # phase kinds: a swing stop strikes; the hip passes over the stance foot; heel strike
FLOW, IMPACT, AT_REST = 0, 1, 2  # the light rows' right side: gravity and bias; their velocity just before; none
RELEASED = 2.0  # a lock's active field: held through the stance, released through the heel strike


@kernel(literal_arguments=False)
def _row_jacobian(p: np.ndarray, t: int, base: int, qd: np.ndarray, jw: int) -> tuple[float, float]:
    """Write the Jacobian columns of the point whose w vectors start at p[base] to p[jw:] (2 n floats) and return
    its bias acceleration Jdot qd = -sum_k Rot(theta_k) w_k thetadot_k^2 (from the same turned vectors: one pass,
    cached angles)."""
    bx = by = 0.0
    roll = rolling(p, t)
    for k in range(coords(p)):
        jx, jy = turned(p, base, k)
        r2 = qd[k] * qd[k]
        bx -= jy * r2
        by += jx * r2
        p[jw + 2 * k], p[jw + 2 * k + 1] = (jx - p[P_R], jy) if k == roll else (jx, jy)
    return bx, by


@kernel(literal_arguments=False)
def _assemble(p: np.ndarray, t: int, w: int, m: int, qd: np.ndarray, flow: bool, release: bool) -> int:
    """Write M of table t and the active lock rows into the (m x m) matrix at p[w:] and, for the ``flow``, the
    generalized forces sum_i m_i J_i^T (g - Jdot_i qd) into p[w + m m:] (each row's terms by
    :func:`~biped_sim.multibody.bodies.add_body_terms`, as the compliant tree's); returns the rows used (the
    workspace's last 2 n floats hold a row's Jacobian meanwhile; the angles cached by :func:`fill_trig`).
    ``release``: the locks marked RELEASED are left free (a heel strike's trailing knee)."""
    n = coords(p)
    r = w + m * m
    jw = r + m + 2 * (int(p[T_NPTS]) + int(p[T_NLIGHT]))
    matrix, forces, jacobian = block(p, w, m, m), p[r : r + m], block(p, jw, n, 2)
    gx, gy = p[P_GX], p[P_GY]
    for a in range(m * m):
        p[w + a] = 0.0
    for a in range(m):
        p[r + a] = 0.0
    for i in range(int(p[T_NPTS])):
        o = row_offset(p, t, i)
        mass, inertia, own = p[o], p[o + 1], int(p[o + 2])
        fx = fy = 0.0
        if mass != 0.0:
            bx, by = _row_jacobian(p, t, o + ROW_HEAD, qd, jw)
            fx, fy = mass * (gx - bx), mass * (gy - by)
        add_body_terms(matrix, forces, jacobian, mass, inertia, own, fx, fy, flow)
    mirror_upper(matrix, n)
    used = n
    for j in range(int(p[T_NLOCK])):
        o = lock_offset(p, j)
        active = p[o + 4]
        if active != 0.0 and not (release and active == RELEASED):
            parent, child = int(p[o]), int(p[o + 1])
            matrix[used, parent] = matrix[parent, used] = -1.0
            matrix[used, child] = matrix[child, used] = 1.0
            used += 1
    return used


@kernel(reference_counts=False, literal_arguments=False)
def _solve(p: np.ndarray, w: int, m: int, used: int, r: int) -> None:
    """Solve the leading (used x used) block of the matrix at p[w:] (row stride m) for the vector at p[r:], in
    place: Cramer's rule up to 2 x 2 (the compass, the wheel), else Gaussian elimination with partial pivoting (the
    constrained system is indefinite)."""
    if used <= 2:
        a, f = p[w], p[r]
        if used == 1:
            p[r] = f / a
            return
        b, c, d, g = p[w + 1], p[w + m], p[w + m + 1], p[r + 1]
        det = a * d - b * c
        p[r], p[r + 1] = (d * f - b * g) / det, (a * g - c * f) / det
        return
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


@kernel(literal_arguments=False)
def _pin_light(p: np.ndarray, t: int, w: int, m: int, r: int) -> None:
    """Give the light coordinates of table t (zero rows and columns of M) a unit diagonal and a zero right side,
    so that the heavy solve leaves them at 0 for :func:`_light_tier`."""
    flags = light_flags(p, t)
    for k in range(coords(p)):
        if p[flags + k] != 0.0:
            p[w + k * m + k] = 1.0
            p[r + k] = 0.0


@kernel(literal_arguments=False)
def _light_tier(p: np.ndarray, t: int, q: np.ndarray, qd: np.ndarray, mode: int, w: int, m: int, r: int) -> None:
    """The light coordinates' equations, the limit of infinitesimal foot masses (Garcia et al. 1998): each light
    row's balance across the light coordinates, sum_i J_iL^T (J_i a - b_i) = 0, with the heavy part of a already
    solved in p[r:] and written back there (b_i: g - Jdot_i qd in the flow, the row's velocity just before an
    impact, 0 for a push or at rest). The heavy equations do not see these rows: their masses vanish. Light row j
    is foot j (the stance foot, then the landing one): the foot pinned in table t (row t) has no Jacobian."""
    n, npts, n_light, flags = coords(p), int(p[T_NPTS]), int(p[T_NLIGHT]), light_flags(p, t)
    size = 0
    for k in range(n):
        size += 1 if p[flags + k] != 0.0 else 0
    if size == 0:
        return
    rhs = r + m + 2 * (npts + n_light)  # the Jacobian's scratch; the light system's right side after it
    jw = rhs + n
    for a in range(size):
        p[rhs + a] = 0.0
        for b in range(size):
            p[w + a * m + b] = 0.0
    for j in range(n_light):
        if j == t:
            continue
        bx, by = _row_jacobian(p, t, row_offset(p, t, npts + j) + ROW_HEAD, qd, jw)
        cx, cy = (p[P_GX] - bx, p[P_GY] - by) if mode == FLOW else (0.0, 0.0)
        if mode == IMPACT:
            cx, cy = velocity_at(p, 0, row_offset(p, 0, npts + j) + ROW_HEAD, qd)
        for k in range(n):
            if p[flags + k] == 0.0:
                cx, cy = cx - p[jw + 2 * k] * p[r + k], cy - p[jw + 2 * k + 1] * p[r + k]
        a = 0
        for k in range(n):
            if p[flags + k] != 0.0:
                p[rhs + a] += p[jw + 2 * k] * cx + p[jw + 2 * k + 1] * cy
                b = 0
                for col in range(n):
                    if p[flags + col] != 0.0:
                        p[w + a * m + b] += p[jw + 2 * k] * p[jw + 2 * col] + p[jw + 2 * k + 1] * p[jw + 2 * col + 1]
                        b += 1
                a += 1
    _solve(p, w, m, size, rhs)
    a = 0
    for k in range(n):
        if p[flags + k] != 0.0:
            p[r + k] = p[rhs + a]
            a += 1


@kernel
def tree_rhs(p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = dx/dt: Kane's equations with the locked stops as constraints, the joint elements' torques among the
    generalized forces."""
    n = coords(p)
    m = n + int(p[T_NLOCK])
    q, qd = x[:n], x[n:]
    fill_trig(p, q)
    w = work_offset(p)
    r = w + m * m
    used = _assemble(p, 0, w, m, qd, True, False)
    element_forces(p, q, qd, r)
    _pin_light(p, 0, w, m, r)
    _solve(p, w, m, used, r)
    _light_tier(p, 0, q, qd, FLOW, w, m, r)
    for k in range(n):
        out[k] = qd[k]
        out[n + k] = p[r + k]


@kernel
def tree_energy(p: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """(kinetic, potential) energy of the rows of table 0 (gravity's potential zero with every point on the ground
    line) and the joint elements' stored energy among the potential."""
    n = coords(p)
    q, qd = x[:n], x[n:]
    fill_trig(p, q)
    gx, gy = p[P_GX], p[P_GY]
    kinetic = potential = 0.0
    for i in range(int(p[T_NPTS])):
        o = row_offset(p, 0, i)
        mass, inertia, own = p[o], p[o + 1], int(p[o + 2])
        vx, vy = velocity_at(p, 0, w_offset(p, 0, i), qd)
        px, py = point_at(p, w_offset(p, 0, i), q)
        body_kinetic, body_potential = body_energy(mass, inertia, vx, vy, qd[own], px, py, gx, gy)
        kinetic += body_kinetic
        potential += body_potential
    return kinetic, potential + tree_element_energy(p, q)


@kernel(literal_arguments=False)
def _impact_rates(p: np.ndarray, t: int, q: np.ndarray, qd: np.ndarray, release: bool) -> None:
    """The rates after a plastic impact with the active locks (the RELEASED ones free when ``release``) in table t,
    written to the workspace's right side; its own right side is each row's momentum just before, m J'^T v- + I
    omega-."""
    n = coords(p)
    m = n + int(p[T_NLOCK])
    w = work_offset(p)
    r, v = w + m * m, w + m * m + m
    npts = int(p[T_NPTS])
    for i in range(npts):
        p[v + 2 * i], p[v + 2 * i + 1] = velocity_at(p, 0, w_offset(p, 0, i), qd)
    used = _assemble(p, t, w, m, qd, False, release)
    for a in range(m):
        p[r + a] = 0.0
    for i in range(npts):
        o = row_offset(p, t, i)
        own = int(p[o + 2])
        p[r + own] += p[o + 1] * qd[own]
        for k in range(n):
            jx, jy = jacobian_column(p, t, w_offset(p, t, i), k)
            p[r + k] += p[o] * (jx * p[v + 2 * i] + jy * p[v + 2 * i + 1])
    _pin_light(p, t, w, m, r)
    _solve(p, w, m, used, r)
    _light_tier(p, t, q, qd, IMPACT, w, m, r)


@kernel
def _released_closing(p: np.ndarray, r: int) -> bool:
    """Whether a RELEASED lock's joint leaves the strike turning into its stop (the rates at p[r:])."""
    for j in range(int(p[T_NLOCK])):
        o = lock_offset(p, j)
        if p[o + 4] == RELEASED and p[o + 3] * (p[r + int(p[o + 1])] - p[r + int(p[o])]) > 0.0:
            return True
    return False


@kernel(literal_arguments=False)
def tree_impact(p: np.ndarray, x: np.ndarray, strike: bool, out: np.ndarray) -> None:
    """out = the state after a plastic impact with the active locks: a stop strike (table 0), or the heel strike
    (``strike``: table 1, the new stance foot pinned; then the roles swapped, coordinate k after it being
    coordinate perm[k] before). Every stop of both legs is locked through the heel strike but the RELEASED ones
    (the trailing leg's, McGeer's free trailing knee), unless one of these would leave it closing on its stop:
    then they are held too (a stop pushes, never pulls)."""
    n = coords(p)
    q, qd = x[:n], x[n:]
    fill_trig(p, q)
    r = work_offset(p) + (n + int(p[T_NLOCK])) ** 2
    t = 1 if strike else 0
    released = False
    if strike:  # every stop of both legs locked through the heel strike, the released ones aside
        for j in range(int(p[T_NLOCK])):
            o = lock_offset(p, j)
            released = released or p[o + 4] == RELEASED
            p[o + 4] = RELEASED if p[o + 4] == RELEASED else 1.0
    _impact_rates(p, t, q, qd, released)
    if released and _released_closing(p, r):
        _impact_rates(p, t, q, qd, False)
    perm = perm_offset(p)
    for k in range(n):
        src = int(p[perm + k]) if strike else k
        out[k] = q[src] + (p[perm + n + k] if strike else 0.0)
        out[n + k] = p[r + src]


@kernel
def tree_guard(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """The phase's guard (its downward zero ends it): a stop's margin, the stance foot's lead over the hip, or the
    heel strike's factor of the landing foot's clearance. With both legs locked (each a rigid body whose foot centre
    is A from the hip, leaning phi from its hip body's axis) the clearance is 2 A sin((th_st + th_land + 2 phi) / 2)
    sin((th_land - th_st) / 2): its second factor vanishes at the mid-stance scuff (ignored), the first at the
    strike, th_st + th_land + 2 phi = 0 (th_land in the stance leg's coordinates: the wheel's next spoke is its
    stance spoke's angle plus the spoke spacing, the shift)."""
    n = coords(p)
    o = phase_offset(p, phase)
    kind = int(p[o])
    if kind == STOP:
        lo = lock_offset(p, int(p[o + 1]))
        return p[lo + 3] * (p[lo + 2] - (x[int(p[lo + 1])] - x[int(p[lo])]))
    npts = int(p[T_NPTS])
    if kind == PAST:
        hip_x, _ = point(p, npts, x[:n])
        return -p[P_R] * x[rolling(p, 0)] - hip_x
    land = int(p[perm_offset(p)])  # the landing leg's hip body: coordinate 0 after the strike
    return x[0] + x[land] + p[perm_offset(p) + n] + 2.0 * p[P_LEAN]


@kernel
def tree_guard_rate(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """Time derivative of :func:`tree_guard` (positions move with the rates in x)."""
    n = coords(p)
    o = phase_offset(p, phase)
    kind = int(p[o])
    if kind == STOP:
        lo = lock_offset(p, int(p[o + 1]))
        return -p[lo + 3] * (x[n + int(p[lo + 1])] - x[n + int(p[lo])])
    npts = int(p[T_NPTS])
    if kind == PAST:
        vx, _ = point_velocity(p, 0, npts, x[:n], x[n:])
        return -p[P_R] * x[n + rolling(p, 0)] - vx
    return x[n] + x[n + int(p[perm_offset(p)])]


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
    for i in range(x.shape[0]):  # not a slice assignment: its shape check's message compiles
        x[i] = out[i]


@kernel
def skip_phase(p: np.ndarray, phase: int, x: np.ndarray) -> bool:
    """The hip already past the stance foot (after a late stop strike): that phase has nothing to wait for."""
    return int(p[phase_offset(p, phase)]) == PAST and tree_guard(p, phase, x) <= 0.0


@kernel
def tree_push(p: np.ndarray, x: np.ndarray, px: float, py: float, out: np.ndarray) -> float:
    """out = the state just after an impulse (px, py) on the hip, ``[M A^T; A 0] [dqd; Lambda] = [J_hip^T p; 0]``
    (the stance foot and the locked stops hold); returns the ground's normal impulse (the walker's momentum change
    minus p, normal part: negative when the push would lift the stance foot)."""
    n = coords(p)
    m = n + int(p[T_NLOCK])
    q, qd = x[:n], x[n:]
    fill_trig(p, q)
    w = work_offset(p)
    r = w + m * m
    npts = int(p[T_NPTS])
    used = _assemble(p, 0, w, m, qd, False, False)
    for a in range(m):
        p[r + a] = 0.0
    for k in range(n):
        jx, jy = jacobian_column(p, 0, w_offset(p, 0, npts), k)
        p[r + k] = jx * px + jy * py
    _pin_light(p, 0, w, m, r)
    _solve(p, w, m, used, r)
    _light_tier(p, 0, q, qd, AT_REST, w, m, r)
    normal = -py
    for i in range(npts):
        mass = p[row_offset(p, 0, i)]
        for k in range(n):
            _, jy = jacobian_column(p, 0, w_offset(p, 0, i), k)
            normal += mass * jy * p[r + k]
    for k in range(n):
        out[k] = q[k]
        out[n + k] = qd[k] + p[r + k]
    return normal


@kernel
def tree_light_rates(p: np.ndarray, x: np.ndarray) -> None:
    """Fill in x the light coordinates' rates that the heavy rates imply with the light rows at rest across them
    (just after a heel strike the new swing foot was the stance foot: Garcia's swing rate cos(2 theta) thetadot)."""
    n = coords(p)
    m = n + int(p[T_NLOCK])
    w = work_offset(p)
    r = w + m * m
    for k in range(n):
        p[r + k] = x[n + k]
    fill_trig(p, x[:n])
    _light_tier(p, 0, x[:n], x[n:], AT_REST, w, m, r)
    for k in range(n):
        x[n + k] = p[r + k]
