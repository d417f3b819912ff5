"""Dense linear algebra the formulations share, compiled and allocation-free."""

from __future__ import annotations

import math

import numpy as np

from biped_sim.kernel import kernel


@kernel
def cholesky_solve(a: np.ndarray, b: np.ndarray, m: int) -> None:
    """Solve a x = b in place for a symmetric positive definite m x m matrix (x overwrites b).

    a = L L^T is factorised in place column by column (L in the lower triangle), then
    L u = b and L^T x = u are solved by forward and back substitution. Used on the Schur complement
    Phi_q M^-1 Phi_q^T of the augmented system, which is positive definite while the constraint
    rows are independent.
    """
    for j in range(m):
        d = a[j, j]
        for k in range(j):
            d -= a[j, k] * a[j, k]
        d = math.sqrt(d)
        a[j, j] = d
        for i in range(j + 1, m):
            v = a[i, j]
            for k in range(j):
                v -= a[i, k] * a[j, k]
            a[i, j] = v / d
    for i in range(m):
        v = b[i]
        for k in range(i):
            v -= a[i, k] * b[k]
        b[i] = v / a[i, i]
    for i in range(m - 1, -1, -1):
        v = b[i]
        for k in range(i + 1, m):
            v -= a[k, i] * b[k]
        b[i] = v / a[i, i]
