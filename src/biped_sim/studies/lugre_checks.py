"""LuGre against Canudas de Wit, Olsson, Astrom and Lischinsky (IEEE TAC 40(3), 1995, 419-425) (issue 28, item 7).

The paper's Table I: sigma0 = 1e5 N/m, sigma1 = sqrt(1e5) N s/m, sigma2 = 0.4 N s/m, Fc = 1 N, Fs = 1.5 N,
vs = 1e-3 m/s, on a unit mass. The project's LuGre is load-proportional (sigma0 and sigma1 per newton of
normal force, g(v) = mu_k + (mu_s - mu_k) exp(-(v/vs)^2)): under a normal force of 1 N with mu_k = Fc / 1 N and
mu_s = Fs / 1 N it is the paper's model term for term, so the checks call the project's compiled
``lugre_bristle_rate`` and ``lugre_friction`` with F_N = 1 N on a 1 kg mass driven by a force u(t):
m xdd = u - F, F = sigma0 z + sigma1 zdot + sigma2 v (scipy's Radau: the bristles are stiff).

What is sourced and what is not: the parameters are Table I. The set-ups of the experiments are as described
in the paper's text as reconstructed by A. Manurung (github.com/auralius/LuGre, demo1.m): presliding, a force
slowly ramped to 0.95 Fs, held, ramped to -0.95 Fs, held and ramped back; break-away, the force ramped at
different rates and the friction force read where the mass starts to slide. The ramp durations and the rates
of the paper's figures are not sourced (the reconstruction guesses them from the figures), so the checks
compare with analytic properties of the model instead of figure data:

* steady state: at a constant velocity v the bristles settle (zdot = 0) where the force is
  Fc + (Fs - Fc) exp(-(v/vs)^2) + sigma2 v;
* presliding: under slow loading (v << vs, g = Fs) the bristles follow the Dahl curve
  dz/dx = 1 - sigma0 sgn(v) z / Fs, so each ramp from force F_a to F_b moves the mass by
  (Fs / sigma0) ln((Fs - sgn F_a) / (Fs - sgn F_b)) (sgn: the ramp's direction): the loop is closed, its
  branches apart (hysteresis), and every displacement is of the order of the bristle length Fs / sigma0;
* break-away: the peak friction force along a ramp rises as the rate falls, towards Fs;
* frictional lag: with the velocity oscillating, 1e-3 (cos(w t) + 1.5) m/s at w = 1, 10, 25 rad/s (the
  reconstruction's Fig. 3), the force lags it: it is higher while the velocity rises than while it falls, the
  loop around the steady-state curve widens with w and closes onto the curve as w -> 0.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from biped_sim.contact.friction import friction_parameters, lugre_bristle_rate, lugre_friction
from biped_sim.studies.checks import Check
from biped_sim.studies.friction_checks import friction_coefficient

SIGMA0, SIGMA1, SIGMA2 = 1e5, math.sqrt(1e5), 0.4  # Table I: N/m, N s/m, N s/m
FC, FS, VS = 1.0, 1.5, 1e-3  # Table I: N, N, m/s
MASS = 1.0  # [kg]
NORMAL_FORCE = 1.0  # [N]: the load-proportional law is then the paper's
PRESLIDING_PEAK = 0.95 * FS  # [N] the presliding ramps' extremes
PRESLIDING_RATE = 0.1425  # [N/s] slow: the mass's velocity stays far below vs
PRESLIDING_HOLD = 5.0  # [s]
BREAKAWAY_RATES = (0.1, 0.3, 1.0, 3.0, 10.0, 30.0)  # [N/s] force rates of the break-away ramps
BREAKAWAY_SLOW_LIMIT = 0.02  # the slowest ramp breaks away within this fraction of Fs (the quasi-static limit)
PRESLIDING_TOLERANCE = 0.02  # relative, against the quasi-static Dahl curve (which neglects sigma1 zdot, v > 0)
STEADY_SPEEDS = (1e-4, 5e-4, 1e-3, 2e-3, 1e-2, 0.1)  # [m/s]
LAG_FREQUENCIES = (1.0, 10.0, 25.0)  # [rad/s] of the velocity oscillation 1e-3 (cos(w t) + 1.5) m/s
LAG_SLOW_LIMIT = 0.02  # [N] the slowest oscillation's largest departure from the steady-state curve


def paper_parameters() -> np.ndarray:
    """Table I in the project's parameter vector (mu_k = Fc, mu_s = Fs per newton of normal force)."""
    return friction_parameters(FC, FS, 1e-3, 1e-2, VS, 0.0, 0.0, SIGMA0, SIGMA1, SIGMA2)


def friction(v: float, z: float, p: np.ndarray) -> tuple[float, float]:
    """(F, zdot): the paper's friction force (opposing v, so the project's force negated) and bristle rate."""
    z_dot = lugre_bristle_rate(v, z, p)
    return -lugre_friction(v, z, z_dot, NORMAL_FORCE, p), z_dot


def steady_state_force(v: float) -> float:
    """The paper's steady-state curve Fc + (Fs - Fc) exp(-(v/vs)^2) + sigma2 v (v > 0)."""
    return FC + (FS - FC) * math.exp(-((v / VS) ** 2)) + SIGMA2 * v


def settled_force(v: float, p: np.ndarray) -> float:
    """The friction force once the bristles have settled at constant velocity ``v``: the bristle rate is linear
    in z at fixed v (and stable), so they settle where it vanishes (:func:`.friction_checks.friction_coefficient`)."""
    return friction_coefficient("lugre", v, p) * NORMAL_FORCE


@dataclass(frozen=True)
class Motion:
    """A driven run: times, displacement, velocity, friction force, applied force."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    friction: np.ndarray
    applied: np.ndarray


def driven_mass(applied: Callable[[float], float], t_end: float, p: np.ndarray, samples: int = 4001) -> Motion:
    """The unit mass at rest (bristles relaxed) pushed by ``applied(t)`` [N] until ``t_end``."""

    def rhs(t: float, s: np.ndarray) -> list[float]:
        f, z_dot = friction(s[1], s[2], p)
        return [s[1], (applied(t) - f) / MASS, z_dot]

    t = np.linspace(0.0, t_end, samples)
    with np.errstate(over="ignore"):  # Radau's finite-difference Jacobian grows its step factors past overflow
        sol = solve_ivp(
            rhs, (0.0, t_end), [0.0, 0.0, 0.0], method="Radau", t_eval=t, rtol=1e-9, atol=1e-13, max_step=0.05
        )
    if not sol.success:
        raise RuntimeError(f"LuGre check: the integration failed ({sol.message})")
    forces = np.array([friction(v, z, p)[0] for v, z in zip(sol.y[1], sol.y[2], strict=True)])
    return Motion(sol.t, sol.y[0], sol.y[1], forces, np.array([applied(ti) for ti in sol.t]))


def presliding_schedule() -> tuple[list[tuple[float, float]], float]:
    """The presliding ramps as (time, force) corners (ramp up, hold, down, hold, up, hold) and the end time."""
    ramp, full = PRESLIDING_PEAK / PRESLIDING_RATE, 2.0 * PRESLIDING_PEAK / PRESLIDING_RATE
    corners = [(0.0, 0.0), (ramp, PRESLIDING_PEAK)]
    for force in (-PRESLIDING_PEAK, PRESLIDING_PEAK):
        t = corners[-1][0] + PRESLIDING_HOLD
        corners += [(t, corners[-1][1]), (t + full, force)]
    corners.append((corners[-1][0] + PRESLIDING_HOLD, PRESLIDING_PEAK))
    return corners, corners[-1][0]


def dahl_displacement(start: float, end: float) -> float:
    """The quasi-static (Dahl) displacement of a ramp of the friction force from ``start`` to ``end`` [m]."""
    sign = 1.0 if end > start else -1.0
    return sign * FS / SIGMA0 * math.log((FS - sign * start) / (FS - sign * end))


@dataclass(frozen=True)
class PreslidingLoop:
    """The displacements [m] at the ends of the three ramps (measured, Dahl) and the loop's width at F = 0."""

    measured: tuple[float, float, float]
    dahl: tuple[float, float, float]
    width: float  # between the falling and the rising branch at zero force [m]
    largest: float  # largest |x| over the run [m]


def presliding_loop(p: np.ndarray | None = None) -> PreslidingLoop:
    """Force ramps 0 -> 0.95 Fs -> -0.95 Fs -> 0.95 Fs on the unit mass: the displacement at each ramp's end
    against the Dahl curve's, and the hysteresis (the falling and rising branches apart at zero force)."""
    corners, t_end = presliding_schedule()
    times, forces = np.array([c[0] for c in corners]), np.array([c[1] for c in corners])
    motion = driven_mass(lambda t: float(np.interp(t, times, forces)), t_end, paper_parameters() if p is None else p)
    ends = [float(np.interp(times[i] + PRESLIDING_HOLD, motion.t, motion.x)) for i in (1, 3, 5)]
    dahl, x = [], 0.0
    for a, b in ((0.0, PRESLIDING_PEAK), (PRESLIDING_PEAK, -PRESLIDING_PEAK), (-PRESLIDING_PEAK, PRESLIDING_PEAK)):
        x += dahl_displacement(a, b)
        dahl.append(x)
    falling = (motion.t > times[2]) & (motion.t < times[3])
    rising = (motion.t > times[4]) & (motion.t < times[5])
    at_zero = [float(np.interp(0.0, motion.applied[mask][::sign], motion.x[mask][::sign])) for mask, sign in
               ((falling, -1), (rising, 1))]  # fmt: skip
    return PreslidingLoop(
        (ends[0], ends[1], ends[2]), (dahl[0], dahl[1], dahl[2]), at_zero[0] - at_zero[1], float(np.abs(motion.x).max())
    )


def breakaway_force(rate: float, p: np.ndarray | None = None) -> float:
    """The friction force [N] where the unit mass, pushed by the applied force ``rate`` t, starts to slide: the
    first maximum of the friction force (it falls once the mass slides, towards Fc, and later the viscous
    sigma2 v would raise it again)."""
    t_end = 1.2 * FS / rate
    motion = driven_mass(lambda t: rate * t, t_end, paper_parameters() if p is None else p)
    falls = np.flatnonzero(np.diff(motion.friction) < 0.0)
    if falls.size == 0:
        raise RuntimeError(f"LuGre break-away at {rate} N/s: the mass did not slide by {t_end:.3g} s")
    return float(motion.friction[falls[0]])


def lag_loop(frequency: float, p: np.ndarray | None = None) -> tuple[float, float]:
    """The velocity 1e-3 (cos(w t) + 1.5) m/s imposed at ``frequency`` w [rad/s]: over the fourth period, the
    largest departure [N] of the force from the steady-state curve and the smallest (rising - falling) force
    difference [N] at equal velocity (positive: the force is higher while the velocity rises)."""
    p = paper_parameters() if p is None else p
    period = 2.0 * math.pi / frequency

    def speed(t: float) -> float:
        return 1e-3 * (math.cos(frequency * t) + 1.5)

    t = np.linspace(3.0 * period, 4.0 * period, 2001)
    sol = solve_ivp(
        lambda ti, z: [friction(speed(ti), z[0], p)[1]], (0.0, t[-1]), [0.0], method="Radau", t_eval=t, rtol=1e-10,
        atol=1e-16,
    )  # fmt: skip
    v = np.array([speed(ti) for ti in t])
    force = np.array([friction(vi, zi, p)[0] for vi, zi in zip(v, sol.y[0], strict=True)])
    departure = float(np.max(np.abs(force - np.array([steady_state_force(vi) for vi in v]))))
    falling, rising = slice(0, 1001), slice(1000, 2001)  # cos falls over the first half period, rises after
    probe = np.linspace(v.min(), v.max(), 52)[1:-1]
    up = np.interp(probe, v[rising], force[rising])
    down = np.interp(probe, v[falling][::-1], force[falling][::-1])
    return departure, float(np.min(up - down))


GROUP = "LuGre (Canudas de Wit et al. 1995, Table I)"


def steady_state_check() -> Check:
    """The settled force at each of STEADY_SPEEDS (both directions) against the paper's steady-state curve."""
    p = paper_parameters()
    gaps = [abs(abs(settled_force(s * v, p)) - steady_state_force(v)) for v in STEADY_SPEEDS for s in (1.0, -1.0)]
    speeds = ", ".join(f"{v:g}" for v in STEADY_SPEEDS)
    return Check(
        GROUP, f"steady state at +-v = {speeds} m/s", "Fc + (Fs - Fc) exp(-(v/vs)^2) + sigma2 v",
        f"max difference {max(gaps):.1e} N", "1e-9 N", max(gaps) <= 1e-9,
    )  # fmt: skip


def presliding_checks() -> list[Check]:
    """The presliding loop against the Dahl curve: the ramps' displacements, the loop's closure and width."""
    loop = presliding_loop()
    gaps = [abs(m - d) / abs(d) for m, d in zip(loop.measured, loop.dahl, strict=True)]
    peak = PRESLIDING_PEAK
    dahl_width = loop.dahl[0] + dahl_displacement(peak, 0.0) - (loop.dahl[1] + dahl_displacement(-peak, 0.0))
    closure = abs(loop.measured[2] - loop.measured[0])
    return [
        Check(
            GROUP, "presliding: displacement at the ramps' ends, +-0.95 Fs [um]",
            " / ".join(f"{1e6 * d:.3f}" for d in loop.dahl) + " (Dahl)",
            " / ".join(f"{1e6 * m:.3f}" for m in loop.measured), f"{PRESLIDING_TOLERANCE:.0%}",
            max(gaps) <= PRESLIDING_TOLERANCE,
        ),
        Check(
            GROUP, "presliding: the loop closes; its width at zero force [um]",
            f"closed; width {1e6 * dahl_width:.3f} (Dahl)",
            f"closure {1e6 * closure:.1e}; width {1e6 * loop.width:.3f}",
            f"closure 1e-3 of the loop; width {PRESLIDING_TOLERANCE:.0%}",
            closure <= 1e-3 * abs(loop.measured[0])
            and abs(loop.width - dahl_width) <= PRESLIDING_TOLERANCE * dahl_width,
        ),
    ]  # fmt: skip


def breakaway_check() -> Check:
    """The break-away force falls as the force rate rises, from Fs at slow rates (above Fc throughout)."""
    forces = [breakaway_force(rate) for rate in BREAKAWAY_RATES]
    falling = all(b < a for a, b in itertools.pairwise(forces))
    rates = ", ".join(f"{r:g}" for r in BREAKAWAY_RATES)
    return Check(
        GROUP, f"break-away force [N] at force rates {rates} N/s",
        f"falls as the rate rises, from Fs = {FS} (within {BREAKAWAY_SLOW_LIMIT:.0%}), above Fc",
        " / ".join(f"{f:.4f}" for f in forces), "-",
        falling and forces[0] >= (1.0 - BREAKAWAY_SLOW_LIMIT) * FS and min(forces) > FC and max(forces) <= FS,
    )  # fmt: skip


def lag_check() -> Check:
    """Frictional lag: the force is higher while the velocity rises; the loop widens with the frequency and
    closes onto the steady-state curve at the slowest."""
    loops = [lag_loop(w) for w in LAG_FREQUENCIES]
    widening = all(b[0] > a[0] for a, b in itertools.pairwise(loops))
    frequencies = ", ".join(f"{w:g}" for w in LAG_FREQUENCIES)
    return Check(
        GROUP, f"frictional lag, v = 1e-3 (cos(w t) + 1.5) m/s at w = {frequencies} rad/s: largest departure from "
        "the steady state [N]; rising minus falling force", f"widens with w, under {LAG_SLOW_LIMIT} at the slowest; "
        "rising > falling", " / ".join(f"{d:.4f}" for d, _ in loops) + "; min " + " / ".join(
            f"{g:.1e}" for _, g in loops), "-",
        widening and loops[0][0] <= LAG_SLOW_LIMIT and min(g for _, g in loops) > 0.0,
    )  # fmt: skip


def lugre_checks() -> list[Check]:
    """The validation rows: steady state, presliding hysteresis, break-away against the force rate, lag."""
    return [steady_state_check(), *presliding_checks(), breakaway_check(), lag_check()]
