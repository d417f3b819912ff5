"""The spatial formulation on ground profiles (:mod:`biped_sim.multibody.spatial_feet`): feet at rest on a sloped
segment at the law's static sinkage (every shape: on a straight stretch the outline's osculating circle is exact),
a planar walker lifted into space walking each profile as in the plane, and its energy audit there; a walker in space
on a level profile as on the flat ground, and its MFPT on random heights."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_sim import simulate
from biped_sim.config import MaterialsConfig
from biped_sim.contact.ground import ProfileGround
from biped_sim.contact.normal import hertz_stiffness
from biped_sim.multibody.spatial import SpatialSystem
from biped_sim.multibody.spatial_feet import foot_kinematics
from biped_sim.studies.uncertainty.mfpt import mfpt_curve
from biped_sim.testing import default_walker
from tests.test_space_compliant import tinkertoy
from tests.test_space_feet_compliant import AXES, RADIUS, TUBE, one_body, settled

SLOPE = 0.3  # [rad] the segment's inclination in the slope frame
NORMAL = np.array([-math.sin(SLOPE), math.cos(SLOPE), 0.0])
# one segment through the origin, rising downhill at SLOPE, then level beyond both ends
SEGMENT = ProfileGround(np.array([[-1.0, -math.tan(SLOPE)], [1.0, math.tan(SLOPE)]]), np.zeros(2))


def on_segment(system: SpatialSystem) -> SpatialSystem:
    """``system`` on :data:`SEGMENT`, gravity along its inward normal (no friction needed to rest) and its body
    turned by SLOPE about z, so that its bottom faces the segment."""
    return system._replace(ground=SEGMENT, gravity=-9.81 * NORMAL)


@pytest.mark.parametrize(
    ("system", "height", "hertz"),
    [
        (one_body(np.zeros(3)), RADIUS, RADIUS),
        (one_body(tube=TUBE), RADIUS + TUBE, math.sqrt((RADIUS + TUBE) * TUBE)),
        (one_body(np.zeros(3), 0.0, axes=AXES), AXES[1], AXES[0] * AXES[2] / AXES[1]),
    ],
    ids=["sphere", "torus", "ellipsoid"],
)
def test_a_foot_at_rest_on_a_sloped_segment_sinks_to_the_law_s_static_sinkage(
    system: SpatialSystem, height: float, hertz: float
) -> None:
    """Settled under gravity along the segment's normal: penetration (m g / K)^(2/3) (Hertz, n = 3/2) along it, the
    contact point (the foot's deepest) ``height`` from the centre of mass along the normal."""
    m = MaterialsConfig()
    k = hertz_stiffness(m.foot.youngs_modulus, m.foot.poisson_ratio, m.ground.youngs_modulus, m.ground.poisson_ratio,
                        hertz)  # fmt: skip
    sinkage = (9.81 / k) ** (2.0 / 3.0)
    system = on_segment(system)
    turn = (math.cos(0.5 * SLOPE), 0.0, 0.0, math.sin(0.5 * SLOPE))
    run = settled(system, height, sinkage, attitude=turn, normal=NORMAL)
    assert run.status == "walking"
    delta, _, _, _, x_contact = foot_kinematics(run.y[-1], system, 0)[:5]
    assert delta == pytest.approx(sinkage, rel=1e-9)
    centre = run.y[-1][:3]
    assert x_contact == pytest.approx(centre[0] - height * NORMAL[0], abs=1e-12)


PROFILES = {
    "polyline": "ground.profile={kind: polyline, x: [0.2, 0.6, 1.0, 1.4], height: [0, 0.004, -0.003, 0]}",
    "slope_change": "ground.profile={kind: slope_change, at: 0.5, slope: 0.04}",
    "random": "ground.profile={kind: random, spacing: 0.05, roughness: 0.001, seed: 4, length: 3}",
    "steps": "ground.profile={kind: steps, steps: [{at: 0.45, height: -0.005}, {at: 0.9, height: 0.002}]}",
}


def strike_time_differences(profile: str, rtol: float, atol: float) -> tuple[np.ndarray, float]:
    """(|spatial - planar| heel-strike times [s], the spatial run's largest energy residual [m g l]) of the compass
    walking ``profile`` for 2 s at dopri5 ``rtol`` and ``atol``, after checking both walk the same steps."""
    tolerances = (f"integrator.rtol={rtol!r}", f"integrator.atol={atol!r}")
    planar = simulate(default_walker(PROFILES[profile], *tolerances, t_end=2.0))
    spatial = simulate(default_walker(PROFILES[profile], *tolerances, "formulation.kind=spatial", t_end=2.0))
    assert spatial.status == planar.status == "walking"
    assert spatial.summary["n_steps"] == planar.summary["n_steps"] >= 4
    assert np.array_equal(spatial.steps.foot, planar.steps.foot)
    m_g_l = spatial.model.total_mass * 9.81 * spatial.model.leg_length
    assert spatial.summary["energy_dissipated"]["normal"] > 1e-3 * m_g_l  # the audit is not trivially closed
    residual = np.max(np.abs(spatial.energy.residual)) / m_g_l
    return np.abs(spatial.steps.strike_time - planar.steps.strike_time), residual


@pytest.mark.parametrize("profile", ["polyline", pytest.param("slope_change", marks=pytest.mark.slow),
                                     pytest.param("random", marks=pytest.mark.slow)])  # fmt: skip
def test_a_planar_walker_lifted_into_space_walks_each_profile_as_in_the_plane(profile: str) -> None:
    """The compass (its feet discs in its sagittal plane: circles in outline) at rtol 1e-10: its heel strikes come
    at the planar formulation's times to 1e-9 s (measured 3e-10 at most), its energy audit closes to 1e-9 m g l."""
    differences, residual = strike_time_differences(profile, 1e-10, 1e-12)
    assert differences.max() < 1e-9
    assert residual < 1e-9


@pytest.mark.slow
def test_down_and_up_steps_the_lifted_walker_s_strike_times_converge_to_the_planar_ones() -> None:
    """On steps the strike after the step up amplifies the integration error (2.2e-8 s at rtol 1e-10): a tolerance
    ten times tighter brings it ten times closer (1.9e-9 s), the difference of two integrations of one motion."""
    loose, _ = strike_time_differences("steps", 1e-10, 1e-12)
    tight, residual = strike_time_differences("steps", 1e-11, 1e-13)
    assert tight.max() < 3e-9
    assert tight.max() < 0.2 * loose.max()
    assert residual < 1e-9


@pytest.mark.slow
def test_coleman_s_toy_walks_a_level_polyline_as_the_flat_ground_on_its_banked_rings_outlines() -> None:
    """The compliant toy banks: its rings' outlines are ellipses, found through their osculating circles on a
    profile and through the lowest point on the flat ground. On a polyline at height 0 the two agree: strikes at the
    flat times to 1e-8 s (measured 3e-9 s at the config's rtol 1e-8), dissipation to 1e-7 relative."""
    flat = simulate(tinkertoy("simulation.t_end=3"))
    level = simulate(
        tinkertoy("simulation.t_end=3", "ground.profile={kind: polyline, x: [-5, 0.26, 50], height: [0, 0, 0]}")
    )
    assert flat.status == level.status == "walking" and len(flat.steps.strike_time) == len(level.steps.strike_time) == 2
    np.testing.assert_allclose(level.steps.strike_time, flat.steps.strike_time, rtol=0, atol=1e-8)
    assert level.summary["energy_dissipated"]["normal"] == pytest.approx(
        flat.summary["energy_dissipated"]["normal"], rel=1e-7
    )


@pytest.mark.slow
def test_the_mfpt_of_a_compliant_walker_in_space_runs_on_random_heights() -> None:
    """The compliant toy on random heights (its rigid model walks random slopes only): at 0.05 % of its leg length
    no walk of 3 steps falls, at 2 % one of two does (measured)."""
    smooth, rough = mfpt_curve(tinkertoy(), "height", [0.0005, 0.02], seeds=2, cap=3).estimates
    assert (smooth.falls, smooth.censored) == (0, 2)
    assert rough.falls >= 1
