"""Period-1 gaits: step-to-step maps, Newton on their fixed points, Floquet multipliers, continuation.

Poincaré section: just after a heel strike. Its coordinates are the independent post-impact variables
(see each rigid walker's ``section_names``): the impact fixes the others (the swing angle is minus the
stance angle; for the simplest walker the swing rate is cos(2 theta) times the stance rate; the rimless
wheel's stance angle is pi/N), so their multipliers are exactly zero and are dropped by working in
section coordinates. The rigid multipliers are the eigenvalues of the step map's Jacobian by central
differences with relative step ``FD_STEP`` (truncation ~ h^2 ~ 1e-10, integration noise ~ 1e-12 / h ~
1e-7 relative at worst; measured agreement with the simplest walker's variational equations: 1e-8).

The compliant model has no instantaneous impact: its section is the touchdown of the new leading foot
(the recorded heel strike: its penetration crosses 0 upward, located to 1e-12 s), where the rates are still
the pre-impact ones. Its step map restarts the compiled integrator from a full state lifted from reduced
section coordinates and follows it to the next heel strike (:class:`TouchdownSection`: the coordinates,
what is dropped and why, the relabelling of the legs). Newton on that map, with a central-difference
Jacobian, finds stable and unstable gaits alike (:func:`compliant_limit_cycle`). Accuracy, measured on the
round-foot walker and Goswami's compass: the map is integrated by DOP853 at rtol 1e-13, atol 1e-15, where
its noise floor (the change of the adaptive step sequence and of the located events with the start point,
:func:`noise_floor`) is 1e-11 (it is 2e-10 at rtol 1e-12, 6e-8 with dopri5 at 1e-11); Newton's tolerance is
``COMPLIANT_TOLERANCE`` = 1e-10, reached in 1 or 2 iterations from a settled start and in 4 from the rigid
unstable cycle (residuals 5e-13 to 7e-12). The relative difference step ``COMPLIANT_FD_STEP`` = 1e-5
balances noise / h ~ 1e-6 against truncation ~ h^2 ~ 1e-7 (a step of 1e-3 already moves the leading
multipliers by 3e-3); the multipliers agree to 3e-6 between steps of 3e-5, 1e-5 and 3e-6, and to 2e-5 with
a least-squares fit along a perturbed run. Goswami's unstable short-step gait (rigid: period 0.58203 s,
multiplier 4.288) exists in the compliant model (0.58193 s, 4.277): Newton finds it from the rigid cycle
with ``settle_steps = 0``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from biped_sim.config import Config
from biped_sim.errors import ConfigError
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.planar import IMPACT_SPEED, N_MODE_COLUMNS, PlanarSystem, foot_kinematics, state_size
from biped_sim.rigid.models import RigidWalker, SimplestWalker, initial_state, rigid_walker
from biped_sim.rigid.stepping import RigidStep, rigid_step
from biped_sim.simulate import simulate
from biped_sim.walkers import BuiltModel, build_model

RIGID_TOLERANCE = 1e-10
COMPLIANT_TOLERANCE = 1e-10  # 10 x the compliant step map's noise floor (module docstring)
FD_STEP = 1e-6
MAX_NEWTON = 30
SETTLE_STEPS = 30
STABILITY_MARGIN = 1e-9  # |lambda| < 1 - margin counts as stable


@dataclass
class LimitCycle:
    """A period-1 fixed point of the step map and its multipliers."""

    dynamics: str
    walker: str
    slope: float
    converged: bool
    iterations: int
    residual: float
    section_names: tuple[str, ...]
    section_point: np.ndarray
    fixed_point: dict[str, float]
    touchdown: dict[str, float]
    step_period: float
    step_length: float
    jacobian: np.ndarray
    multipliers: np.ndarray
    tolerance: float
    notes: list[str] = field(default_factory=list)

    @property
    def max_multiplier_modulus(self) -> float:
        return float(np.max(np.abs(self.multipliers))) if len(self.multipliers) else math.nan

    @property
    def stable(self) -> bool:
        return bool(self.converged and self.max_multiplier_modulus < 1.0 - STABILITY_MARGIN)

    @property
    def speed(self) -> float:
        return self.step_length / self.step_period if self.step_period > 0 else math.nan

    def to_json(self) -> dict[str, Any]:
        """The JSON document of ``biped-sim limit-cycle --json``."""
        order = np.argsort(-np.abs(self.multipliers))
        return {
            "dynamics": self.dynamics,
            "walker": self.walker,
            "slope": self.slope,
            "converged": self.converged,
            "iterations": self.iterations,
            "residual": self.residual,
            "tolerance": self.tolerance,
            "section": list(self.section_names),
            "fixed_point": self.fixed_point,
            "touchdown": self.touchdown,
            "step_period": self.step_period,
            "step_length": self.step_length,
            "speed": self.speed,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers[order]],
            "max_multiplier_modulus": self.max_multiplier_modulus,
            "stable": self.stable,
            "notes": self.notes,
        }


class StepFailedError(RuntimeError):
    """The walker fell or stalled during a step of the map."""


# --- rigid ---------------------------------------------------------------------------------------------------


def rigid_map(walker: RigidWalker, z: np.ndarray) -> tuple[np.ndarray, RigidStep]:
    """The step-to-step map on the section: post-impact coordinates -> the next ones."""
    step = rigid_step(walker, walker.from_section(np.asarray(z, dtype=float)))
    if step.status != "strike" or step.x_plus is None:
        raise StepFailedError(f"the rigid {walker.name} {step.status} during the step")
    return walker.to_section(step.x_plus), step


def map_jacobian(func: Callable[[np.ndarray], np.ndarray], z: np.ndarray, step: float = FD_STEP) -> np.ndarray:
    """Central-difference Jacobian; each coordinate perturbed by step * max(1, |z_i|)."""
    n = len(z)
    jac = np.zeros((n, n))
    for i in range(n):
        h = step * max(1.0, abs(z[i]))
        dz = np.zeros(n)
        dz[i] = h
        jac[:, i] = (func(z + dz) - func(z - dz)) / (2.0 * h)
    return jac


def newton_fixed_point(
    func: Callable[[np.ndarray], np.ndarray],
    z0: np.ndarray,
    tolerance: float,
    max_iter: int = MAX_NEWTON,
    fd_step: float = FD_STEP,
) -> tuple[np.ndarray, bool, int, float]:
    """Newton on F(z) = P(z) - z with a finite-difference Jacobian (relative step ``fd_step``); damped when a
    full step fails.

    Returns (z, converged, iterations, residual |P(z) - z|_inf).
    """
    z = np.asarray(z0, dtype=float)
    residual = math.inf
    for iteration in range(1, max_iter + 1):
        f = func(z) - z
        residual = float(np.max(np.abs(f)))
        if residual <= tolerance:
            return z, True, iteration - 1, residual
        jac = map_jacobian(func, z, fd_step) - np.eye(len(z))
        delta = np.linalg.lstsq(jac, -f, rcond=None)[0]
        scale = 1.0
        while True:
            try:
                candidate = z + scale * delta
                new_residual = float(np.max(np.abs(func(candidate) - candidate)))
                if new_residual < residual or scale < 1e-3:
                    break
            except StepFailedError:
                pass
            scale *= 0.5
            if scale < 1e-3:
                return z, False, iteration, residual
        z = candidate
    residual = float(np.max(np.abs(func(z) - z)))
    return z, residual <= tolerance, max_iter, residual


def settle(step_map: Callable[[np.ndarray], np.ndarray], z: np.ndarray, steps: int) -> np.ndarray:
    """Iterate the map ``steps`` times from z (a walk toward a stable cycle); stop at the last good point."""
    for _ in range(steps):
        try:
            z_next = step_map(z)
        except StepFailedError:
            break
        if not np.all(np.isfinite(z_next)):
            break
        z = z_next
    return z


def rigid_limit_cycle(
    config: Config, guess: dict[str, float] | None = None, settle_steps: int = SETTLE_STEPS
) -> LimitCycle:
    """Period-1 fixed point of the rigid model of ``config.walker`` and its multipliers.

    The initial guess is ``guess`` (the four README keys), else the config's initial state, else (for the
    rigid_limit_cycle start) a generic post-impact state. The guess first walks ``settle_steps`` steps, so
    that Newton starts near the stable cycle when there is one (Newton from the raw guess if that fails);
    ``settle_steps = 0`` finds the cycle nearest the guess, stable or not.
    """
    rigid = config if config.dynamics == "rigid" else config.model_copy(update={"dynamics": "rigid"})
    walker = rigid_walker(rigid)
    if guess is not None:
        starts = [walker.state_from_legs(guess)]
    elif config.simulation.initial == "rigid_limit_cycle":
        starts = _generic_starts(walker)
    else:
        starts = [initial_state(rigid, walker)]

    def step_map(z: np.ndarray) -> np.ndarray:
        return rigid_map(walker, z)[0]

    found = None
    for start in starts:
        z0 = walker.to_section(start)
        for z_start in (settle(step_map, z0, settle_steps), z0) if settle_steps else (z0,):
            try:
                found = newton_fixed_point(step_map, z_start, RIGID_TOLERANCE)
                _, step = rigid_map(walker, found[0])
            except StepFailedError:
                found = None
                continue
            if found[1]:
                break
        if found is not None and found[1]:
            break
    if found is None:
        raise ConfigError("simulation.initial", f"no rigid limit cycle: the rigid {walker.name} falls from the guess")
    z, converged, iterations, residual = found
    jac = map_jacobian(step_map, z)
    x_plus = walker.from_section(z)
    touchdown = walker.legs_state(np.concatenate([step.x_minus[: walker.n_q][::-1], step.x_minus[walker.n_q :][::-1]]))
    return LimitCycle(
        dynamics="rigid",
        walker=walker.name,
        slope=walker.slope,
        converged=converged,
        iterations=iterations,
        residual=residual,
        section_names=walker.section_names,
        section_point=z,
        fixed_point=walker.legs_state(x_plus),
        touchdown=touchdown,
        step_period=step.period,
        step_length=step.length,
        jacobian=jac,
        multipliers=np.linalg.eigvals(jac),
        tolerance=RIGID_TOLERANCE,
        notes=[
            "section just after heel strike; coordinates " + ", ".join(walker.section_names),
            f"multipliers: central differences, relative step {FD_STEP:g}; the coordinates the impact fixes "
            "(zero multipliers) are not section coordinates",
            "touchdown: the state just before the strike, relabelled (stance = the leg touching down)",
        ],
    )


def _generic_starts(walker: RigidWalker) -> list[np.ndarray]:
    """Post-impact states typical of passive gaits (rates scaled by sqrt(g / l)), tried when no guess is given."""
    scale = math.sqrt(walker.gravity / walker.leg_length)
    if walker.name == "rimless_wheel":
        return [walker.from_section(np.array([-k * scale])) for k in (1.0, 0.5, 2.0)]
    return [
        np.array([angle, -angle, -k * scale, -0.4 * k * scale]) for angle, k in ((0.25, 0.36), (0.2, 0.2), (0.3, 0.5))
    ]


def rigid_limit_cycle_initial(config: Config) -> dict[str, float]:
    """The rigid model's period-1 fixed point as a compliant run's initial state (the four README keys)."""
    cycle = rigid_limit_cycle(config)
    if not cycle.converged:
        raise ConfigError(
            "simulation.initial", f"rigid_limit_cycle: Newton did not converge (residual {cycle.residual:.1e})"
        )
    return cycle.fixed_point


__all__ = [
    "COMPLIANT_TOLERANCE",
    "RIGID_TOLERANCE",
    "LimitCycle",
    "StepFailedError",
    "map_jacobian",
    "newton_fixed_point",
    "rigid_limit_cycle",
    "rigid_limit_cycle_initial",
    "rigid_map",
]


# --- compliant -----------------------------------------------------------------------------------------------

COMPLIANT_METHOD = "dop853"  # at tight tolerances it is faster and 10x less noisy than dopri5 on the step map
COMPLIANT_RTOL = 1e-13
COMPLIANT_ATOL = 1e-15
COMPLIANT_FD_STEP = 1e-5
CONTACT_MULTIPLIER_FLOOR = 1e-6  # |lambda| below this: at the finite-difference resolution, i.e. zero
COMPLIANT_SETTLE_STEPS = 20
MAP_HORIZON = 10.0  # [sqrt(l / g)] a step not ended by then has stalled (periods are about 2 sqrt(l / g))
NOISE_PROBES = 4  # map evaluations that measure the noise floor at the fixed point
NOISE_PROBE_STEP = 1e-8  # their relative offset: the map is linear there to 1e-16
TOUCHDOWN_KEYS = ("stance_angle", "swing_angle", "stance_rate", "swing_rate")


def _rotate(angle: float, v: np.ndarray) -> np.ndarray:
    """A(angle) v: a body-frame vector in the slope frame."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _cross(omega: float, v: np.ndarray) -> np.ndarray:
    """omega x v in the plane."""
    return omega * np.array([-v[1], v[0]])


@dataclass
class CompliantStep:
    """One evaluation of the compliant step map."""

    z_next: np.ndarray  # section coordinates at the next heel strike
    period: float  # [s]
    length: float  # [m] contact point of the new striking foot minus that of the previous one


class TouchdownSection:
    """The compliant compass walker's Poincaré section at heel strike, in reduced coordinates.

    The section is the touchdown of the new leading foot A (its penetration crosses 0 upward). The full
    state has two bodies' (x, y, phi) and rates (12), the bristles, the work integrals and the contact
    modes. Reduced coordinates drop: the 4 hip-joint constraints (position and velocity, satisfied exactly
    by :meth:`lift`, which places the hip and hangs the legs from it), the translation along the slope (the
    map is invariant to it: the hip is put at x = 0), the section condition (A's penetration = 0 fixes
    the hip height), and the work integrals (they do not act on the motion). What is left:

    * stance_angle, swing_angle, stance_rate, swing_rate: leg A (touching down) and leg B (trailing);
    * hip_vx, hip_vy: the hip velocity (rolling is not imposed: the trailing foot may slip and sink);
    * trailing_impact_speed: the approach velocity remembered by the trailing foot B since its last
      touchdown (a bounce, if it bounced), which the Hunt-Crossley-type laws use while B is loaded;
    * trailing_bristle (LuGre only): B's bristle deflection.

    The striking foot's modes are set as the touchdown event sets them (``update_modes``): armed,
    touching, remembered approach velocity = its approach velocity in the lifted state, bristle relaxed
    (0). The trailing foot is armed and touching when it penetrates; otherwise it is in the air behind
    its partner, where the scuffing guard (if on) disarms it. The walker's legs are identical, so after a
    step the new striking foot is read as A again (:meth:`project` takes its index): the relabelling.
    """

    def __init__(self, config: Config, model: BuiltModel) -> None:
        system = model.system
        if not (
            isinstance(system, PlanarSystem)
            and system.body_mass.shape[0] == 2
            and system.joint_bodies.tolist() == [[0, 1]]
            and system.foot_body.tolist() == [0, 1]
            and system.foot_partner.tolist() == [1, 0]
            and system.body_mass[0] == system.body_mass[1]
            and system.body_inertia[0] == system.body_inertia[1]
        ):
            raise ConfigError(
                "walker.kind", "the compliant limit cycle needs the planar compass walker (two identical legs)"
            )
        self.system = system
        self.hip_in_body = system.joint_points[0, :2].copy()
        self.centre_from_hip = system.foot_center[0] - self.hip_in_body
        self.radius = float(system.foot_radius[0])
        self.lugre = config.friction.model == "lugre"
        self.guard = config.contact.scuffing_guard
        self.names = (
            "stance_angle",
            "swing_angle",
            "stance_rate",
            "swing_rate",
            "hip_vx",
            "hip_vy",
            "trailing_impact_speed",
        ) + (("trailing_bristle",) if self.lugre else ())
        self.integrator = config.integrator.model_copy(
            update={"method": COMPLIANT_METHOD, "adaptive": True, "rtol": COMPLIANT_RTOL, "atol": COMPLIANT_ATOL}
        )
        self.horizon = MAP_HORIZON * math.sqrt(config.walker.leg_length / config.gravity)

    def lift(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(y, modes) of the section point z; foot 0 (body 0) is the striking foot, the hip at x = 0."""
        angles, rates, hip_velocity = z[0:2], z[2:4], z[4:6]
        hip = np.array([0.0, self.radius - _rotate(angles[0], self.centre_from_hip)[1]])
        y = np.zeros(state_size(self.system))
        for body in (0, 1):
            arm = _rotate(angles[body], self.hip_in_body)  # centre of mass -> hip
            y[3 * body : 3 * body + 2] = hip - arm
            y[3 * body + 2] = angles[body]
            y[6 + 3 * body : 6 + 3 * body + 2] = hip_velocity - _cross(rates[body], arm)
            y[6 + 3 * body + 2] = rates[body]
        if self.lugre:
            y[13] = z[7]
        modes = np.zeros((2, N_MODE_COLUMNS))
        modes[0] = (1.0, 1.0, foot_kinematics(y, self.system, 0)[1])
        trailing_down = foot_kinematics(y, self.system, 1)[0] > 0.0
        modes[1] = (1.0 if trailing_down or not self.guard else 0.0, 1.0 if trailing_down else 0.0, z[6])
        return y, modes

    def project(self, y: np.ndarray, modes: np.ndarray, striking_foot: int) -> np.ndarray:
        """Section coordinates of a heel-strike state (y, modes) whose striking foot is ``striking_foot``."""
        legs = (striking_foot, 1 - striking_foot)
        angles = [y[3 * b + 2] for b in legs]
        rates = [y[6 + 3 * b + 2] for b in legs]
        hip_velocity = np.mean(
            [
                y[6 + 3 * b : 6 + 3 * b + 2] + _cross(y[6 + 3 * b + 2], _rotate(y[3 * b + 2], self.hip_in_body))
                for b in legs
            ],
            axis=0,
        )
        bristle = [y[12 + legs[1]]] if self.lugre else []
        return np.array([*angles, *rates, *hip_velocity, modes[legs[1], IMPACT_SPEED], *bristle])

    def step(self, z: np.ndarray) -> CompliantStep:
        """The step map from z: integrate from the lifted state to the next heel strike and project it."""
        y0, modes0 = self.lift(np.asarray(z, dtype=float))
        run = integrate_model(
            self.system, y0, modes0, self.integrator, self.horizon, 1.0 / self.horizon, max_strikes=1,
            initial_stance_foot=0,
        )  # fmt: skip
        if len(run.strike_t) == 0:
            reason = "stalled" if run.status == "walking" else run.status
            raise StepFailedError(f"the compliant walker {reason} before its next heel strike")
        foot = int(run.strike_foot[0])
        y1 = run.strike_y[0]
        length = foot_kinematics(y1, self.system, foot)[3] - foot_kinematics(y0, self.system, 0)[3]
        return CompliantStep(self.project(y1, run.strike_modes[0], foot), float(run.strike_t[0]), float(length))

    def legs(self, z: np.ndarray) -> dict[str, float]:
        """The four README keys of a section point (the touchdown state, stance = leg A)."""
        return {name: float(z[self.names.index(name)]) for name in TOUCHDOWN_KEYS}


def touchdown_guesses(
    config: Config, section: TouchdownSection, guess: dict[str, float] | None, settle: int
) -> list[np.ndarray]:
    """Section points to start Newton from: touchdowns of a ``simulate`` run from the guess.

    The run starts from ``guess`` (the four README keys, just after a heel strike), else the config's
    initial state (which may be the rigid limit cycle) and walks ``settle`` + 1 steps at the config's
    integrator settings. Returns its last touchdown (near the stable gait when there is one) and, when
    ``settle`` > 0 and the run got further than that, its first touchdown (nearest the guess).
    """
    data = config.model_dump(mode="json")
    data["simulation"]["max_steps"] = settle + 1
    data["simulation"]["t_end"] = (settle + 2) * section.horizon
    if guess is not None:
        data["simulation"]["initial"] = dict(guess)
    run = simulate(Config.model_validate(data)).run
    if len(run.strike_t) == 0:
        raise ConfigError("simulation.initial", f"the compliant walker {run.status} before its first heel strike")
    touchdowns = [
        section.project(run.strike_y[k], run.strike_modes[k], int(run.strike_foot[k])) for k in range(len(run.strike_t))
    ]
    return [touchdowns[-1], touchdowns[0]] if len(touchdowns) > 1 else touchdowns


def noise_floor(step_map: Callable[[np.ndarray], np.ndarray], z: np.ndarray, jacobian: np.ndarray) -> float:
    """Integration noise of the step map at z: max |P(z + dz) - P(z) - J dz| over a few tiny random dz.

    With |dz| ~ NOISE_PROBE_STEP the map is linear to ~1e-16, so what remains is the change of the adaptive
    step sequence and of the event location with the start point: the resolution of P.
    """
    rng = np.random.default_rng(0)
    base = step_map(z)
    worst = 0.0
    for _ in range(NOISE_PROBES):
        dz = NOISE_PROBE_STEP * np.maximum(1.0, np.abs(z)) * rng.choice((-1.0, 1.0), size=len(z))
        worst = max(worst, float(np.max(np.abs(step_map(z + dz) - base - jacobian @ dz))))
    return worst


def compliant_limit_cycle(
    config: Config, guess: dict[str, float] | None = None, settle_steps: int = COMPLIANT_SETTLE_STEPS
) -> LimitCycle:
    """Period-1 gait of the compliant model: Newton on its step map between heel strikes; multipliers.

    ``guess`` (else the config's initial state, else the rigid limit cycle when the config says so) walks
    ``settle_steps`` steps (see :func:`touchdown_guesses`); Newton starts from the last touchdown, then from
    the first. ``settle_steps = 0`` finds the cycle nearest the guess, stable or not.
    """
    model = build_model(config)
    section = TouchdownSection(config, model)

    def step_map(z: np.ndarray) -> np.ndarray:
        return section.step(z).z_next

    found = None
    for z_start in touchdown_guesses(config, section, guess, settle_steps):
        try:
            attempt = newton_fixed_point(step_map, z_start, COMPLIANT_TOLERANCE, fd_step=COMPLIANT_FD_STEP)
        except StepFailedError:
            continue
        if found is None or attempt[3] < found[3]:
            found = attempt
        if found[1]:
            break
    if found is None:
        raise ConfigError("simulation.initial", "no compliant limit cycle: the walker falls from every start")
    z, converged, iterations, residual = found
    step = section.step(z)
    jacobian = map_jacobian(step_map, z, COMPLIANT_FD_STEP)
    multipliers = np.linalg.eigvals(jacobian)
    noise = noise_floor(step_map, z, jacobian)
    legs = section.legs(z)
    return LimitCycle(
        dynamics="compliant",
        walker=config.walker.kind,
        slope=config.ground.slope,
        converged=converged,
        iterations=iterations,
        residual=residual,
        section_names=section.names,
        section_point=z,
        fixed_point=legs,
        touchdown=legs,
        step_period=step.period,
        step_length=step.length,
        jacobian=jacobian,
        multipliers=multipliers,
        tolerance=COMPLIANT_TOLERANCE,
        notes=[
            "compliant section: touchdown of the new leading foot (its penetration crosses 0); the fixed point "
            "is the touchdown state (pre-impact rates: the impact takes time), stance = the leg touching down",
            "section coordinates " + ", ".join(section.names) + "; dropped: the joint constraints (exact in the "
            "lift), the translation along the slope, the section condition (the hip height), the work integrals",
            f"step map: {section.integrator.method} at rtol {section.integrator.rtol:g}, atol "
            f"{section.integrator.atol:g}; its noise floor at the fixed point is {noise:.1e} (Newton tolerance "
            f"{COMPLIANT_TOLERANCE:g})",
            f"multipliers: central differences, relative step {COMPLIANT_FD_STEP:g}; "
            + contact_multiplier_note(multipliers),
        ],
    )


def contact_multiplier_note(multipliers: np.ndarray) -> str:
    """Which multipliers are the contact's: those at the finite-difference resolution (zero)."""
    zero = int(np.sum(np.abs(multipliers) < CONTACT_MULTIPLIER_FLOOR))
    return (
        f"one per section coordinate ({len(multipliers)}; the rigid touchdown section has 3, the compliant one adds "
        f"the hip velocity, the trailing leg's angle (its foot's sinkage) and its impact-speed memory); {zero} are "
        f"below {CONTACT_MULTIPLIER_FLOOR:g}, i.e. zero: contact perturbations forgotten within the step"
    )


def limit_cycle(config: Config, guess: dict[str, float] | None = None, settle_steps: int | None = None) -> LimitCycle:
    """The period-1 gait of ``config`` with its own dynamics (rigid or compliant).

    ``settle_steps``: steps walked from the guess before Newton (None: each model's default; 0: the cycle
    nearest the guess, stable or not).
    """
    if config.dynamics == "rigid":
        return rigid_limit_cycle(config, guess, SETTLE_STEPS if settle_steps is None else settle_steps)
    return compliant_limit_cycle(config, guess, COMPLIANT_SETTLE_STEPS if settle_steps is None else settle_steps)


# --- compliant -> rigid convergence ----------------------------------------------------------------------------

CONVERGE_LEVELS = 5
CONVERGE_STEPS = 20


@dataclass
class ConvergenceRow:
    """The compliant gait at one contact setting against the rigid gait."""

    stiffness: float
    restitution: float
    bristle_stiffness: float
    status: str
    touchdown_difference: float  # max |compliant - rigid| over the four touchdown variables
    period_difference: float  # compliant - rigid step period [s]
    settled: float  # change of the touchdown state over the last compliant step
    slip: float  # stance-foot slip over the last step [m]


def converge(
    config: Config, levels: int = CONVERGE_LEVELS, steps: int = CONVERGE_STEPS
) -> tuple[LimitCycle, list[ConvergenceRow]]:
    """The compliant gait approaching the rigid one as the contact stiffens, dissipates and stops slipping.

    Level k (0-based): contact stiffness 10^k times the config's (Hertz or explicit), restitution
    0.3 / sqrt(10)^k, and LuGre friction (mu_k 1.0, mu_s 1.2) whose bristle stiffness sigma0 = 1e4 * 10^k
    per metre (damping sigma1 = 20 sqrt(sigma0 / 1e4)): LuGre sticks elastically instead of creeping as
    the regularised laws do, so the slip vanishes with sigma0. Each compliant run starts on the rigid limit
    cycle and walks ``steps`` steps; its last touchdown state and step period are compared with the rigid
    touchdown (the pre-impact state, relabelled) and period.
    """
    from biped_sim.walkers.model import contact_stiffness

    rigid = rigid_limit_cycle(config)
    rigid_touchdown = np.array([rigid.touchdown[k] for k in TOUCHDOWN_KEYS])
    base_stiffness = contact_stiffness(config)
    rows = []
    for k in range(levels):
        data = config.model_dump(mode="json")
        stiffness = base_stiffness * 10.0**k
        restitution = 0.3 / math.sqrt(10.0) ** k
        sigma0 = 1e4 * 10.0**k
        data["contact"].update(stiffness=stiffness, materials=None, restitution=restitution)
        data["friction"].update(
            model="lugre", mu_kinetic=1.0, mu_static=1.2, sigma0=sigma0, sigma1=20.0 * math.sqrt(sigma0 / 1e4)
        )
        data["simulation"].update(initial=rigid.fixed_point, max_steps=steps, t_end=max(200.0, config.simulation.t_end))
        result = simulate(Config.model_validate(data))
        states = result.heel_strike_states
        if result.status != "walking" or len(states) < 3:
            rows.append(
                ConvergenceRow(stiffness, restitution, sigma0, result.status, math.nan, math.nan, math.nan, math.nan)
            )
            continue
        touchdowns = np.array([[s[key] for key in TOUCHDOWN_KEYS] for s in states])
        rows.append(
            ConvergenceRow(
                stiffness=stiffness,
                restitution=restitution,
                bristle_stiffness=sigma0,
                status=result.status,
                touchdown_difference=float(np.max(np.abs(touchdowns[-1] - rigid_touchdown))),
                period_difference=float(result.step_periods[-1] - rigid.step_period),
                settled=float(np.max(np.abs(touchdowns[-1] - touchdowns[-2]))),
                slip=float(result.summary["slip_per_step"][-1]),
            )
        )
    return rigid, rows


# --- an independent route to the multipliers, and the period-doubling slope ------------------------------------


def simplest_variational_jacobian(walker: SimplestWalker, z: np.ndarray) -> np.ndarray:
    """Step-map Jacobian of the simplest walker from the variational equations (not finite differences).

    Phi' = Df(x) Phi along the flow, the saltation through the strike guard g = theta_st + theta_sw
    (the event time moves with the state), then the impact's Jacobian, in section coordinates.
    """
    from scipy.integrate import solve_ivp

    step = rigid_step(walker, walker.from_section(z))
    if step.status != "strike":
        raise StepFailedError(f"the simplest walker {step.status}")

    def augmented(_t: float, y: np.ndarray) -> np.ndarray:
        x, phi = y[:4], y[4:].reshape(4, 4)
        return np.concatenate([walker.rhs(x), (walker.jacobian(x) @ phi).ravel()])

    x0 = walker.from_section(z)
    y0 = np.concatenate([x0, np.eye(4).ravel()])
    sol = solve_ivp(augmented, (0.0, step.period), y0, method="DOP853", rtol=1e-12, atol=1e-12)
    x_minus, phi = sol.y[:4, -1], sol.y[4:, -1].reshape(4, 4)
    f = walker.rhs(x_minus)
    grad = np.array([1.0, 1.0, 0.0, 0.0])
    saltation = np.eye(4) - np.outer(f, grad) / (grad @ f)
    full = walker.impact_jacobian(x_minus) @ saltation @ phi
    # d(from_section)/dz and the section rows (theta_st, thetadot_st)
    theta, theta_d = z
    lift = np.array(
        [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [-2.0 * math.sin(2.0 * theta) * theta_d, math.cos(2.0 * theta)]]
    )
    return full[[0, 2]] @ lift


def continue_cycle(config: Config, slope: float, guess: dict[str, float]) -> LimitCycle:
    """The rigid period-1 cycle at another slope, Newton started from ``guess`` (no settling)."""
    data = config.model_dump(mode="json")
    data["ground"]["slope"] = slope
    return rigid_limit_cycle(Config.model_validate(data), guess, settle_steps=0)


def flip_margin(cycle: LimitCycle) -> float:
    """1 + the most negative real multiplier (<= 0 once the period-1 gait has flipped); 1 if none is real."""
    real = [m.real for m in cycle.multipliers if abs(m.imag) < 1e-12]
    return min(real) + 1.0 if real else 1.0


def period_doubling_slope(
    config: Config, low: float, high: float, step: float = 5e-4, tolerance: float = 1e-7
) -> tuple[float, LimitCycle]:
    """Slope in [low, high] where a multiplier of the period-1 gait leaves the unit circle through -1.

    Natural continuation from ``low`` (the config's cycle there must not have flipped) in increments of
    ``step``, each solution the next guess, until the flip margin changes sign; then bisection to
    ``tolerance``. Returns the slope and the cycle just past it.
    """
    lower = continue_cycle(config, low, rigid_limit_cycle(config).fixed_point)
    if flip_margin(lower) <= 0:
        raise ValueError(f"period_doubling_slope: the gait has already flipped at slope {low}")
    slope = low
    while True:
        slope = min(slope + step, high)
        upper = continue_cycle(config, slope, lower.fixed_point)
        if not upper.converged:
            raise ValueError(f"period_doubling_slope: continuation lost the cycle at slope {slope}")
        if flip_margin(upper) <= 0:
            break
        if slope >= high:
            raise ValueError(f"period_doubling_slope: no flip between slopes {low} and {high}")
        lower = upper
    return bisect_flip(config, lower, upper, tolerance)


def bisect_flip(
    config: Config, lower: LimitCycle, upper: LimitCycle, tolerance: float = 1e-7
) -> tuple[float, LimitCycle]:
    """Bisection on the flip margin between a cycle that has not flipped and one that has."""
    a, b = lower.slope, upper.slope
    while b - a > tolerance:
        mid = 0.5 * (a + b)
        cycle = continue_cycle(config, mid, lower.fixed_point)
        if flip_margin(cycle) > 0:
            a, lower = mid, cycle
        else:
            b, upper = mid, cycle
    return 0.5 * (a + b), upper
