"""Euler-parameter algebra of the spatial formulation (Nikravesh, Computer-Aided Analysis of Mechanical Systems, ch. 6).

A body's orientation is p = (e0, e) with p.p = 1; its notation, used here and in
:mod:`biped_sim.multibody.spatial`:

* A(p) = E G^T = (e0^2 - e.e) I + 2 e e^T + 2 e0 e~ (exactly orthonormal when |p| = 1; the
  homogeneous quadratic form |p|^2 R is used everywhere, so that every Jacobian is exact);
* E = [-e, e~ + e0 I], G = [-e, -e~ + e0 I]: omega = 2 E pdot (global), omega' = 2 G pdot (body);
* the point r + A(p) s' of a body has velocity rdot + B(p, s') pdot with the exact 3 x 4 Jacobian
  B(p, s') = d(A s')/dp = 2 [e0 s' + e~ s', (e.s') I + e s'^T - s' e^T - e0 s'~], linear in p, so
  its acceleration is B(p, s') pdd + B(pdot, s') pdot.

Products are written out on tuples (no matrices are formed); everything is compiled and
allocation-free. The state accessors read body b's blocks of y = [q (7 nb) | qd (7 nb) | ...]:
``position(y, b)`` and ``parameters(y, b)`` its r and p, the same at ``nb + b`` its rdot and pdot.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.kernel import kernel


@kernel
def rotate(p: tuple, s: tuple) -> tuple[float, float, float]:
    """A(p) s."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    c = e0 * e0 - e1 * e1 - e2 * e2 - e3 * e3
    es = 2.0 * (e1 * s0 + e2 * s1 + e3 * s2)
    x0 = e2 * s2 - e3 * s1
    x1 = e3 * s0 - e1 * s2
    x2 = e1 * s1 - e2 * s0
    return c * s0 + es * e1 + 2.0 * e0 * x0, c * s1 + es * e2 + 2.0 * e0 * x1, c * s2 + es * e3 + 2.0 * e0 * x2


@kernel
def rotate_t(p: tuple, f: tuple) -> tuple[float, float, float]:
    """A(p)^T f (A of the conjugate parameters)."""
    return rotate((p[0], -p[1], -p[2], -p[3]), f)


@kernel
def _b_terms(p: tuple, s: tuple) -> tuple[float, float, float, float]:
    """(e.s, e0 s + e x s): the parts of B(p, s) that do not depend on what it multiplies."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    return (
        e1 * s0 + e2 * s1 + e3 * s2,
        e0 * s0 + e2 * s2 - e3 * s1,
        e0 * s1 + e3 * s0 - e1 * s2,
        e0 * s2 + e1 * s1 - e2 * s0,
    )


@kernel
def b_mul(p: tuple, s: tuple, x: tuple) -> tuple[float, float, float]:
    """B(p, s) x = 2 [(e0 s + e x s) x0 + (e.s) xv + e (s.xv) - s (e.xv) - e0 (s x xv)]."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    x0, v0, v1, v2 = x
    es, c0, c1, c2 = _b_terms(p, s)
    sv = s0 * v0 + s1 * v1 + s2 * v2
    ev = e1 * v0 + e2 * v1 + e3 * v2
    w0 = s1 * v2 - s2 * v1
    w1 = s2 * v0 - s0 * v2
    w2 = s0 * v1 - s1 * v0
    return (
        2.0 * (c0 * x0 + es * v0 + e1 * sv - s0 * ev - e0 * w0),
        2.0 * (c1 * x0 + es * v1 + e2 * sv - s1 * ev - e0 * w1),
        2.0 * (c2 * x0 + es * v2 + e3 * sv - s2 * ev - e0 * w2),
    )


@kernel
def b_tmul(p: tuple, s: tuple, f: tuple) -> tuple[float, float, float, float]:
    """B(p, s)^T f = 2 [(e0 s + e x s).f, (e.s) f + s (e.f) - e (s.f) + e0 (s x f)]."""
    e0, e1, e2, e3 = p
    s0, s1, s2 = s
    f0, f1, f2 = f
    es, c0, c1, c2 = _b_terms(p, s)
    ef = e1 * f0 + e2 * f1 + e3 * f2
    sf = s0 * f0 + s1 * f1 + s2 * f2
    return (
        2.0 * (c0 * f0 + c1 * f1 + c2 * f2),
        2.0 * (es * f0 + s0 * ef - e1 * sf + e0 * (s1 * f2 - s2 * f1)),
        2.0 * (es * f1 + s1 * ef - e2 * sf + e0 * (s2 * f0 - s0 * f2)),
        2.0 * (es * f2 + s2 * ef - e3 * sf + e0 * (s0 * f1 - s1 * f0)),
    )


@kernel
def g_mul(p: tuple, x: tuple) -> tuple[float, float, float]:
    """G(p) x = -e x0 + e0 xv - e x xv (omega' = 2 G pdot)."""
    e0, e1, e2, e3 = p
    x0, v0, v1, v2 = x
    return (
        -e1 * x0 + e0 * v0 - (e2 * v2 - e3 * v1),
        -e2 * x0 + e0 * v1 - (e3 * v0 - e1 * v2),
        -e3 * x0 + e0 * v2 - (e1 * v1 - e2 * v0),
    )


@kernel
def g_tmul(p: tuple, w: tuple) -> tuple[float, float, float, float]:
    """G(p)^T w = (-e.w, e0 w + e x w)."""
    e0, e1, e2, e3 = p
    w0, w1, w2 = w
    return (
        -(e1 * w0 + e2 * w1 + e3 * w2),
        e0 * w0 + e2 * w2 - e3 * w1,
        e0 * w1 + e3 * w0 - e1 * w2,
        e0 * w2 + e1 * w1 - e2 * w0,
    )


@kernel
def e_mul(p: tuple, x: tuple) -> tuple[float, float, float]:
    """E(p) x = -e x0 + e0 xv + e x xv (omega = 2 E pdot)."""
    e0, e1, e2, e3 = p
    x0, v0, v1, v2 = x
    return (
        -e1 * x0 + e0 * v0 + (e2 * v2 - e3 * v1),
        -e2 * x0 + e0 * v1 + (e3 * v0 - e1 * v2),
        -e3 * x0 + e0 * v2 + (e1 * v1 - e2 * v0),
    )


@kernel
def e_tmul(p: tuple, n: tuple) -> tuple[float, float, float, float]:
    """E(p)^T n = (-e.n, e0 n - e x n), G^T n of the conjugate parameters with its first entry negated: the
    generalized force 2 E^T n of a torque n (slope frame) on p."""
    g = g_tmul((p[0], -p[1], -p[2], -p[3]), n)
    return -g[0], g[1], g[2], g[3]


@kernel
def position(y: np.ndarray, b: int) -> tuple[float, float, float]:
    """r of body b (rdot at index nb + b): its first three state entries."""
    return y[7 * b], y[7 * b + 1], y[7 * b + 2]


@kernel
def parameters(y: np.ndarray, b: int) -> tuple[float, float, float, float]:
    """p of body b (pdot at index nb + b): its Euler parameters (e0, e1, e2, e3)."""
    return y[7 * b + 3], y[7 * b + 4], y[7 * b + 5], y[7 * b + 6]


@kernel(literal_arguments=False)
def vec3(a: np.ndarray, row: int, k: int) -> tuple[float, float, float]:
    """a[row, k:k + 3] as a tuple."""
    return a[row, k], a[row, k + 1], a[row, k + 2]


@kernel
def dot3(a: tuple, b: tuple) -> float:
    """a.b of two 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel
def inertia_mul(j: np.ndarray, b: int, w: tuple) -> tuple[float, float, float]:
    """J[b] w for a stack of 3 x 3 matrices J (inertias or their inverses)."""
    return (
        j[b, 0, 0] * w[0] + j[b, 0, 1] * w[1] + j[b, 0, 2] * w[2],
        j[b, 1, 0] * w[0] + j[b, 1, 1] * w[1] + j[b, 1, 2] * w[2],
        j[b, 2, 0] * w[0] + j[b, 2, 1] * w[1] + j[b, 2, 2] * w[2],
    )


@kernel
def point_state(
    y: np.ndarray, nb: int, b: int, s: tuple
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(position, velocity) of the body-frame point s of body b: r + A s, rdot + B(p, s) pdot."""
    r = position(y, b)
    p = parameters(y, b)
    a = rotate(p, s)
    v = position(y, nb + b)
    w = b_mul(p, s, parameters(y, nb + b))
    return (r[0] + a[0], r[1] + a[1], r[2] + a[2]), (v[0] + w[0], v[1] + w[1], v[2] + w[2])


@kernel
def g_col(p: tuple, j: int) -> tuple[float, float, float]:
    """Column j of G(p) = [-e, e0 I - e~]."""
    e0, e1, e2, e3 = p
    if j == 0:
        return -e1, -e2, -e3
    if j == 1:
        return e0, -e3, e2
    if j == 2:
        return e3, e0, -e1
    return -e2, e1, e0


@kernel
def unit4(j: int) -> tuple[float, float, float, float]:
    """The unit 4-vector along axis j (a column of the identity: Jacobian columns by products)."""
    return (1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0, 1.0 if j == 3 else 0.0)


@kernel
def attitude(y: np.ndarray, nb: int, b: int) -> tuple[float, float, float, float]:
    """(pitch, roll, yaw, omega_z) of body b.

    pitch is the sagittal angle of the body's -y' axis (its legs) from the slope normal, positive
    with the feet downhill (the planar leg angle); roll the elevation of its lateral z' axis above
    the slope plane (lateral rocking); yaw the heading of z' about the normal (drift); omega_z the
    global angular rate about the lateral axis (the planar leg angle rate).
    """
    p = parameters(y, b)
    norm = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    ay = rotate(p, (0.0, 1.0, 0.0))
    az = rotate(p, (0.0, 0.0, 1.0))
    sin_roll = min(1.0, max(-1.0, az[1] / norm))
    omega = e_mul(p, parameters(y, nb + b))
    return math.atan2(-ay[0], ay[1]), math.asin(sin_roll), math.atan2(-az[0], az[2]), 2.0 * omega[2]
