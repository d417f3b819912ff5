"""Integrator orders on a smooth problem, adaptive/fixed agreement, and bit-for-bit reproducibility."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import config_from_dict, simulate
from biped_sim.config import IntegratorConfig
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.planar import PlanarSystem


def pendulum(amplitude: float) -> tuple[PlanarSystem, np.ndarray]:
    """A uniform rod (1 kg, 1 m) hinged to the ground at its end, released at rest: smooth, no contact."""
    length, mass = 1.0, 1.0
    system = PlanarSystem(
        body_mass=np.array([mass]),
        body_inertia=np.array([mass * length**2 / 12.0]),
        joint_bodies=np.array([[0, -1]], dtype=np.int64),
        joint_points=np.array([[0.0, 0.5 * length, 0.0, 0.0]]),
        foot_body=np.zeros(0, dtype=np.int64),
        foot_center=np.zeros((0, 2)),
        foot_radius=np.zeros(0),
        foot_partner=np.zeros(0, dtype=np.int64),
        gravity=np.array([0.0, -9.81]),
        baumgarte=np.array([10.0, 10.0]),
        normal_params=np.zeros(4),
        friction_params=np.zeros(10),
        switches=np.zeros(3, dtype=np.int64),
        limits=np.array([1e-3, -math.inf, math.inf]),
    )
    centre = 0.5 * length * np.array([math.sin(amplitude), -math.cos(amplitude)])
    y0 = np.array([*centre, amplitude, 0.0, 0.0, 0.0, 0.0, 0.0])
    return system, y0


def final_state(method: str, n_steps: int, t_end: float, amplitude: float = 0.1) -> np.ndarray:
    """Position and velocity of the rod after n_steps fixed steps (step-size control off)."""
    system, y0 = pendulum(amplitude)
    integrator = IntegratorConfig(method=method, dt=t_end / n_steps, adaptive=False)
    run = integrate_model(system, y0, np.zeros((0, 3)), integrator, t_end, sample_rate=1.0 / t_end)
    return run.y[-1, :6]


@pytest.mark.parametrize(
    ("method", "order", "t_end", "steps"),
    [
        ("euler", 1, 10.0, (20_000, 40_000)),
        ("rk2", 2, 10.0, (2_000, 4_000)),
        ("rk4", 4, 100.0, (6_400, 12_800)),
        ("dopri5", 5, 100.0, (6_400, 12_800)),
        ("dop853", 8, 100.0, (1_600, 3_200)),
    ],
)
def test_convergence_order_on_smooth_problem(method: str, order: int, t_end: float, steps: tuple[int, int]) -> None:
    """Global error ratio at halved steps on a nearly linear pendulum (10-50 periods).

    The high-order methods have small principal error coefficients: on strongly nonlinear
    problems their measured order exceeds the nominal one until round-off takes over, so the
    problem is a small (0.1 rad) swing over many periods, where the asymptotic regime is
    reached with errors well above round-off.
    """
    reference = final_state("dop853", 40_000, t_end)
    coarse, fine = (np.linalg.norm(final_state(method, n, t_end) - reference) for n in steps)
    measured = math.log2(coarse / fine)
    assert abs(measured - order) < 0.3, (coarse, fine, measured)


def test_adaptive_methods_agree_on_the_walker() -> None:
    periods = {}
    for method in ("dopri5", "dop853", "radau"):
        result = simulate(config_from_dict({}, [f"integrator.method={method}", "simulation.t_end=2"]))
        periods[method] = result.step_periods
    np.testing.assert_allclose(periods["dop853"], periods["dopri5"], rtol=1e-6)
    np.testing.assert_allclose(periods["radau"], periods["dopri5"], rtol=1e-4)


def test_same_config_same_bits() -> None:
    config = config_from_dict({}, ["simulation.t_end=2"])
    first, second = simulate(config), simulate(config)
    assert np.array_equal(first.run.y, second.run.y)
    assert np.array_equal(first.run.strike_t, second.run.strike_t)
    assert first.summary["config_hash"] == second.summary["config_hash"]


def test_progress_chunking_does_not_change_results() -> None:
    config = config_from_dict({}, ["simulation.t_end=2"])
    times: list[float] = []
    with_progress = simulate(config, progress=times.append)
    assert times and times[-1] == pytest.approx(2.0)
    assert np.array_equal(with_progress.run.y, simulate(config).run.y)
