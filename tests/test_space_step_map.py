"""The step map of the walker in space checked from random starts near Coleman et al.'s toy's fixed point: the
map's Jacobian measured along random directions has the multipliers of the one along the axes, and perturbations
follow the Jacobian's powers, their slowest part decaying at the largest multiplier's modulus per step."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from biped_sim.config import load_config
from biped_sim.rigid.limit_cycle import RIGID_TOLERANCE, map_jacobian, newton_fixed_point
from biped_sim.rigid.space_cycle import SpaceMap, space_walker_model
from biped_sim.rigid.space_dynamics import hip_push
from biped_sim.rigid.space_integration import FALL_BANK, space_clearance, space_scratch
from biped_sim.rigid.space_kernels import space_flow
from biped_sim.rigid.space_step import space_step
from biped_sim.rigid.space_walk import walk_step
from biped_sim.rigid.step import ATOL, RTOL

TINKERTOY = Path(__file__).resolve().parents[1] / "configs" / "space" / "tinkertoy.yaml"
# docs/guide/rigid.md's fixed point (heading, bank, pitch, omega x y z, hinge rate), polished by Newton here
TINKERTOY_POINT = (0.09866766, -0.00924861, -0.16016583, -0.06623178, 0.46696908, -0.13656793, -0.39255917)
TINKERTOY_LARGEST = 0.83915586  # the modulus of its largest multipliers, a complex pair
SIZE = 1e-4  # the random starts' distance from the fixed point (section coordinates)
STEPS = 30


@pytest.fixture(scope="module")
def tinkertoy() -> tuple[SpaceMap, np.ndarray, np.ndarray]:
    """The toy's step map, its fixed point and the map's Jacobian there (central differences along the axes)."""
    step_map = SpaceMap(space_walker_model(load_config(TINKERTOY)))
    z, converged, _, _ = newton_fixed_point(step_map, np.array(TINKERTOY_POINT), RIGID_TOLERANCE)
    assert converged
    return step_map, z, map_jacobian(step_map, z)


def scipy_phases(step_map: SpaceMap, x: np.ndarray, push: tuple[float, np.ndarray] | None = None) -> list[Any]:
    """The reference: scipy's solve_ivp (DOP853, the step map's tolerances) over the compiled flow through both
    phases of a step to each guard's downward zero, stopped at ``push`` (its time and impulse) to apply it."""
    params = step_map.params
    guards = [lambda t, x: x[3], lambda t, x: space_clearance(params, x)]
    solutions, t, phase = [], 0.0, 0
    while phase < 2:
        event = guards[phase]
        event.terminal, event.direction = True, -1.0  # type: ignore[attr-defined]
        end = 20.0 if push is None or push[0] <= t else push[0]
        sol = solve_ivp(lambda t, x: space_flow(params, x), (t, end), x, "DOP853", rtol=RTOL, atol=ATOL,
                        events=event, dense_output=True)  # fmt: skip
        solutions.append(sol)
        t, x = (sol.t_events[0][0], sol.y_events[0][0]) if sol.status == 1 else (sol.t[-1], sol.y[:, -1])
        phase += sol.status
        if push is not None and sol.status == 0:
            x = hip_push(step_map.model, x, push[1])[0]
    return solutions


@pytest.mark.parametrize("pushed", [False, True])
def test_the_compiled_step_and_a_runs_samples_are_scipys_integration_of_the_same_flow(pushed: bool) -> None:
    """A run's step from the toy's gait (unpushed: the step map's bit for bit; or pushed sideways at 0.7) integrated
    by scipy's solve_ivp to the same guards: touchdown state and time to 1e-12 (the same steps and event location,
    rounding apart), the samples (100 a second) on its dense output to 1e-12."""
    step_map, z = SpaceMap(space_walker_model(load_config(TINKERTOY))), np.array(TINKERTOY_POINT)
    x0, pushes = step_map.section.from_section(z), [(0.7, np.array([0.0, -0.01, 0.0]))] if pushed else []
    walked = walk_step(step_map.model, step_map.params, space_scratch(2001), x0, 100.0, pushes)
    assert len(walked.pushes) == len(pushes) and len(walked.samples_t) == math.ceil(walked.step.period * 100.0)
    if not pushed:
        assert walked.step.period == step_map.step(z)[1].period
    solutions = scipy_phases(step_map, x0, pushes[0] if pushed else None)
    landing = solutions[-1]
    assert landing.status == 1 and walked.step.period == pytest.approx(landing.t_events[0][0], abs=1e-12)
    np.testing.assert_allclose(walked.step.x_minus, landing.y_events[0][0], atol=1e-12)
    assert len(solutions) == 2 + pushed
    for sol in solutions:
        inside = (walked.samples_t >= sol.t[0]) & (walked.samples_t < sol.t[-1])
        assert inside.sum() >= 10
        np.testing.assert_allclose(walked.samples_x[inside], sol.sol(walked.samples_t[inside]).T, atol=1e-12)


@pytest.mark.slow
def test_random_directions_give_the_same_multipliers(tinkertoy: tuple[SpaceMap, np.ndarray, np.ndarray]) -> None:
    """Central differences along seeded random unit directions D give J = R D^-1 with the axes' multipliers."""
    step_map, z, jac = tinkertoy
    directions = np.random.default_rng(28).normal(size=(len(z), len(z)))
    directions /= np.linalg.norm(directions, axis=0)
    responses = np.column_stack([(step_map(z + SIZE * d) - step_map(z - SIZE * d)) / (2 * SIZE) for d in directions.T])
    random_jac = responses @ np.linalg.inv(directions)
    moduli = np.sort(np.abs(np.linalg.eigvals(random_jac)))
    np.testing.assert_allclose(moduli, np.sort(np.abs(np.linalg.eigvals(jac))), atol=2e-5)
    assert moduli[-1] == pytest.approx(TINKERTOY_LARGEST, abs=2e-5)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_starts_decay_at_the_largest_multiplier(
    tinkertoy: tuple[SpaceMap, np.ndarray, np.ndarray], seed: int
) -> None:
    """A seeded start SIZE off the fixed point walked STEPS steps: it stays within 5 % of J^n d0 (the linear map's
    prediction), and its part along the largest multipliers' eigenvectors (eigen-coordinates V^-1 d) shrinks at
    their modulus per step, to 1e-3."""
    step_map, z, jac = tinkertoy
    values, vectors = np.linalg.eig(jac)
    start = np.random.default_rng(seed).normal(size=len(z))
    z_n, predicted = z + SIZE * start / np.linalg.norm(start), SIZE * start / np.linalg.norm(start)
    leading = int(np.argmax(np.abs(values)))
    first = abs(np.linalg.solve(vectors, predicted)[leading])
    for _ in range(STEPS):
        z_n, predicted = step_map(z_n), jac @ predicted
        assert np.linalg.norm(z_n - z - predicted) < 0.05 * np.linalg.norm(predicted)
    last = abs(np.linalg.solve(vectors, z_n - z)[leading])
    assert (last / first) ** (1.0 / STEPS) == pytest.approx(TINKERTOY_LARGEST, abs=1e-3)


def test_a_roll_rate_too_large_topples_the_toy_sideways() -> None:
    """Rolling out at 1 rad/s from the gait, the toy banks past FALL_BANK during the step: it ends there, fell."""
    step_map, z = SpaceMap(space_walker_model(load_config(TINKERTOY))), np.array(TINKERTOY_POINT)
    z[3] = 1.0
    step = space_step(step_map.model, step_map.section.from_section(z))
    assert step.status == "fell" and step.x_plus is None
    assert step.x_minus[1] == pytest.approx(FALL_BANK, abs=1e-12)
