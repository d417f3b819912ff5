"""scipy's BDF and Radau with their Newton matrices factored and solved by LAPACK directly.

Both solvers factor I - c J (Radau: also its complex counterpart) with ``scipy.linalg.lu_factor`` and solve with
``lu_solve`` several times a step. On a walker's few dozen coordinates the array-API wrappers and finiteness checks
of those two functions cost more than LAPACK's work itself. :class:`DirectBDF` and :class:`DirectRadau` call the
same LAPACK routines (getrf, getrs) on the same arrays, so every step is the same to the bit; a matrix that is not
finite gives a solution that is not finite, which the step's error control rejects (scipy's checks raised a
``ValueError`` instead). They replace the solvers' ``lu`` and ``solve_lu`` attributes, scipy internals: a test
checks that they still take effect.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from scipy.integrate import BDF, Radau
from scipy.linalg import LinAlgWarning
from scipy.linalg.lapack import dgetrf, dgetrs, zgetrf, zgetrs

_ROUTINES = {np.dtype(np.float64): (dgetrf, dgetrs), np.dtype(np.complex128): (zgetrf, zgetrs)}


def lu_factor(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """LU with partial pivoting of ``a`` (overwritten), as ``scipy.linalg.lu_factor(a, overwrite_a=True)``."""
    lu, piv, info = _ROUTINES[a.dtype][0](a, overwrite_a=True)
    if info > 0:  # as lu_factor says it
        warnings.warn(f"Diagonal number {info} is exactly zero. Singular matrix.", LinAlgWarning, stacklevel=2)
    return lu, piv


def lu_solve(factors: tuple[np.ndarray, np.ndarray], b: np.ndarray) -> np.ndarray:
    """The solution x of a x = b from :func:`lu_factor`'s factors (``b`` overwritten), as ``scipy.linalg.lu_solve``."""
    lu, piv = factors
    x, _ = _ROUTINES[np.promote_types(lu.dtype, b.dtype)][1](lu, piv, b, overwrite_b=True)  # lu_solve's choice
    return x


class _DirectLU:
    """Mixin: after the solver's set-up, its dense Newton matrices go through :func:`lu_factor` and :func:`lu_solve`
    (a sparse Jacobian keeps scipy's own)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if isinstance(self.J, np.ndarray):
            self.lu, self.solve_lu = self._factor, lu_solve

    def _factor(self, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        self.nlu += 1  # the count scipy reports
        return lu_factor(a)


class DirectBDF(_DirectLU, BDF):
    """scipy's BDF (``solve_ivp(method=DirectBDF)``), its Newton matrices through LAPACK directly."""


class DirectRadau(_DirectLU, Radau):
    """scipy's Radau IIA (``solve_ivp(method=DirectRadau)``), its Newton matrices through LAPACK directly."""
