"""Butcher tableaus of the explicit Runge-Kutta methods, packed for the compiled loop.

Euler, Heun's RK2 and the classic RK4 are textbook tableaus. Dormand-Prince 5(4) is written
out below exactly as scipy's ``RK45`` spells it (Dormand & Prince 1980; dense output with
Shampine's optimal c_6), so the floats are identical; 8(5,3) takes its coefficients from scipy's
tables (Hairer, Norsett & Wanner, "Solving ODEs I", 1993) when first asked for: importing
``scipy.integrate`` costs 0.3 s of start-up that the other methods do not need.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

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


DOPRI5_C = [0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1]
DOPRI5_A = [
    [0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
]
DOPRI5_B = [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]
DOPRI5_E = [-71 / 57600, 0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40]
DOPRI5_P = [
    [1, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0, 0, 0, 0],
    [0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
]

_TABLEAUS: dict[str, Tableau] = {
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
    "dopri5": _tableau(DOPRI5, 5, 4, DOPRI5_A, DOPRI5_B, DOPRI5_C, e=DOPRI5_E, p=DOPRI5_P),
}


@functools.cache
def _dop853() -> Tableau:
    from scipy.integrate._ivp.rk import DOP853  # here: scipy.integrate adds 0.3 s to start-up

    return _tableau(
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
    )


def tableau(method: str) -> Tableau:
    """The tableau of an explicit method (KeyError for an unknown name)."""
    return _dop853() if method == "dop853" else _TABLEAUS[method]
