"""Compiled equations of the rigid walkers: flow, guards, fall checks and impact maps (numba).

The same equations as :mod:`biped_sim.rigid.models` (which stays the readable reference the tests compare
with), written allocation-free for the compiled step map of :mod:`biped_sim.rigid.compiled`. A walker is a
``kind`` and a parameter vector ``p`` (layout: the ``P_*`` indices below, built by
:func:`biped_sim.rigid.compiled.walker_params`):

* ``SIMPLEST``: Garcia's walker, MODEL.md 8 (only the slope and the fall angle are read);
* ``COMPASS``: two legs and a hip mass as a chain of bodies (Kane's equations, rolling arc foot), with the
  leg centre-of-mass offset ``w`` (perpendicular to the leg) and the foot-arc offset ``d``: slope frame x
  downhill, y normal; axis(theta) = (sin, -cos) (hip -> foot), perp(theta) = (cos, sin); body = hip + c
  axis + w perp; hip = C - (l - R) axis(theta_st) - d perp(theta_st), C = (x_C0 - R theta_st, R);
* ``WHEEL``: the rimless wheel, one hub mass on a spoke of the chain (n_q = 1);
* ``TREE``: a described walker (:mod:`biped_sim.rigid.tree_kernels`: any tree, its stops as phases).

Each body of a chain is (mass, inertia, leg, distance along the leg, offset perpendicular to it).
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.kernel import kernel
from biped_sim.rigid.tree_kernels import (
    FALL_HIP_FRACTION,
    T_NPHASE,
    after_phase,
    begin_step,
    skip_phase,
    tree_fall,
    tree_guard,
    tree_guard_rate,
    tree_impact,
    tree_rhs,
)

SIMPLEST, COMPASS, WHEEL, TREE = 0, 1, 2, 3
P_NQ, P_L, P_R, P_D, P_G, P_SLOPE, P_FALL, P_HALF, P_NB, P_BODIES = range(10)
BODY_FIELDS = 5  # mass, inertia, leg, distance, offset


@kernel
def _hip_derivatives(p: np.ndarray, theta: float) -> tuple[float, float, float, float]:
    """d(hip)/d(theta_st) and d2(hip)/d(theta_st)^2 (x, y each) for the rolling stance foot."""
    lr, r, d = p[P_L] - p[P_R], p[P_R], p[P_D]
    s, c = math.sin(theta), math.cos(theta)
    return -r - lr * c + d * s, -lr * s - d * c, lr * s + d * c, -lr * c + d * s


@kernel
def _body_terms(p: np.ndarray, b: int, q: np.ndarray, qd: np.ndarray, leg: int) -> tuple:
    """Body b's Jacobian columns (j0x, j0y, j1x, j1y) and bias acceleration Jdot qd (bx, by), carried by ``leg``."""
    base = P_BODIES + BODY_FIELDS * b
    dist, off = p[base + 3], p[base + 4]
    hx, hy, hxx, hyy = _hip_derivatives(p, q[0])
    s, c = math.sin(q[leg]), math.cos(q[leg])
    cx, cy = dist * c - off * s, dist * s + off * c  # d(position)/d(theta_leg) of the leg's part
    rate2 = qd[leg] * qd[leg]
    bx = hxx * qd[0] * qd[0] - (dist * s + off * c) * rate2
    by = hyy * qd[0] * qd[0] + (dist * c - off * s) * rate2
    if leg == 0:
        return hx + cx, hy + cy, 0.0, 0.0, bx, by
    return hx, hy, cx, cy, bx, by


@kernel
def _solve(m00: float, m01: float, m11: float, f0: float, f1: float, n: int) -> tuple[float, float]:
    """Solution of the symmetric 1x1 or 2x2 system M a = f."""
    if n == 1:
        return f0 / m00, 0.0
    det = m00 * m11 - m01 * m01
    return (m11 * f0 - m01 * f1) / det, (m00 * f1 - m01 * f0) / det


@kernel
def _chain_rhs(p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """Kane's equations M(q) qdd = sum_b J_b^T m_b (g - Jdot_b qd), M = sum_b m_b J_b^T J_b + I_b e_b e_b^T."""
    n = int(p[P_NQ])
    q, qd = x[:n], x[n:]
    gx, gy = p[P_G] * math.sin(p[P_SLOPE]), -p[P_G] * math.cos(p[P_SLOPE])
    m00 = m01 = m11 = f0 = f1 = 0.0
    for b in range(int(p[P_NB])):
        base = P_BODIES + BODY_FIELDS * b
        mass, inertia, leg = p[base], p[base + 1], int(p[base + 2])
        j0x, j0y, j1x, j1y, bx, by = _body_terms(p, b, q, qd, leg)
        m00 += mass * (j0x * j0x + j0y * j0y)
        m01 += mass * (j0x * j1x + j0y * j1y)
        m11 += mass * (j1x * j1x + j1y * j1y)
        if leg == 0:
            m00 += inertia
        else:
            m11 += inertia
        f0 += mass * (j0x * (gx - bx) + j0y * (gy - by))
        f1 += mass * (j1x * (gx - bx) + j1y * (gy - by))
    a0, a1 = _solve(m00, m01, m11, f0, f1, n)
    out[:n] = qd
    out[n] = a0
    if n == 2:
        out[3] = a1


@kernel
def _simplest_rhs(p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """Garcia's equations (MODEL.md 8); x = (theta, theta_sw, thetadot, thetadot_sw), phi = theta - theta_sw."""
    theta, theta_sw, theta_d, theta_sw_d = x[0], x[1], x[2], x[3]
    phi = theta - theta_sw
    theta_dd = math.sin(theta - p[P_SLOPE])
    phi_dd = theta_dd + math.sin(phi) * (theta_d * theta_d - math.cos(theta - p[P_SLOPE]))
    out[0] = theta_d
    out[1] = theta_sw_d
    out[2] = theta_dd
    out[3] = theta_dd - phi_dd


@kernel
def rigid_rhs(kind: int, p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = dx/dt of the walker ``kind``."""
    if kind == SIMPLEST:
        _simplest_rhs(p, x, out)
    elif kind == TREE:
        tree_rhs(p, x, out)
    else:
        _chain_rhs(p, x, out)


@kernel
def strike_angle_offset(kind: int, p: np.ndarray) -> float:
    """phi = atan2(d, l - R): the offset foot's arc centre leans phi from the leg axis (0 without an offset)."""
    if kind != COMPASS or p[P_D] == 0.0:
        return 0.0
    return math.atan2(p[P_D], p[P_L] - p[P_R])


@kernel
def guard(kind: int, p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """Phase 0: the hip passing over the stance arc centre (x[0] + phi); phase 1: the heel strike (downward zero).

    With a foot offset d the swing foot's clearance (l - R)(cos th_st - cos th_sw) + d (sin th_sw - sin th_st)
    factors as 2 A sin((th_st + th_sw + 2 phi) / 2) sin((th_sw - th_st) / 2) (A = hypot(l - R, d)), so the
    strike is th_st + th_sw + 2 phi = 0, as in :class:`~biped_sim.rigid.models.CompassChain` (phi = 0 without d).
    """
    if kind == TREE:
        return tree_guard(p, phase, x)
    phi = strike_angle_offset(kind, p)
    if phase == 0:
        return x[0] if phi == 0.0 else x[0] + phi
    if kind == WHEEL:
        return x[0] + p[P_HALF]
    return x[0] + x[1] if phi == 0.0 else x[0] + x[1] + 2.0 * phi


@kernel
def guard_rate(kind: int, p: np.ndarray, phase: int, x: np.ndarray, f: np.ndarray) -> float:
    """Time derivative of :func:`guard` along the flow f = dx/dt."""
    if kind == TREE:
        return tree_guard_rate(p, phase, x)
    if phase == 0 or kind == WHEEL:
        return f[0]
    return f[0] + f[1]


@kernel
def first_phase(kind: int) -> int:
    """The wheel's step has only the strike phase; the bipeds first wait for the stance leg to pass the normal."""
    return 1 if kind == WHEEL else 0


@kernel
def n_phases(kind: int, p: np.ndarray) -> int:
    """The phases of a step (the last ends at the heel strike): a described walker's come from its stops."""
    return int(p[T_NPHASE]) if kind == TREE else 2


@kernel
def start_step(kind: int, p: np.ndarray) -> None:
    """A step begins: a described walker's swing stops unlock."""
    if kind == TREE:
        begin_step(p)


@kernel
def phase_skipped(kind: int, p: np.ndarray, phase: int, x: np.ndarray) -> bool:
    """Whether the phase has already ended when it starts (a described walker's hip past the stance foot)."""
    return kind == TREE and skip_phase(p, phase, x)


@kernel
def end_phase(kind: int, p: np.ndarray, phase: int, x: np.ndarray, out: np.ndarray) -> None:
    """After a phase's guard (before the last): a described walker's stop strike (x in place; out: scratch)."""
    if kind == TREE:
        after_phase(p, phase, x, out)


@kernel
def n_fall_checks(kind: int, p: np.ndarray) -> int:
    """Fall functions: one per leg angle, then the hip height."""
    return 3 if kind == TREE else (2 if kind == SIMPLEST else int(p[P_NQ])) + 1


@kernel
def fall_check(kind: int, p: np.ndarray, i: int, x: np.ndarray) -> float:
    """Fall function i (positive while standing): fall angle - |leg angle i|, or hip height - 0.05 l."""
    if kind == TREE:
        return tree_fall(p, i, x)
    n = n_fall_checks(kind, p) - 1
    if i < n:
        return p[P_FALL] - abs(x[i])
    lr = p[P_L] - p[P_R]
    height = p[P_R] + lr * math.cos(x[0]) - p[P_D] * math.sin(x[0])
    return height - FALL_HIP_FRACTION * p[P_L]


@kernel
def _simplest_impact(x: np.ndarray, out: np.ndarray) -> None:
    """MODEL.md 8: theta+ = -theta-, thetadot+ = cos 2theta thetadot-, phi+ = -2 theta-,
    phidot+ = cos 2theta (1 - cos 2theta) thetadot-; theta_sw = theta - phi."""
    theta, theta_d = x[0], x[2]
    c2 = math.cos(2.0 * theta)
    theta_d_p = c2 * theta_d
    out[0] = -theta
    out[1] = theta
    out[2] = theta_d_p
    out[3] = theta_d_p - c2 * (1.0 - c2) * theta_d


@kernel
def _chain_impact(kind: int, p: np.ndarray, x: np.ndarray, q_work: np.ndarray, out: np.ndarray) -> None:
    """Plastic strike: (J'^T M J') qd+ = J'^T M v-, v- = J qd- the bodies' velocities before; legs relabelled."""
    n = int(p[P_NQ])
    q, qd = x[:n], x[n:]
    q_new, zero = q_work[:2], q_work[2:4]  # the new angles; zero rates (the Jacobians need no bias)
    zero[:] = 0.0
    if kind == WHEEL:
        q_new[0] = q[0] + 2.0 * p[P_HALF]
    else:
        q_new[0], q_new[1] = q[1], q[0]
    m00 = m01 = m11 = r0 = r1 = 0.0
    for b in range(int(p[P_NB])):
        base = P_BODIES + BODY_FIELDS * b
        mass, inertia, leg = p[base], p[base + 1], int(p[base + 2])
        j0x, j0y, j1x, j1y, _, _ = _body_terms(p, b, q, qd, leg)
        vx = j0x * qd[0] + (j1x * qd[1] if n == 2 else 0.0)
        vy = j0y * qd[0] + (j1y * qd[1] if n == 2 else 0.0)
        omega = qd[leg]
        new_leg = leg if kind == WHEEL else 1 - leg
        k0x, k0y, k1x, k1y, _, _ = _body_terms(p, b, q_new, zero, new_leg)
        m00 += mass * (k0x * k0x + k0y * k0y)
        m01 += mass * (k0x * k1x + k0y * k1y)
        m11 += mass * (k1x * k1x + k1y * k1y)
        r0 += mass * (k0x * vx + k0y * vy)
        r1 += mass * (k1x * vx + k1y * vy)
        if new_leg == 0:
            m00 += inertia
            r0 += inertia * omega
        else:
            m11 += inertia
            r1 += inertia * omega
    a0, a1 = _solve(m00, m01, m11, r0, r1, n)
    out[:n] = q_new[:n]
    out[n] = a0
    if n == 2:
        out[3] = a1


@kernel
def rigid_impact(kind: int, p: np.ndarray, x: np.ndarray, q_work: np.ndarray, out: np.ndarray) -> None:
    """out = the post-impact state (new stance leg first) from the pre-impact state x (q_work: 4 scratch floats)."""
    if kind == SIMPLEST:
        _simplest_impact(x, out)
    elif kind == TREE:
        tree_impact(p, x, True, out)
    else:
        _chain_impact(kind, p, x, q_work, out)
