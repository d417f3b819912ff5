"""The step map of the walker in space checked from random starts near Coleman et al.'s toy's fixed point: the
map's Jacobian measured along random directions has the multipliers of the one along the axes, and perturbations
follow the Jacobian's powers, their slowest part decaying at the largest multiplier's modulus per step."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import load_config
from biped_sim.rigid.limit_cycle import RIGID_TOLERANCE, map_jacobian, newton_fixed_point
from biped_sim.rigid.space_cycle import SpaceMap, space_walker_model
from biped_sim.rigid.space_integration import FALL_BANK
from biped_sim.rigid.space_step import clearance, passed, phase, space_step

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


def test_the_compiled_step_is_scipys_integration_of_the_same_flow() -> None:
    """Both phases of a step of the toy's gait integrated by scipy's solve_ivp to the same guards (a run's phases,
    :func:`~biped_sim.rigid.space_step.phase`): the compiled map's touchdown state and time to 1e-12 (the same steps
    and event location; rounding apart)."""
    step_map, z = SpaceMap(space_walker_model(load_config(TINKERTOY))), np.array(TINKERTOY_POINT)
    _, step = step_map.step(z)
    passing = phase(step_map.model, step_map.params, step_map.section.from_section(z), 0.0, passed)
    landing = phase(step_map.model, step_map.params, passing.x, passing.t, clearance(step_map.model))
    assert landing.how == "guard" and step.period == pytest.approx(landing.t, abs=1e-12)
    np.testing.assert_allclose(step.x_minus, landing.x, atol=1e-12)


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
