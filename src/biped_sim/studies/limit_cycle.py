"""The compliant walker's period-1 gait: Newton on its step map between heel strikes; multipliers.

The compliant model has no instantaneous impact: its section is the touchdown of the new leading foot
(the recorded heel strike: its penetration crosses 0 upward, located to 1e-12 s), where the rates are still
the pre-impact ones. Its step map restarts the compiled integrator from a full state lifted from reduced
section coordinates and follows it to the next heel strike (:class:`TouchdownSection`: the coordinates,
what is dropped and why, the relabelling of the legs). Newton on that map, with a central-difference
Jacobian, finds stable and unstable gaits alike (:func:`compliant_limit_cycle`). The map is integrated
by DOP853 at rtol 1e-13, atol 1e-15, where its noise floor (the change of the adaptive step sequence and
of the located events with the start point, :func:`noise_floor`, reported with every cycle) is well below
Newton's tolerance ``COMPLIANT_TOLERANCE``. The relative difference step ``COMPLIANT_FD_STEP`` balances
noise / h against the truncation error ~ h^2. Goswami's unstable short-step gait exists in the compliant
model too: Newton finds it from the rigid cycle with ``settle_steps = 0`` (a test).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from biped_sim.config import STATE_KEYS, Config, derive, parse_yaml
from biped_sim.contact.response import IMPACT_SPEED, N_MODE_COLUMNS
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.integrate.driver import integrate_model
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.multibody.formulation import COMPLIANT_LIMIT_CYCLE
from biped_sim.multibody.planar import foot_kinematics
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.limit_cycle import (
    LINES_NOTE,
    SETTLE_STEPS,
    LimitCycle,
    SearchFellError,
    StepFailedError,
    map_jacobian,
    newton_fixed_point,
    rigid_limit_cycle,
)
from biped_sim.rigid.space_cycle import space_limit_cycle
from biped_sim.simulate import prepare_model, simulate
from biped_sim.walkers import BuiltModel

COMPLIANT_TOLERANCE = 1e-10  # 10 x the compliant step map's noise floor (module docstring)
COMPLIANT_METHOD = "dop853"  # at tight tolerances it is faster and 10x less noisy than dopri5 on the step map
COMPLIANT_RTOL = 1e-13
COMPLIANT_ATOL = 1e-15
COMPLIANT_FD_STEP = 1e-5
CONTACT_MULTIPLIER_FLOOR = 1e-6  # |lambda| below this: at the finite-difference resolution, i.e. zero
COMPLIANT_SETTLE_STEPS = 20
MAP_HORIZON = 10.0  # [sqrt(l / g)] a step not ended by then has stalled (periods are about 2 sqrt(l / g))
NOISE_PROBES = 4  # map evaluations that measure the noise floor at the fixed point
NOISE_PROBE_STEP = 1e-8  # their relative offset: the map is linear there to 1e-16


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
        formulation = formulation_of(system)
        if not formulation.supports(COMPLIANT_LIMIT_CYCLE):
            raise ConfigError("formulation.kind", f"the compliant limit cycle is not available in {formulation.name!r}")
        if not (
            system.body_mass.shape[0] == 2
            and system.joint_bodies.tolist() == [[0, 1]]
            and system.foot_body.tolist() == [0, 1]
            and system.foot_partner.tolist() == [1, 0]
            and system.body_mass[0] == system.body_mass[1]
            and system.body_inertia[0] == system.body_inertia[1]
        ):
            raise ConfigError(
                "walker.kind", "the compliant limit cycle needs the planar compass walker (two identical legs)"
            )
        if config.ground.profile.kind != "flat":
            raise ConfigError("ground.profile", "a compliant limit cycle needs the flat ground (the same every step)")
        self.system = system
        self.layout = formulation.layout_of(system)
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
        layout = self.layout
        y = np.zeros(layout.size)
        for body in (0, 1):
            arm = _rotate(angles[body], self.hip_in_body)  # centre of mass -> hip
            y[layout.position(body)] = (*(hip - arm), angles[body])
            y[layout.velocity(body)] = (*(hip_velocity - _cross(rates[body], arm)), rates[body])
        if self.lugre:
            y[layout.bristle(1)] = z[7]
        modes = np.zeros((2, N_MODE_COLUMNS))
        modes[0, :3] = (1.0, 1.0, foot_kinematics(y, self.system, 0)[1])
        trailing_down = foot_kinematics(y, self.system, 1)[0] > 0.0
        modes[1, :3] = (1.0 if trailing_down or not self.guard else 0.0, 1.0 if trailing_down else 0.0, z[6])
        return y, modes

    def project(self, y: np.ndarray, modes: np.ndarray, striking_foot: int) -> np.ndarray:
        """Section coordinates of a heel-strike state (y, modes) whose striking foot is ``striking_foot``."""
        legs = (striking_foot, 1 - striking_foot)
        layout = self.layout
        angles = [y[layout.coordinate(b, "phi")] for b in legs]
        rates = [y[layout.rate(b, "omega")] for b in legs]
        hip_velocity = np.mean(
            [
                y[layout.velocity(b)][:2] + _cross(rate, _rotate(angle, self.hip_in_body))
                for b, angle, rate in zip(legs, angles, rates, strict=True)
            ],
            axis=0,
        )
        bristle = [*y[layout.bristle(legs[1])]] if self.lugre else []
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
        return {name: float(z[self.names.index(name)]) for name in STATE_KEYS}


def touchdown_guesses(
    config: Config, section: TouchdownSection, guess: dict[str, float] | None, settle: int
) -> list[np.ndarray]:
    """Section points to start Newton from: touchdowns of a ``simulate`` run from the guess.

    The run starts from ``guess`` (the four README keys, just after a heel strike), else the config's
    initial state (which may be the rigid limit cycle) and walks ``settle`` + 1 steps at the config's
    integrator settings. Returns its last touchdown (near the stable gait when there is one) and, when
    ``settle`` > 0 and the run got further than that, its first touchdown (nearest the guess).
    """
    walk = {"simulation.max_steps": settle + 1, "simulation.t_end": (settle + 2) * section.horizon}
    if guess is not None:
        walk["simulation.initial"] = dict(guess)
    run = simulate(derive(config, walk)).run
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
    model = prepare_model(config)
    section = TouchdownSection(config, model)

    def step_map(z: np.ndarray) -> np.ndarray:
        return section.step(z).z_next

    tried = "the touchdowns of a run from " + ("the guess" if guess is not None else "the config's initial state")
    tried += f" (after {settle_steps} steps and its first)" if settle_steps else ""
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
        raise SearchFellError("simulation.initial", f"no compliant limit cycle: the walker falls from {tried}")
    z, converged, iterations, residual = found
    step = section.step(z)
    jacobian = map_jacobian(step_map, z, COMPLIANT_FD_STEP)
    multipliers = np.linalg.eigvals(jacobian)
    noise = noise_floor(step_map, z, jacobian)
    legs = section.legs(z)
    rigid = rigid_walker(config.model_copy(update={"dynamics": "rigid"}))  # the same legs' geometry
    lines = rigid.leg_lines(rigid.state_from_legs(legs))
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
            LINES_NOTE,
        ],
        tried=tried,
        lines={"fixed_point": lines, "touchdown": lines},
    )


def contact_multiplier_note(multipliers: np.ndarray) -> str:
    """Which multipliers are the contact's: those at the finite-difference resolution (zero)."""
    zero = int(np.sum(np.abs(multipliers) < CONTACT_MULTIPLIER_FLOOR))
    return (
        f"one per section coordinate ({len(multipliers)}; the rigid touchdown section has 3, the compliant one adds "
        f"the hip velocity, the trailing leg's angle (its foot's sinkage) and its impact-speed memory); {zero} are "
        f"below {CONTACT_MULTIPLIER_FLOOR:g}, i.e. zero: contact perturbations forgotten within the step"
    )


def guess_keys(config: Config) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The keys a guess of ``config``'s gait may take: its initial-state keys (:meth:`Config.initial_keys`) and, in
    rigid dynamics, its Poincare section's coordinates (the compliant search starts from a run: the state only)."""
    if config.in_space:
        raise ArgumentError("guess", "a walker in space finds its gait without a guess (its scan)")
    section = rigid_walker(config).section_names if config.dynamics == "rigid" else ()
    return config.initial_keys(), section


def parse_guess(text: str | None, keys: tuple[str, ...], section: tuple[str, ...] = ()) -> dict[str, float] | None:
    """A guess of the gait from text: a YAML/JSON mapping of the walker's initial-state ``keys`` (the compass's four
    README keys, a kneed walker's eight) or of its ``section`` coordinates, or as many numbers in either's order
    (None for None); ArgumentError naming ``guess`` and listing the keys otherwise."""
    if text is None:
        return None
    try:
        value = parse_yaml(text, source="guess")
    except ConfigError as exc:
        raise ArgumentError("guess", exc.reason) from None
    if isinstance(value, list):
        names = next((names for names in (keys, section) if names and len(value) == len(names)), ())
        value = dict(zip(names, value, strict=True)) if names else None
    if not isinstance(value, dict) or set(value) not in [set(keys)] + ([set(section)] if section else []):
        expected = f"expected the {len(keys)} keys {', '.join(keys)} (or {len(keys)} numbers in that order)"
        if section:
            expected += f", or the section's {len(section)}: {', '.join(section)}"
        raise ArgumentError("guess", expected)
    names = tuple(value)
    if any(isinstance(value[k], bool) or not isinstance(value[k], int | float) for k in names):
        raise ArgumentError("guess", "values must be numbers")
    bad = [k for k in names if not math.isfinite(value[k])]
    if bad:
        raise ArgumentError("guess", f"{bad[0]} must be a finite number")
    return {k: float(value[k]) for k in names}


def limit_cycle(config: Config, guess: dict[str, float] | None = None, settle_steps: int | None = None) -> LimitCycle:
    """The period-1 gait of ``config`` with its own dynamics (rigid or compliant).

    ``settle_steps``: steps walked from the guess before Newton (None: each model's default; 0: the cycle
    nearest the guess, stable or not).
    """
    if config.in_space:  # its own rigid model and search (no guess: guess_keys refuses)
        return space_limit_cycle(config, SETTLE_STEPS if settle_steps is None else settle_steps)
    if config.dynamics == "rigid":
        if config.ground.profile.kind != "flat":  # the rigid step map reads the plane
            raise ConfigError("ground.profile", "a rigid limit cycle needs the flat ground (the same every step)")
        return rigid_limit_cycle(config, guess, SETTLE_STEPS if settle_steps is None else settle_steps)
    return compliant_limit_cycle(config, guess, COMPLIANT_SETTLE_STEPS if settle_steps is None else settle_steps)
