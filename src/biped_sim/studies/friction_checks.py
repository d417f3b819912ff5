"""Every friction law's dry limit against mechanics' exact answers on an incline (issue 28, item 7).

A sphere (I = 2/5 m R^2), a disc (I = 1/2 m R^2) and a block (two small round feet, no rolling) rest on a
slope of angle theta and are let go. With dry (Coulomb) friction of static and kinetic coefficients mu_s and
mu_k, and k = I / (m R^2), mechanics gives (x downhill, spin in the rolling sense):

* rolling without slip while the friction it needs, k / (1 + k) tan(theta) of the normal force (2/7 tan for
  the sphere, 1/3 tan for the disc), is at most mu_s: a = g sin(theta) / (1 + k) (5/7 and 2/3 g sin) and
  R alpha = a; the block sticks (a = 0) while tan(theta) <= mu_s;
* sliding past it: a = g (sin(theta) - mu_k cos(theta)) and R alpha = mu_k g cos(theta) / k.

The bodies run in the project's own engine (:mod:`.incline`: the same compiled loop, contact response and laws
as a walker's feet, on the default normal law), started at rest at their static penetration. LuGre's bristles
start loaded with the friction the body needs (a body set down slowly: :func:`settled_bristles`).

Each law is a regularised family whose dry limit is ``scale -> 0`` (:func:`dry_limit_parameters`); each case
runs at two scales. Its dry coefficients are read from the law itself: mu_k its value in fast sliding, mu_s
its peak over the slip speed (:func:`friction_coefficient`; the laws without stiction have mu_s = mu_k).
The needed friction is set to 0.9 mu_s (rolling, sticking) and 1.1 mu_s (sliding). The measured accelerations
are the mean ones from rest, 2 x(T) / T^2 and 2 R phi(T) / T^2, and their tolerances follow from the
regularisation:

* rolling (sticking): the body creeps at the slip speed v_c where the law gives the needed friction (0 for
  LuGre, whose bristles hold a slip of at most d = mu_s / sigma0); the centre then runs ahead of rolling by
  k / (1 + k) of the slip, so |a - a_roll| <= 2 k / (1 + k) (v_c T + d) / T^2 (1 / (1 + k) for R alpha); the
  block also leans on its compliant feet under the friction's moment (:func:`~.incline.block_lean`);
* sliding: the law differs from dry friction only while the slip crosses its regularised band, which the slip
  (growing at least at s_min = g (sin - mu_s cos (1 + 1/k))) crosses in the time I / s_min, I the integral of
  |mu(v) - mu_k| over the slip speed (LuGre adds the time its bristles take to load over their length
  d and their damping's sigma1 d); so |a - a_dry| <= 2 g cos(theta) (I / s_min) / T (divided by k for R alpha).

Both shrink with the scale (proportionally; LuGre's bristle time as its square root): the check also wants the
measured error to shrink. The sphere in space, rolling straight down, is the plane problem by symmetry (the
plane through the fall line and the centre is a mirror plane): it must give the planar sphere's numbers and
no lateral motion; rolling with a lateral velocity it keeps that velocity and rolls down at 5/7 g sin. Sliding
with sidespin on flat ground (a slip along neither axis) its slip keeps its direction until it rolls, at
v0 - 2/7 s0 whatever the law (:func:`flat_slide_row`): the check of the slip-vector form of the laws in space.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from biped_sim.contact.friction import (
    FRICTION_LAWS,
    MU_S,
    SIGMA0,
    SIGMA1,
    VS,
    friction_parameters,
    lugre_bristle_rate,
    lugre_friction,
)
from biped_sim.studies.checks import Check
from biped_sim.studies.incline import (
    BLOCK,
    BODIES,
    DURATION,
    GRAVITY,
    RADIUS,
    SPHERE,
    Body,
    block_lean,
    contact_slip,
    final_state,
    planar_body,
    rolling_angle,
    sampled_states,
    slope_for,
    spatial_sphere,
)

MU_KINETIC, MU_STATIC = 0.3, 0.4
BASE_SPEED = 1e-3  # [m/s] the regularisation speed at scale 1
SCALES = (1.0, 0.1)
ROLL_MARGIN, SLIDE_MARGIN = 0.9, 1.1  # needed friction over the dry static coefficient
NUMERICAL_FLOOR = 1e-6  # [m/s^2] below this an error is the integrator's, not the law's
LATERAL_SPEED = 0.5  # [m/s] the sphere in space rolling across the slope
SPATIAL_AGREEMENT = 1e-8  # [m/s^2] the sphere in space against the planar sphere: two formulations at rtol 1e-10
CHECKED_LAWS = tuple(name for name in FRICTION_LAWS if name != "none")  # "none": frictionless_row
FRICTIONLESS_SLOPE = 0.3  # [rad]
# the sphere sliding on flat ground with sidespin: centre velocity and angular velocity (slope frame), so that its
# first slip (1.3, 0.3) m/s is along neither axis nor its velocity
FLAT_VELOCITY, FLAT_SPIN = (1.0, 0.0, 0.5), (2.0, 0.0, 3.0)


def dry_limit_parameters(scale: float) -> np.ndarray:
    """Parameters of every law at ``scale`` of its regularisation (one vector: each law reads what it names).

    The dry limit is scale -> 0: Coulomb and Threlfall v0 = scale 1e-3 m/s; Ambrosio v0 likewise, v1 = 10 v0;
    Bengisu-Akay v_s = scale 1e-3 m/s, decay 1/xi = 10 v_s; Brown-McPhee v_t0 = scale 1e-3 m/s, no viscous
    term; LuGre v_s = scale 1e-3 m/s, sigma0 = 1e4 / scale [1/m] (bristle length ~ scale), sigma1 = 20 /
    sqrt(scale) [s/m] (the bristles' damping ratio kept) and no viscous sigma2.
    """
    v = BASE_SPEED * scale
    return friction_parameters(
        MU_KINETIC, MU_STATIC, v, 10.0 * v, v, 1.0 / (10.0 * v), 0.0, 1e4 / scale, 20.0 / math.sqrt(scale), 0.0
    )


def friction_coefficient(law: str, speed: float, p: np.ndarray) -> float:
    """|F_T| / F_N in steady sliding at slip ``speed`` > 0, from the law's own compiled functions.

    LuGre: its steady state, the bristle deflection z at which the bristle rate vanishes (the rate is linear
    in z, so z = -rate(v, 0) / (rate(v, 1) - rate(v, 0))) and F_T from its force law with zdot = 0.
    """
    if FRICTION_LAWS[law].stateful:
        rate0 = lugre_bristle_rate(speed, 0.0, p)
        z = -rate0 / (lugre_bristle_rate(speed, 1.0, p) - rate0)
        return -lugre_friction(speed, z, 0.0, 1.0, p)
    return -FRICTION_LAWS[law].function(speed, 1.0, p)


def _speed_grid(p: np.ndarray) -> np.ndarray:
    return np.geomspace(1e-6 * p[VS], 1e4 * p[VS], 4001)


def dry_coefficients(law: str, p: np.ndarray) -> tuple[float, float]:
    """(mu_s, mu_k) of the law's dry limit: its peak over the slip speed and its value in fast sliding."""
    grid = _speed_grid(p)
    mu = np.array([friction_coefficient(law, v, p) for v in grid])
    return float(mu.max()), float(mu[-1])


def creep_speed(law: str, ratio: float, p: np.ndarray) -> float:
    """The slip speed at which the law gives ``ratio`` of the normal force on its rising branch (it holds a
    body that needs that much friction by creeping at it); 0 for LuGre, whose bristles hold without slip."""
    if FRICTION_LAWS[law].stateful:
        return 0.0
    grid = _speed_grid(p)
    mu = np.array([friction_coefficient(law, v, p) for v in grid])
    peak = int(np.argmax(mu >= ratio))  # the first grid speed past the needed friction
    return brentq(lambda v: friction_coefficient(law, v, p) - ratio, 0.0, grid[peak], xtol=1e-15, rtol=1e-13)


def regularised_band(law: str, p: np.ndarray) -> float:
    """The integral over the slip speed of |mu(v) - mu_k| [m/s]: how much the law's sliding differs from dry."""
    _, mu_k = dry_coefficients(law, p)
    top = _speed_grid(p)[-1]
    points = [p[VS] * f for f in (1.0, 10.0, 100.0)]
    value, _ = quad(lambda v: abs(friction_coefficient(law, v, p) - mu_k), 0.0, top, points=points, limit=400)
    return value


@dataclass(frozen=True)
class InclineCase:
    """One run's expected and measured mean accelerations (m/s^2, R alpha for the spin) and their tolerance."""

    law: str
    body: str
    regime: str  # "rolls" (the block: sticks) or "slides"
    scale: float
    slope: float  # [rad]
    expected: float
    measured: float
    tolerance: float
    expected_spin: float = math.nan  # R alpha in the rolling sense; nan for the block
    measured_spin: float = math.nan
    spin_tolerance: float = math.nan
    slip: float = math.nan  # rolling (sticking): the slip speed at the end [m/s]
    creep: float = math.nan  # rolling (sticking): the law's creep speed at the needed friction [m/s]
    allowance: float = 0.0  # the part of the tolerance that is not the regularisation's (the block's lean)

    @property
    def error(self) -> float:
        """|measured - expected| of the acceleration [m/s^2]."""
        return abs(self.measured - self.expected)

    @property
    def spin_error(self) -> float:
        """|measured - expected| of R alpha [m/s^2]; 0 for the block."""
        return abs(self.measured_spin - self.expected_spin) if math.isfinite(self.expected_spin) else 0.0

    @property
    def creeps_as_the_law_says(self) -> bool:
        """Rolling (sticking): the final slip speed is the law's creep speed (within 1 %, or 1e-6 m/s)."""
        return not math.isfinite(self.creep) or abs(self.slip - self.creep) <= 0.01 * self.creep + 1e-6

    @property
    def passed(self) -> bool:
        """Both errors within their tolerances (and the integrator's floor), the slip the law's creep."""
        spin_ok = not math.isfinite(self.expected_spin) or self.spin_error <= self.spin_tolerance + NUMERICAL_FLOOR
        return self.error <= self.tolerance + NUMERICAL_FLOOR and spin_ok and self.creeps_as_the_law_says


def bristle_length(law: str, p: np.ndarray) -> float:
    """The slip LuGre's bristles hold before sliding, mu_s / sigma0 [m]; 0 for the laws without state."""
    return p[MU_S] / p[SIGMA0] if FRICTION_LAWS[law].stateful else 0.0


def _band_time(law: str, p: np.ndarray, slip_rate: float) -> float:
    """The time [s] the law's sliding differs from dry friction, in units of mu: its band crossed at
    ``slip_rate``; LuGre adds its bristles' loading over their length d (sqrt(2 d / rate)) and damping sigma1 d."""
    band = regularised_band(law, p) / slip_rate
    if FRICTION_LAWS[law].stateful:
        d = bristle_length(law, p)
        band += p[MU_S] * math.sqrt(2.0 * d / slip_rate) + p[SIGMA1] * d
    return band


def settled_bristles(law: str, ratio: float, p: np.ndarray) -> float:
    """LuGre's bristle deflection carrying ``ratio`` of the normal force at rest, ratio / sigma0; 0 for the others.

    A body set down on the slope slowly (the bristles loaded with it) starts there. Let go with relaxed bristles
    (a step load) LuGre breaks away below mu_s: the bristles overshoot (damping ratio about 0.5) while the slip
    runs past v_s, so g(v) falls towards mu_k during the loading: the rate-dependent break-away of the
    paper (:mod:`.lugre_checks`), which a step load takes to its limit.
    """
    return ratio / p[SIGMA0] if FRICTION_LAWS[law].stateful else 0.0


def _mean_motion(body: Body, y: np.ndarray) -> dict[str, float]:
    """The mean accelerations from rest to the final planar state ``y`` (2 x / T^2, 2 R phi / T^2 in the rolling
    sense) and the contact point's final slip speed."""
    T = DURATION
    if not body.rolls:
        return {"measured": 2.0 * y[0] / T**2, "slip": y[3]}
    return {"measured": 2.0 * y[0] / T**2, "measured_spin": -2.0 * RADIUS * y[2] / T**2, "slip": y[3] + y[5] * RADIUS}


def rolling_case(law: str, body: Body, scale: float) -> InclineCase:
    """``body`` on the slope where it needs ROLL_MARGIN of the law's static coefficient: it rolls (sticks)."""
    p = dry_limit_parameters(scale)
    ratio = ROLL_MARGIN * dry_coefficients(law, p)[0]
    slope = slope_for(body, ratio)
    y = final_state(*planar_body(body, law, p, slope, settled_bristles(law, ratio, p)))
    k, T = body.inertia_ratio, DURATION
    creep = creep_speed(law, ratio, p)
    slip_distance = creep * T + bristle_length(law, p)  # the most the contact slips
    case = InclineCase(
        law, body.name, "rolls", scale, slope, 0.0, creep=creep, **_mean_motion(body, y),
        tolerance=2.0 * body.share * slip_distance / T**2,
    )  # fmt: skip
    if not body.rolls:
        lean = 2.0 * block_lean(ratio, slope) / T**2
        return replace(case, tolerance=case.tolerance + lean, allowance=lean)
    a = GRAVITY * math.sin(slope) / (1.0 + k)
    return replace(case, expected=a, expected_spin=a, spin_tolerance=2.0 / (1.0 + k) * slip_distance / T**2)


def sliding_case(law: str, body: Body, scale: float) -> InclineCase:
    """``body`` on the slope where it would need SLIDE_MARGIN of the law's static coefficient: it slides."""
    p = dry_limit_parameters(scale)
    mu_s, mu_k = dry_coefficients(law, p)
    slope = slope_for(body, SLIDE_MARGIN * mu_s)
    y = final_state(*planar_body(body, law, p, slope))
    s, c = math.sin(slope), math.cos(slope)
    slip_rate = GRAVITY * (s - mu_s * c / body.share)  # the slowest: the law at its peak
    tolerance = 2.0 * GRAVITY * c * _band_time(law, p, slip_rate) / DURATION
    motion = _mean_motion(body, y)
    del motion["slip"]  # no creep to compare it with
    case = InclineCase(law, body.name, "slides", scale, slope, GRAVITY * (s - mu_k * c), tolerance=tolerance, **motion)
    if not body.rolls:
        return case
    k = body.inertia_ratio
    return replace(case, expected_spin=mu_k * GRAVITY * c / k, spin_tolerance=tolerance / k)


GROUP = "Friction dry limits on an incline"


def shrinks(base: InclineCase, fine: InclineCase) -> bool:
    """Whether the finer regularisation's errors are at most half the base's, or within what is not the law's."""
    floor = fine.allowance + NUMERICAL_FLOOR
    return all(f <= max(0.5 * b, floor) for b, f in ((base.error, fine.error), (base.spin_error, fine.spin_error)))


def incline_row(cases: list[InclineCase]) -> Check:
    """One report row: a law, a body and a regime at every scale of SCALES (errors as the regularisation shrinks)."""
    first = cases[0]
    verb = first.regime if first.body != BLOCK.name else ("sticks" if first.regime == "rolls" else "slides")
    margin = ROLL_MARGIN if first.regime == "rolls" else SLIDE_MARGIN
    expected = f"a {first.expected:.4f}"
    obtained = "a err " + " -> ".join(f"{c.error:.1e}" for c in cases)
    tolerance = " -> ".join(f"{c.tolerance + NUMERICAL_FLOOR:.1e}" for c in cases)
    if math.isfinite(first.expected_spin):
        expected += f", R alpha {first.expected_spin:.4f}"
        obtained += "; R alpha err " + " -> ".join(f"{c.spin_error:.1e}" for c in cases)
        tolerance += "; " + " -> ".join(f"{c.spin_tolerance + NUMERICAL_FLOOR:.1e}" for c in cases)
    scales = " -> ".join(f"{c.scale:g}" for c in cases)
    passed = all(c.passed for c in cases) and all(shrinks(a, b) for a, b in itertools.pairwise(cases))
    return Check(
        GROUP, f"{first.law}: {first.body} {verb} at {margin:g} mu_s ({math.degrees(first.slope):.2f} deg; "
        f"regularisation x {scales})", expected + " m/s^2", obtained, tolerance, passed,
    )  # fmt: skip


def frictionless_row() -> Check:
    """Without friction (law "none", its own dry limit) every body slides at g sin(theta) and does not spin."""
    p, slope = dry_limit_parameters(1.0), FRICTIONLESS_SLOPE
    expected = GRAVITY * math.sin(slope)
    worst = 0.0
    for body in BODIES:
        motion = _mean_motion(body, final_state(*planar_body(body, "none", p, slope)))
        worst = max(worst, abs(motion["measured"] - expected), abs(motion.get("measured_spin", 0.0)))
    return Check(
        GROUP, f"none: sphere, disc and block slide without spin ({math.degrees(slope):.2f} deg)",
        f"a {expected:.4f}, R alpha 0 m/s^2", f"max err {worst:.1e}", f"{NUMERICAL_FLOOR:g}", worst <= NUMERICAL_FLOOR,
    )  # fmt: skip


def incline_cases(law: str) -> list[list[InclineCase]]:
    """Every body rolling (sticking) and sliding under ``law``, each at every scale of SCALES."""
    return [[case(law, body, scale) for scale in SCALES] for body in BODIES for case in (rolling_case, sliding_case)]


def incline_checks() -> list[Check]:
    """The validation rows: every law, body and regime; the sphere in space."""
    planar = [incline_row(cases) for law in CHECKED_LAWS for cases in incline_cases(law)]
    return [frictionless_row(), *planar, *(row for law in CHECKED_LAWS for row in spatial_rows(law))]


@dataclass(frozen=True)
class SpatialCase:
    """The sphere in space against the planar sphere (straight down) or against rolling (across the slope)."""

    law: str
    regime: str  # "rolls", "slides" (straight down) or "rolls across"
    planar: tuple[float, float]  # the planar sphere's mean (a, R alpha) [m/s^2]; rolling across: the exact ones
    spatial: tuple[float, float]  # the sphere in space's (across: a and the change of its lateral speed)
    lateral: float  # the largest of |z| [m] and the tilt Euler parameters |e1|, |e2| (across: |z - w0 T| [m])
    tolerance: float  # [m/s^2]


def spatial_case(law: str, regime: str) -> SpatialCase:
    """The sphere in space at scale 1 on the slope of the planar ``regime`` ("rolls" or "slides", straight down),
    or rolling across the slope at LATERAL_SPEED ("rolls across")."""
    p = dry_limit_parameters(1.0)
    T = DURATION
    planar = (rolling_case if regime != "slides" else sliding_case)(law, SPHERE, 1.0)
    ratio = ROLL_MARGIN * dry_coefficients(law, p)[0] if regime != "slides" else 0.0
    across = LATERAL_SPEED if regime == "rolls across" else 0.0
    sphere = spatial_sphere(
        law, p, planar.slope, (0.0, 0.0, across), (across / RADIUS, 0.0, 0.0), settled_bristles(law, ratio, p)
    )
    states = sampled_states(*sphere, 400.0)
    y = states[-1]
    a = 2.0 * y[0] / T**2
    if across:
        lateral_change = (y[9] - across) / T  # [m/s^2]: the lateral speed must not change
        return SpatialCase(
            law, regime, (planar.expected, 0.0), (a, lateral_change), abs(y[2] - across * T), planar.tolerance
        )
    spin = 2.0 * RADIUS * rolling_angle(states) / T**2
    tilt = max(abs(y[2]), abs(y[4]), abs(y[5]))
    return SpatialCase(law, regime, (planar.measured, planar.measured_spin), (a, spin), tilt, SPATIAL_AGREEMENT)


def dead_band(law: str, p: np.ndarray) -> float:
    """The largest slip speed at which the law gives no friction (Ambrosio: v0; 0 for the others), to rounding."""
    grid = _speed_grid(p)
    idle = np.flatnonzero([friction_coefficient(law, v, p) <= 0.0 for v in grid])
    if idle.size == 0:
        return 0.0
    low, high = grid[idle[-1]], grid[min(idle[-1] + 1, grid.size - 1)]
    for _ in range(60):  # bisect the edge of the band between two grid speeds
        middle = 0.5 * (low + high)
        low, high = (middle, high) if friction_coefficient(law, middle, p) <= 0.0 else (low, middle)
    return float(high)


def flat_slide_row(law: str) -> Check:
    """The sphere sliding with sidespin on flat ground: its slip keeps its first direction (any isotropic law
    decelerates it along itself) until it rolls, at v0 - 2/7 s0 whatever the law (the angular momentum about the
    contact plane's line under the centre is kept: friction acts in that plane at depth R). A law with a dead
    band stops slipping anywhere in it, so the final velocity may differ by 2/7 of the band."""
    p = dry_limit_parameters(1.0)
    states = sampled_states(*spatial_sphere(law, p, 0.0, FLAT_VELOCITY, FLAT_SPIN), 200.0)
    slips = np.array([contact_slip(y) for y in states])
    expected = np.array(FLAT_VELOCITY)[[0, 2]] - SPHERE.share * slips[0]
    error = float(np.linalg.norm(states[-1][[7, 9]] - expected))
    sliding = np.linalg.norm(slips, axis=1) > 1e-3 * np.linalg.norm(slips[0])
    moving, first = slips[sliding], slips[0]
    cross = moving[:, 0] * first[1] - moving[:, 1] * first[0]  # the 2D cross product: |s| |s0| sin(turn)
    turned = np.abs(cross) / (np.linalg.norm(moving, axis=1) * np.linalg.norm(first))
    tolerance = SPHERE.share * dead_band(law, p) + NUMERICAL_FLOOR
    return Check(
        "Friction dry limits: the sphere in space",
        f"{law}: sliding with sidespin on flat ground keeps its slip's direction, then rolls at v0 - 2/7 s0",
        f"({expected[0]:.4f}, {expected[1]:.4f}) m/s; slip direction fixed",
        f"error {error:.1e} m/s; slip turns {turned.max():.1e} rad", f"{tolerance:.1e} m/s; 1e-9 rad",
        error <= tolerance and turned.max() <= 1e-9,
    )  # fmt: skip


def spatial_rows(law: str) -> list[Check]:
    """The sphere in space: straight down it is the planar sphere (rolling and sliding) with no lateral motion;
    rolling across the slope it keeps its lateral speed and rolls down at 5/7 g sin(theta)."""
    straight = [spatial_case(law, regime) for regime in ("rolls", "slides")]
    gap = max(abs(a - b) for case in straight for a, b in zip(case.planar, case.spatial, strict=True))
    lateral = max(case.lateral for case in straight)
    across = spatial_case(law, "rolls across")
    error, change = abs(across.spatial[0] - across.planar[0]), abs(across.spatial[1])
    group = "Friction dry limits: the sphere in space"
    return [
        Check(
            group, f"{law}: straight down (rolls, slides) as the planar sphere; no lateral motion",
            "planar a, R alpha; lateral 0", f"max difference {gap:.1e} m/s^2; lateral {lateral:.1e}",
            f"{SPATIAL_AGREEMENT:g} m/s^2; 1e-12", gap <= SPATIAL_AGREEMENT and lateral <= 1e-12,
        ),
        Check(
            group, f"{law}: rolling across at {LATERAL_SPEED} m/s keeps its lateral speed",
            f"a {across.planar[0]:.4f} m/s^2, lateral speed constant",
            f"a err {error:.1e}; lateral speed change / T {change:.1e} m/s^2, |z - w0 T| {across.lateral:.1e} m",
            f"{across.tolerance + NUMERICAL_FLOOR:.1e}; {NUMERICAL_FLOOR:g}; 1e-9",
            error <= across.tolerance + NUMERICAL_FLOOR and change <= NUMERICAL_FLOOR and across.lateral <= 1e-9,
        ),
        flat_slide_row(law),
    ]  # fmt: skip
