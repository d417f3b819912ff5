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
from biped_sim.multibody.bodies import add_body_terms, body_energy, lever_terms, mirror_lower
from biped_sim.rigid.tree_elements import element_forces, tree_element_energy
from biped_sim.rigid.tree_layout import (
    RigidTree,
    fill_trig,
    hip,
    jacobian_column,
    lever,
    light,
    light_row,
    point,
    point_at,
    point_velocity,
    velocity_at,
)

STOP, PAST, STRIKE = 0, 1, 2  # phase kinds: a swing stop strikes; the hip passes over the stance foot; heel strike
FLOW, IMPACT, AT_REST = 0, 1, 2  # the light rows' right side: gravity and bias; their velocity just before; none
RELEASED = 2.0  # a lock's active field: held through the stance, released through the heel strike


@kernel(literal_arguments=False)
def _row_jacobian(
    tree: RigidTree, t: int, i: int, qd: np.ndarray, jacobian: np.ndarray, dense: bool
) -> tuple[float, float]:
    """Write the Jacobian of point i of table t to ``jacobian`` and return its bias acceleration Jdot qd, both by
    :func:`~biped_sim.multibody.bodies.lever_terms` of each coordinate's lever (one pass, cached angles), over its
    nonzero columns alone (``tree.columns[t, i]``, summed in ascending order: a zero column adds nothing to the
    sum, the same bits): row a is column ``tree.columns[t, i, a]``, or, ``dense``, row k is column k (n x 2)."""
    w, columns, roll = tree.w[t, i], tree.columns[t, i], tree.rolling[t]
    if dense:
        for k in range(tree.n):
            jacobian[k, 0] = jacobian[k, 1] = 0.0
    bx = by = 0.0
    for a in range(tree.n_columns[t, i] - 1, -1, -1):
        k = columns[a]
        lx, ly = lever(tree, w, k)
        jx, jy, bx, by = lever_terms(lx, ly, qd[k], bx, by)
        row = k if dense else a
        jacobian[row, 0], jacobian[row, 1] = (jx - tree.radius, jy) if k == roll else (jx, jy)
    return bx, by


@kernel(literal_arguments=False)
def _assemble(tree: RigidTree, t: int, m: int, qd: np.ndarray, flow: bool, release: bool) -> int:
    """Write M of table t and the active lock rows into the workspace's (m x m) matrix and, for the ``flow``, the
    generalized forces sum_i m_i J_i^T (g - Jdot_i qd) into its right side, work[:m] (each row's terms by
    :func:`~biped_sim.multibody.bodies.add_body_terms` over its nonzero columns, as the compliant tree's); returns
    the rows used (the workspace's ``jacobian`` holds a row's columns meanwhile; the angles cached by
    :func:`fill_trig`). ``release``: the locks marked RELEASED are left free (a heel strike's trailing knee)."""
    n, work, matrix, levers = tree.n, tree.work, tree.matrix, tree.jacobian
    forces = work[:m]
    for a in range(m):
        for b in range(m):
            matrix[a, b] = 0.0
    for a in range(m):
        work[a] = 0.0
    for i in range(tree.n_points):
        row = tree.rows[t, i]
        mass = row.mass
        fx = fy = 0.0
        if mass != 0.0:
            bx, by = _row_jacobian(tree, t, i, qd, levers, False)
            fx, fy = mass * (tree.gx - bx), mass * (tree.gy - by)
        count = tree.n_columns[t, i]
        add_body_terms(matrix, forces, levers, tree.columns[t, i], count, mass, row.inertia, row.own, fx, fy, flow)
    mirror_lower(matrix, n)
    used = n
    for j in range(tree.locks.shape[0]):
        lock = tree.locks[j]
        active = lock.active
        if active != 0.0 and not (release and active == RELEASED):
            parent, child = lock.parent, lock.child
            matrix[used, parent] = matrix[parent, used] = -1.0
            matrix[used, child] = matrix[child, used] = 1.0
            used += 1
    return used


@kernel(reference_counts=False, literal_arguments=False)
def _solve(a: np.ndarray, v: np.ndarray, used: int, r: int) -> None:
    """Solve the leading (used x used) block of the matrix a for the vector at v[r:], in place: Cramer's rule up to
    2 x 2 (the compass, the wheel), else Gaussian elimination with partial pivoting (the constrained system is
    indefinite)."""
    if used <= 2:
        a00, f = a[0, 0], v[r]
        if used == 1:
            v[r] = f / a00
            return
        b, c, d, g = a[0, 1], a[1, 0], a[1, 1], v[r + 1]
        det = a00 * d - b * c
        v[r], v[r + 1] = (d * f - b * g) / det, (a00 * g - c * f) / det
        return
    for col in range(used):
        pivot = col
        for row in range(col + 1, used):
            if abs(a[row, col]) > abs(a[pivot, col]):
                pivot = row
        if pivot != col:
            for k in range(used):
                a[col, k], a[pivot, k] = a[pivot, k], a[col, k]
            v[r + col], v[r + pivot] = v[r + pivot], v[r + col]
        for row in range(col + 1, used):
            factor = a[row, col] / a[col, col]
            for k in range(col, used):
                a[row, k] -= factor * a[col, k]
            v[r + row] -= factor * v[r + col]
    for col in range(used - 1, -1, -1):
        total = v[r + col]
        for k in range(col + 1, used):
            total -= a[col, k] * v[r + k]
        v[r + col] = total / a[col, col]


@kernel(literal_arguments=False)
def _pin_light(tree: RigidTree, t: int) -> None:
    """Give the light coordinates of table t (zero rows and columns of M) a unit diagonal and a zero right side,
    so that the heavy solve leaves them at 0 for :func:`_light_tier`."""
    for k in range(tree.n):
        if light(tree, t, k):
            tree.matrix[k, k] = 1.0
            tree.work[k] = 0.0


@kernel(literal_arguments=False)
def _light_tier(tree: RigidTree, t: int, q: np.ndarray, qd: np.ndarray, mode: int, m: int) -> None:
    """The light coordinates' equations, the limit of infinitesimal foot masses (Garcia et al. 1998): each light
    row's balance across the light coordinates, sum_i J_iL^T (J_i a - b_i) = 0, with the heavy part of a already
    solved in work[:m] and written back there (b_i: g - Jdot_i qd in the flow, the row's velocity just before an
    impact, 0 for a push or at rest). The heavy equations do not see these rows: their masses vanish. Light row j
    is foot j (the stance foot, then the landing one): the foot pinned in table t (row t) has no Jacobian."""
    n, work, matrix, jacobian = tree.n, tree.work, tree.matrix, tree.jacobian
    size = 0
    for k in range(n):
        size += 1 if light(tree, t, k) else 0
    if size == 0:
        return
    rhs = m + 2 * (tree.n_points + tree.n_light)  # the light system's right side
    for a in range(size):
        work[rhs + a] = 0.0
        for b in range(size):
            matrix[a, b] = 0.0
    for j in range(tree.n_light):
        if j == t:
            continue
        bx, by = _row_jacobian(tree, t, light_row(tree, j), qd, jacobian, True)
        cx, cy = (tree.gx - bx, tree.gy - by) if mode == FLOW else (0.0, 0.0)
        if mode == IMPACT:
            cx, cy = velocity_at(tree, 0, tree.w[0, light_row(tree, j)], qd)
        for k in range(n):
            if not light(tree, t, k):
                cx, cy = cx - jacobian[k, 0] * work[k], cy - jacobian[k, 1] * work[k]
        a = 0
        for k in range(n):
            if light(tree, t, k):
                work[rhs + a] += jacobian[k, 0] * cx + jacobian[k, 1] * cy
                b = 0
                for col in range(n):
                    if light(tree, t, col):
                        matrix[a, b] += jacobian[k, 0] * jacobian[col, 0] + jacobian[k, 1] * jacobian[col, 1]
                        b += 1
                a += 1
    _solve(matrix, work, size, rhs)
    a = 0
    for k in range(n):
        if light(tree, t, k):
            work[k] = work[rhs + a]
            a += 1


@kernel
def tree_rhs(tree: RigidTree, x: np.ndarray, out: np.ndarray) -> None:
    """out = dx/dt: Kane's equations with the locked stops as constraints, the joint elements' torques among the
    generalized forces."""
    n, work = tree.n, tree.work
    m = n + tree.locks.shape[0]
    q, qd = x[:n], x[n:]
    fill_trig(tree, q)
    used = _assemble(tree, 0, m, qd, True, False)
    element_forces(tree.elements, tree.element_params, q, qd, work)
    _pin_light(tree, 0)
    _solve(tree.matrix, work, used, 0)
    _light_tier(tree, 0, q, qd, FLOW, m)
    for k in range(n):
        out[k] = qd[k]
        out[n + k] = work[k]


@kernel
def tree_energy(tree: RigidTree, x: np.ndarray) -> tuple[float, float]:
    """(kinetic, potential) energy of the rows of table 0 (gravity's potential zero with every point on the ground
    line) and the joint elements' stored energy among the potential."""
    n = tree.n
    q, qd = x[:n], x[n:]
    fill_trig(tree, q)
    kinetic = potential = 0.0
    for i in range(tree.n_points):
        row, w = tree.rows[0, i], tree.w[0, i]
        vx, vy = velocity_at(tree, 0, w, qd)
        px, py = point_at(tree, w, q)
        body_kinetic, body_potential = body_energy(row.mass, row.inertia, vx, vy, qd[row.own], px, py, tree.gx, tree.gy)
        kinetic += body_kinetic
        potential += body_potential
    return kinetic, potential + tree_element_energy(tree, q)


@kernel(literal_arguments=False)
def _impact_rates(tree: RigidTree, t: int, q: np.ndarray, qd: np.ndarray, release: bool) -> None:
    """The rates after a plastic impact with the active locks (the RELEASED ones free when ``release``) in table t,
    written to the workspace's right side; its own right side is each row's momentum just before, m J'^T v- + I
    omega-."""
    n, work = tree.n, tree.work
    m = n + tree.locks.shape[0]
    v = m  # the rows' velocities just before, after the right side
    npts = tree.n_points
    for i in range(npts):
        work[v + 2 * i], work[v + 2 * i + 1] = velocity_at(tree, 0, tree.w[0, i], qd)
    used = _assemble(tree, t, m, qd, False, release)
    for a in range(m):
        work[a] = 0.0
    for i in range(npts):
        row = tree.rows[t, i]
        own = row.own
        work[own] += row.inertia * qd[own]
        for k in range(n):
            jx, jy = jacobian_column(tree, t, tree.w[t, i], k)
            work[k] += row.mass * (jx * work[v + 2 * i] + jy * work[v + 2 * i + 1])
    _pin_light(tree, t)
    _solve(tree.matrix, work, used, 0)
    _light_tier(tree, t, q, qd, IMPACT, m)


@kernel
def _released_closing(tree: RigidTree) -> bool:
    """Whether a RELEASED lock's joint leaves the strike turning into its stop (the rates at work[:n])."""
    work = tree.work
    for j in range(tree.locks.shape[0]):
        lock = tree.locks[j]
        if lock.active == RELEASED and lock.sign * (work[lock.child] - work[lock.parent]) > 0.0:
            return True
    return False


@kernel(literal_arguments=False)
def tree_impact(tree: RigidTree, x: np.ndarray, strike: bool, out: np.ndarray) -> None:
    """out = the state after a plastic impact with the active locks: a stop strike (table 0), or the heel strike
    (``strike``: table 1, the new stance foot pinned; then the roles swapped, coordinate k after it being
    coordinate perm[k] before). Every stop of both legs is locked through the heel strike but the RELEASED ones
    (the trailing leg's, McGeer's free trailing knee), unless one of these would leave it closing on its stop:
    then they are held too (a stop pushes, never pulls)."""
    n = tree.n
    q, qd = x[:n], x[n:]
    fill_trig(tree, q)
    t = 1 if strike else 0
    released = False
    if strike:  # every stop of both legs locked through the heel strike, the released ones aside
        for j in range(tree.locks.shape[0]):
            lock = tree.locks[j]
            released = released or lock.active == RELEASED
            lock.active = RELEASED if lock.active == RELEASED else 1.0
    _impact_rates(tree, t, q, qd, released)
    if released and _released_closing(tree):
        _impact_rates(tree, t, q, qd, False)
    for k in range(n):
        src = tree.coords[k].perm if strike else k
        out[k] = q[src] + (tree.coords[k].shift if strike else 0.0)
        out[n + k] = tree.work[src]


@kernel
def tree_guard(tree: RigidTree, phase: int, x: np.ndarray) -> float:
    """The phase's guard (its downward zero ends it): a stop's margin, the stance foot's lead over the hip, or the
    heel strike's factor of the landing foot's clearance. With both legs locked (each a rigid body whose foot centre
    is A from the hip, leaning phi from its hip body's axis) the clearance is 2 A sin((th_st + th_land + 2 phi) / 2)
    sin((th_land - th_st) / 2): its second factor vanishes at the mid-stance scuff (ignored), the first at the
    strike, th_st + th_land + 2 phi = 0 (th_land in the stance leg's coordinates: the wheel's next spoke is its
    stance spoke's angle plus the spoke spacing, the shift)."""
    n = tree.n
    kind = tree.phases[phase].kind
    if kind == STOP:
        lock = tree.locks[tree.phases[phase].lock]
        return lock.sign * (lock.limit - (x[lock.child] - x[lock.parent]))
    if kind == PAST:
        hip_x, _ = point(tree, hip(tree), x[:n])
        return -tree.radius * x[tree.rolling[0]] - hip_x
    land = tree.coords[0].perm  # the landing leg's hip body: coordinate 0 after the strike
    return x[0] + x[land] + tree.coords[0].shift + 2.0 * tree.lean


@kernel
def tree_guard_rate(tree: RigidTree, phase: int, x: np.ndarray) -> float:
    """Time derivative of :func:`tree_guard` (positions move with the rates in x)."""
    n = tree.n
    kind = tree.phases[phase].kind
    if kind == STOP:
        lock = tree.locks[tree.phases[phase].lock]
        return -lock.sign * (x[n + lock.child] - x[n + lock.parent])
    if kind == PAST:
        vx, _ = point_velocity(tree, 0, hip(tree), x[:n], x[n:])
        return -tree.radius * x[n + tree.rolling[0]] - vx
    return x[n] + x[n + tree.coords[0].perm]


@kernel
def begin_step(tree: RigidTree) -> None:
    """At a step's start the stance leg's stops are locked and the swing leg's free (the new swing knee unlocks)."""
    for k in range(tree.phases.shape[0]):
        if tree.phases[k].kind == STOP:
            tree.locks[tree.phases[k].lock].active = 0.0


@kernel
def after_phase(tree: RigidTree, phase: int, x: np.ndarray, out: np.ndarray) -> None:
    """After a swing stop's strike: lock it at its limit (the strike located to round-off, or a fixed step's
    overshoot projected out) and apply the plastic impact to x (in place, through out)."""
    if tree.phases[phase].kind != STOP:
        return
    lock = tree.locks[tree.phases[phase].lock]
    lock.active = 1.0
    x[lock.child] = x[lock.parent] + lock.limit
    tree_impact(tree, x, False, out)
    for i in range(x.shape[0]):  # not a slice assignment: its shape check's message compiles
        x[i] = out[i]


@kernel
def skip_phase(tree: RigidTree, phase: int, x: np.ndarray) -> bool:
    """The hip already past the stance foot (after a late stop strike): that phase has nothing to wait for."""
    return tree.phases[phase].kind == PAST and tree_guard(tree, phase, x) <= 0.0


@kernel
def tree_push(tree: RigidTree, x: np.ndarray, px: float, py: float, out: np.ndarray) -> float:
    """out = the state just after an impulse (px, py) on the hip, ``[M A^T; A 0] [dqd; Lambda] = [J_hip^T p; 0]``
    (the stance foot and the locked stops hold); returns the ground's normal impulse (the walker's momentum change
    minus p, normal part: negative when the push would lift the stance foot)."""
    n, work = tree.n, tree.work
    m = n + tree.locks.shape[0]
    q, qd = x[:n], x[n:]
    fill_trig(tree, q)
    used = _assemble(tree, 0, m, qd, False, False)
    for a in range(m):
        work[a] = 0.0
    for k in range(n):
        jx, jy = jacobian_column(tree, 0, tree.w[0, hip(tree)], k)
        work[k] = jx * px + jy * py
    _pin_light(tree, 0)
    _solve(tree.matrix, work, used, 0)
    _light_tier(tree, 0, q, qd, AT_REST, m)
    normal = -py
    for i in range(tree.n_points):
        mass = tree.rows[0, i].mass
        for k in range(n):
            _, jy = jacobian_column(tree, 0, tree.w[0, i], k)
            normal += mass * jy * work[k]
    for k in range(n):
        out[k] = q[k]
        out[n + k] = qd[k] + work[k]
    return normal


@kernel
def tree_light_rates(tree: RigidTree, x: np.ndarray) -> None:
    """Fill in x the light coordinates' rates that the heavy rates imply with the light rows at rest across them
    (just after a heel strike the new swing foot was the stance foot: Garcia's swing rate cos(2 theta) thetadot)."""
    n, work = tree.n, tree.work
    m = n + tree.locks.shape[0]
    for k in range(n):
        work[k] = x[n + k]
    fill_trig(tree, x[:n])
    _light_tier(tree, 0, x[:n], x[n:], AT_REST, m)
    for k in range(n):
        x[n + k] = work[k]
