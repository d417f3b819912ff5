"""scipy's BDF and Radau with their Newton matrices through LAPACK directly (integrate.newton_lu): the same steps
to the bit as scipy's own, on a stiff problem with a known Jacobian."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from biped_sim.integrate.newton_lu import DirectBDF, DirectRadau, lu_factor, lu_solve

MU = 1000.0  # van der Pol's stiffness


def van_der_pol(t: float, y: np.ndarray) -> np.ndarray:
    return np.array([y[1], MU * (1.0 - y[0] ** 2) * y[1] - y[0]])


def jacobian(t: float, y: np.ndarray) -> np.ndarray:
    return np.array([[0.0, 1.0], [-2.0 * MU * y[0] * y[1] - 1.0, MU * (1.0 - y[0] ** 2)]])


@pytest.mark.parametrize(("ours", "scipys"), [(DirectBDF, "BDF"), (DirectRadau, "Radau")])
def test_the_direct_solvers_take_scipys_steps_to_the_bit(ours: type, scipys: str) -> None:
    """Through a relaxation oscillation (steps from 1e-6 to 1e2): every step's time and state equal, the same
    number of factorizations (Radau: real and complex ones)."""
    runs = [
        solve_ivp(van_der_pol, (0.0, 3000.0), [2.0, 0.0], method=m, jac=jacobian, rtol=1e-8, atol=1e-10)
        for m in (ours, scipys)
    ]
    assert runs[0].success and len(runs[0].t) > 500
    np.testing.assert_array_equal(runs[0].t, runs[1].t)
    np.testing.assert_array_equal(runs[0].y, runs[1].y)
    assert runs[0].nlu == runs[1].nlu > 0


def test_the_direct_solvers_still_replace_scipys_factorization() -> None:
    """The replacement sets scipy's internal attributes ``lu`` and ``solve_lu``: a scipy that renamed them would
    silently take its own path again."""
    solver = DirectBDF(van_der_pol, 0.0, np.array([2.0, 0.0]), 1.0, jac=jacobian)
    assert solver.solve_lu is lu_solve and solver.lu == solver._factor


def test_a_matrix_that_is_not_finite_gives_a_solution_that_is_not_finite() -> None:
    """scipy's lu_factor raises on it; a step's Newton solve here returns NaNs, which its error control rejects."""
    factors = lu_factor(np.array([[1.0, np.nan], [0.0, 1.0]]))
    assert not np.isfinite(lu_solve(factors, np.array([1.0, 1.0]))).all()


def test_the_complex_factorization_solves_a_complex_system() -> None:
    a = np.array([[2.0 + 1.0j, 1.0], [1.0, 3.0 - 1.0j]])
    b = np.array([1.0 + 0.0j, 2.0j])
    np.testing.assert_allclose(a @ lu_solve(lu_factor(a.copy()), b.copy()), b, rtol=1e-14)


@pytest.mark.parametrize(("solver", "scipys"), [(DirectBDF, "BDF"), (DirectRadau, "Radau")])
def test_a_jacobian_that_is_not_finite_fails_the_integration_with_a_status(solver: type, scipys: str) -> None:
    """scipy's own solvers raise a ValueError there (its finiteness check), which the stiff driver re-raised as a
    traceback; these reject the steps until the step size underflows: solve_ivp's status -1, which the driver reports
    as a diverged run (the stiff solver failed)."""
    with warnings.catch_warnings():  # numpy's overflow warnings on the way down
        warnings.simplefilter("ignore", RuntimeWarning)
        run = solve_ivp(lambda t, y: -1000.0 * y, (0.0, 1.0), [1.0], method=solver, jac=lambda t, y: [[np.nan]])
    assert run.status == -1
    with pytest.raises(ValueError, match="infs or NaNs"):
        solve_ivp(lambda t, y: -1000.0 * y, (0.0, 1.0), [1.0], method=scipys, jac=lambda t, y: [[np.nan]])
