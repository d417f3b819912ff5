"""Butcher tableaus of the explicit Runge-Kutta methods, packed for the compiled loop.

Euler, Heun's RK2 and the classic RK4 are textbook tableaus. Dormand-Prince 5(4) and
8(5,3) take their coefficients (including the dense-output ones) from scipy's published
tables, so that the numbers are those of Dormand & Prince (1980) and Hairer, Norsett &
Wanner, "Solving ODEs I" (1993), as scipy ships them.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.integrate._ivp.rk import DOP853, RK45

FIXED, DOPRI5, DOP853_KIND = 0, 1, 2
MAX_STAGES = 16


class Tableau(NamedTuple):
    """Coefficients of one explicit RK method (arrays padded to MAX_STAGES)."""

    kind: int  # FIXED (no embedded error), DOPRI5 or DOP853_KIND
    stages: int
    order: int  # order of the propagated solution
    error_order: int  # order of the embedded error estimator (step-size exponent 1/(q+1))
    a: np.ndarray  # (16, 16)
    b: np.ndarray  # (16,)
    c: np.ndarray  # (16,)
    e: np.ndarray  # (16,) error weights (dop853: E5) over stages + the FSAL stage
    e3: np.ndarray  # (16,) dop853's third-order error weights
    p: np.ndarray  # (7, 4) dopri5 dense-output polynomial
    a_extra: np.ndarray  # (3, 16) dop853 extra stages for dense output
    c_extra: np.ndarray  # (3,)
    d: np.ndarray  # (4, 16) dop853 dense-output weights


def _pad(values: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    out = np.zeros(shape)
    out[tuple(slice(0, s) for s in values.shape)] = values
    return out


def _tableau(kind: int, order: int, error_order: int, a: list | np.ndarray, b: list, c: list, **extra) -> Tableau:
    a = np.asarray(a, dtype=float)
    return Tableau(
        kind=kind,
        stages=len(b),
        order=order,
        error_order=error_order,
        a=_pad(a, (MAX_STAGES, MAX_STAGES)),
        b=_pad(np.asarray(b, dtype=float), (MAX_STAGES,)),
        c=_pad(np.asarray(c, dtype=float), (MAX_STAGES,)),
        e=_pad(np.asarray(extra.get("e", [0.0])), (MAX_STAGES,)),
        e3=_pad(np.asarray(extra.get("e3", [0.0])), (MAX_STAGES,)),
        p=_pad(np.asarray(extra.get("p", np.zeros((1, 1)))), (7, 4)),
        a_extra=_pad(np.asarray(extra.get("a_extra", np.zeros((1, 1)))), (3, MAX_STAGES)),
        c_extra=_pad(np.asarray(extra.get("c_extra", [0.0])), (3,)),
        d=_pad(np.asarray(extra.get("d", np.zeros((1, 1)))), (4, MAX_STAGES)),
    )


TABLEAUS: dict[str, Tableau] = {
    "euler": _tableau(FIXED, 1, 0, [[0.0]], [1.0], [0.0]),
    "rk2": _tableau(FIXED, 2, 0, [[0.0, 0.0], [1.0, 0.0]], [0.5, 0.5], [0.0, 1.0]),
    "rk4": _tableau(
        FIXED,
        4,
        0,
        [[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]],
        [1 / 6, 1 / 3, 1 / 3, 1 / 6],
        [0.0, 0.5, 0.5, 1.0],
    ),
    "dopri5": _tableau(DOPRI5, 5, 4, RK45.A, list(RK45.B), list(RK45.C), e=RK45.E, p=RK45.P),
    "dop853": _tableau(
        DOP853_KIND,
        8,
        7,
        DOP853.A,
        list(DOP853.B),
        list(DOP853.C),
        e=DOP853.E5,
        e3=DOP853.E3,
        a_extra=DOP853.A_EXTRA,
        c_extra=DOP853.C_EXTRA,
        d=DOP853.D,
    ),
}
