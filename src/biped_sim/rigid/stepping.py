"""One rigid step by scipy: the slow reference that the compiled step map (:mod:`biped_sim.rigid.compiled`,
which every run and study takes) is tested against, and the limit cycles' ``engine="scipy"``.

The flow is integrated by scipy's DOP853 (8th order, 7th-order dense output) at rtol = atol = 1e-12.
Each guard phase ends at a downward zero crossing of its guard function, found by root finding on the
dense output (scipy's brentq, to 4 machine epsilon) and then polished by Newton steps on the exact flow
direction, dt = -g / (grad g . f), until |g| <= 1e-14: the heel strike is located to about 1e-12 in
time and state (the integration error), not to the step size. Falls (a leg past
``simulation.fall_leg_angle``, the hip on the ground) and stalls (no strike within ``MAX_STEP_TIME``
natural periods) end the step with a status instead of a strike. Pushes stop the flow at their times and
continue it after the velocity jump, in the same guard phase. On a ground profile the strike guard is the
swing foot's clearance above the profile (:mod:`biped_sim.rigid.ground`), sought once the swing foot has left
its mid-stance scuff (the plane's strike guard has become positive: the swing leg is ahead of the stance leg's
mirror image, the swing foot above the stance level); a riser hit ends the step ``tripped``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from biped_sim.rigid.ground import RISER_TOLERANCE, ProfileStrike
from biped_sim.rigid.step import ATOL, GUARD_TOLERANCE, MAX_STEP_TIME, RTOL, RigidStep
from biped_sim.rigid.tree import RigidWalker
from biped_sim.rigid.tree_kernels import FALL_HIP_FRACTION


def _guard_event(guard, direction: float):  # type: ignore[no-untyped-def]
    def event(_t: float, x: np.ndarray) -> float:
        return guard(x)

    event.terminal = True  # type: ignore[attr-defined]
    event.direction = direction  # type: ignore[attr-defined]
    return event


def _polish(walker: RigidWalker, guard, t: float, x: np.ndarray) -> tuple[float, np.ndarray]:  # type: ignore[no-untyped-def]
    """Newton on the guard along the flow: a few dt = -g / (grad g . f) steps of a Taylor expansion."""
    eps = 1e-7
    for _ in range(4):
        g = guard(x)
        if abs(g) <= GUARD_TOLERANCE:
            break
        f = walker.rhs(x)
        slope = (guard(x + eps * f) - guard(x - eps * f)) / (2 * eps)
        if slope == 0.0:
            break
        dt = -g / slope
        # second-order Taylor step of the flow over the (tiny) correction
        f_mid = walker.rhs(x + 0.5 * dt * f)
        x = x + dt * f_mid
        t += dt
    return t, x


def rigid_step(
    walker: RigidWalker,
    x_start: np.ndarray,
    sample_rate: float | None = None,
    pushes: Sequence[tuple[float, np.ndarray]] = (),
    profile: ProfileStrike | None = None,
) -> RigidStep:
    """Integrate one step from a post-impact state; sample it at ``sample_rate`` (per unit time) if given.

    The samples fall on the grid k / sample_rate of the step's own clock (t = 0 at its start) and are kept
    whatever the step's outcome (strike, fall or stall). ``pushes``: (time on the step's clock, impulse) in
    time order; the flow stops at each that comes before the step ends, the walker's ``hip_push`` makes the
    jump, and the same guard phase goes on (``RigidStep.pushes`` lists those applied; a sample at a
    push's time holds the state after it). ``profile``: the strike on a ground profile (None: the walker's own
    guard, on the plane); a swing foot below the profile when the strike is first sought, or one that meets a
    riser, ends the step ``tripped``.
    """
    from scipy.integrate import solve_ivp  # imported here: scipy.integrate costs 0.3 s of every CLI start-up

    scale = math.sqrt(walker.leg_length / walker.gravity)
    t_limit = MAX_STEP_TIME * scale
    fall_events = [_guard_event(lambda x, i=i: walker.fall_leg_angle - abs(x[i]), 0.0) for i in range(walker.n_q)] + [
        _guard_event(lambda x: walker.hip_height(x) - FALL_HIP_FRACTION * walker.leg_length, 0.0)
    ]
    t, x = 0.0, np.asarray(x_start, dtype=float)
    evals = 0
    accepted = 0
    samples_t: list[np.ndarray] = []
    samples_x: list[np.ndarray] = []
    applied: list[tuple[float, float, float]] = []
    stops: list[tuple[float, float]] = []

    def finish(step: RigidStep) -> RigidStep:
        # every outcome keeps its samples, counters and pushes (a run records the fall's trajectory too)
        step.accepted_steps = accepted
        step.pushes = applied
        step.stop_strikes = stops
        if samples_t:
            step.samples_t = np.concatenate(samples_t)
            step.samples_x = np.vstack(samples_x)
        return step

    phases = walker.guard_phases()
    n_own = len(phases)  # the walker's own phases; on a profile the last gives way to two of the profile's
    if profile is not None:
        plane_strike = phases[-1][1]
        phases = [*phases[:-1], ("swing_foot_out", lambda y: -plane_strike(y)), ("heel_strike", profile.clearance)]
    walker.begin_step()
    for index, (name, guard) in enumerate(phases):
        on_profile = profile is not None and index == len(phases) - 1
        if (index < n_own and walker.skip_phase(index, x)) or (name == "swing_foot_out" and guard(x) <= 0.0):
            continue  # the swing foot is already past its mid-stance scuff
        if on_profile and guard(x) < -RISER_TOLERANCE * walker.leg_length:  # below the profile: in a riser
            return finish(RigidStep("tripped", x_start, x, None, t, math.nan, evals))
        strike = _guard_event(guard, -1.0)
        while True:
            t_stop = min(pushes[len(applied)][0], t_limit) if len(applied) < len(pushes) else t_limit
            if t_stop > t:
                sol = solve_ivp(
                    lambda _t, y: walker.rhs(y), (t, t_stop), x, method="DOP853", rtol=RTOL, atol=ATOL,
                    events=[strike, *fall_events], dense_output=sample_rate is not None,
                )  # fmt: skip
                evals += sol.nfev
                accepted += len(sol.t) - 1
                if sample_rate is not None and sol.sol is not None:
                    _sample(sol, t, sample_rate, samples_t, samples_x)
                if sol.status == 1:  # an event: the guard or a fall
                    break
                t, x = float(sol.t[-1]), sol.y[:, -1]
                if sol.status != 0 or t_stop >= t_limit:  # no event: ran to the time limit
                    return finish(RigidStep("stalled", x_start, x, None, t, math.nan, evals))
            x = _push(walker, t, x, pushes[len(applied)][1], applied)
        if len(sol.t_events[0]) == 0:
            return finish(RigidStep("fell", x_start, sol.y[:, -1], None, sol.t[-1], math.nan, evals))
        t, x = float(sol.t_events[0][0]), sol.y_events[0][0]
        if on_profile and profile.tripped(x):  # type: ignore[union-attr]
            return finish(RigidStep("tripped", x_start, x, None, t, math.nan, evals))
        t, x = _polish(walker, guard, t, x)
        x_after = walker.after_phase(index, x) if index < n_own else x
        if not np.array_equal(x_after, x):  # a joint stop struck: book its plastic loss
            stops.append((t, walker.energy(x)[0] - walker.energy(x_after)[0]))
        x = x_after
    x_plus = walker.impact(x) if profile is None else profile.impact(x)
    return finish(RigidStep("strike", x_start, x, x_plus, t, walker.step_length(x_start, x), evals))


def _sample(sol, t: float, sample_rate: float, samples_t: list, samples_x: list) -> None:  # type: ignore[no-untyped-def]
    """Append the grid points k / sample_rate in [t, end of ``sol``) from its dense output."""
    t_end = sol.t[-1]
    grid = np.arange(math.ceil(t * sample_rate), math.floor(t_end * sample_rate) + 1) / sample_rate
    grid = grid[(grid >= t) & (grid < t_end)]
    if len(grid):
        samples_t.append(grid)
        samples_x.append(sol.sol(grid).T)


def _push(walker: RigidWalker, t: float, x: np.ndarray, impulse: np.ndarray, applied: list) -> np.ndarray:
    """The state after the push at t; appends its record (t, work = kinetic energy jump, ground normal impulse)."""
    x_after, ground_normal = walker.hip_push(x, impulse)
    applied.append((t, walker.energy(x_after)[0] - walker.energy(x)[0], ground_normal))
    return x_after
