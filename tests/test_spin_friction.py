"""The spin (drilling) friction torque about the contact normal (``friction.spin_radius``): its law, its refusals,
a sphere spinning down on flat ground at mechanics' rate, its energy audit, and runs without spin unchanged."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from biped_sim.contact.friction import FRICTION_LAWS, friction_parameters, spin_friction_torque
from biped_sim.contact.ground import ProfileGround
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.spatial_kernels import mechanical_energy
from biped_sim.studies import incline

from .conftest import DEFAULT_CONFIG, ROOT, invoke, one_line_error
from .record_golden import read_golden, simulated_summary
from .test_golden import differences

MU, SPIN_RADIUS, W0 = 0.3, 0.01, 5.0  # dry coefficient, r_s [m], initial spin [rad/s]
V0 = 1e-5  # [m/s] Coulomb's regularisation speed
INERTIA = incline.SPHERE.inertia_ratio * incline.MASS * incline.RADIUS**2  # about the vertical [kg m^2]
LOAD = incline.MASS * incline.GRAVITY  # [N]
RATE = 10_000.0  # [1/s] samples
STATELESS = [name for name, law in FRICTION_LAWS.items() if not law.stateful]
KNEED_3D = ROOT / "configs" / "space" / "kneed_walker_3d.yaml"


@pytest.mark.parametrize("law", STATELESS)
def test_the_spin_torque_is_the_law_at_the_spin_speed_times_the_radius(law: str) -> None:
    """M_n = r_s F_T(r_s w_n, F_N): the law's own force at the speed of a point r_s out, opposing the spin."""
    p = friction_parameters(0.6, 0.8, 1e-3, 1e-2, 1e-3, 100.0, 0.5, 1e4, 20.0, 0.0, spin_radius=0.02)
    function = FRICTION_LAWS[law].function
    for w in (-3.0, -0.2, 0.04, 0.3, 7.0):
        assert spin_friction_torque(FRICTION_LAWS[law].index, w, 9.0, p) == 0.02 * function(0.02 * w, 9.0, p)
    assert spin_friction_torque(FRICTION_LAWS[law].index, 7.0, 9.0, friction_parameters(*p[:10])) == 0.0


@pytest.mark.parametrize(
    ("config", "sets", "expected"),
    [
        (DEFAULT_CONFIG, ["friction.spin_radius=0.01"], "friction.spin_radius: only in space"),
        (KNEED_3D, ["friction.spin_radius=-0.01"], "friction.spin_radius: Input should be greater than or equal to 0"),
        (KNEED_3D, ["friction.model=lugre", "friction.spin_radius=0.01"], "friction.spin_radius: needs a stateless"),
        (KNEED_3D, ["friction.model=none", "friction.spin_radius=0.01"], "friction.spin_radius: needs a stateless"),
    ],
)
def test_bad_spin_friction_is_one_line_exit_2(tmp_path: Path, config: Path, sets: list[str], expected: str) -> None:
    out = tmp_path / "out"
    result = invoke("run", str(config), *(arg for s in sets for arg in ("--set", s)), "--out", str(out))
    assert result.exit_code == 2, result.output
    assert expected in one_line_error(result.stderr)
    assert not out.exists()


def spin_down(ground: ProfileGround | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(t, spin about the vertical, energy audit residual, friction work at the end [J]) of the sphere (radius
    0.1 m, 1 kg) spinning at W0 about the vertical on flat ground under Coulomb spin friction (mu 0.3, r_s 1 cm),
    at rest otherwise; ``ground``: the same level ground as a profile."""
    p = friction_parameters(MU, MU, V0, 10 * V0, V0, 0.0, 0.0, 1e4, 20.0, 0.0, spin_radius=SPIN_RADIUS)
    system, y0, modes0 = incline.spatial_sphere("coulomb", p, 0.0, spin=(0.0, W0, 0.0))
    if ground is not None:
        system = system._replace(ground=ground)
    run = integrate_model(system, y0, modes0, incline.INTEGRATOR, t_end=incline.DURATION, sample_rate=RATE)
    assert run.status == "walking" and math.isclose(run.t[-1], incline.DURATION)
    spin = np.array([incline.angular_velocity(y)[1] for y in run.y])
    total = [sum(mechanical_energy(y, system, m)) + y[-2] + y[-1] for y, m in zip(run.y, run.modes, strict=True)]
    return run.t, spin, np.asarray(total) - total[0], float(run.y[-1, -1])


@pytest.mark.slow
def test_a_sphere_spinning_on_flat_ground_stops_at_the_dry_rate_and_its_energy_audit_closes() -> None:
    """Dry spin friction decelerates the spin at alpha = mu N r_s / I_n and stops it at t = I_n w0 / (mu N r_s)
    (0.680 s here). Regularised Coulomb departs from dry by (v0 / r_s w)^2 / 2 while r_s w >> v0 (2e-6 at the
    end of the window checked; measured 1.8e-6), and takes at most (v0 / r_s) / alpha longer to reach r_s w = v0
    than dry friction takes to stop: the stop time is measured where r_s w falls below v0 (measured 2e-5 s after
    t). The audit (kinetic + potential + elastic + dissipated) closes to 1e-11 of the spin's energy I w0^2 / 2
    (measured 9e-15), all of which the spin friction takes."""
    t, spin, residual, friction_work = spin_down()
    alpha = MU * LOAD * SPIN_RADIUS / INERTIA
    t_stop = INERTIA * W0 / (MU * LOAD * SPIN_RADIUS)
    turning = t < 0.9 * t_stop
    assert spin[turning] == pytest.approx(W0 - alpha * t[turning], rel=1e-5)
    stopped = t[np.argmax(SPIN_RADIUS * spin < V0)]
    assert abs(stopped - t_stop) <= (V0 / SPIN_RADIUS) / alpha + 1.0 / RATE
    assert np.all(np.abs(spin[t > stopped]) < V0 / SPIN_RADIUS)
    scale = 0.5 * INERTIA * W0**2
    assert np.max(np.abs(residual)) < 1e-11 * scale
    assert friction_work == pytest.approx(scale, rel=1e-6)


@pytest.mark.slow
def test_the_spin_down_on_a_level_profile_is_the_flat_grounds() -> None:
    """The profile's kernel applies the torque about its feature's normal: on a level polyline the spin and the audit
    are the flat ground's (to 1e-10 rad/s, measured 8e-14)."""
    _, spin, residual, _ = spin_down(ProfileGround(np.array([[-1.0, 0.0], [1.0, 0.0]]), np.zeros(2)))
    _, flat_spin, _, _ = spin_down()
    assert spin == pytest.approx(flat_spin, abs=1e-10)
    assert np.max(np.abs(residual)) < 1e-11 * 0.5 * INERTIA * W0**2


def test_a_planar_walker_in_space_with_spin_friction_is_bit_for_bit_its_golden_run() -> None:
    """Its feet never turn about the ground's normal (omega_n = 0 exactly), so the torque is 0 and the run, spin
    friction on, is bit for bit the golden one recorded without it."""
    case = read_golden()["cases"]["spatial_compass_short"]
    now = simulated_summary({**case, "overrides": [*case["overrides"], "friction.spin_radius=0.01"]})
    assert differences(now, case) == {}
