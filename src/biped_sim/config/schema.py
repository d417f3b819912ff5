"""The configuration schema: every section, field, default, unit and validation rule (pydantic models)."""

from __future__ import annotations

import hashlib
import json
import math
from typing import Annotated, Any, Literal

import yaml
from pydantic import (
    BeforeValidator,
    Field,
    model_validator,
)

from biped_sim.config.base import IN_SPACE, FrictionModelName, NormalModelName, Strict
from biped_sim.config.description import LEG_KEYS
from biped_sim.config.space_description import SPACE_STATE_KEYS, SPACE_TORSO_KEYS
from biped_sim.config.space_form import in_space as described_in_space
from biped_sim.config.space_form import space_form
from biped_sim.config.walker_registry import capabilities, profile_refusal, refusal
from biped_sim.config.walker_schema import CompassWalker, WalkerConfig
from biped_sim.contact.profile import FlatProfile, GroundProfile, profile_support_error
from biped_sim.errors import quote


class GroundConfig(Strict):
    """The slope: a plane through the origin inclined downhill by ``slope``, shaped by ``profile`` in its frame."""

    slope: float = Field(0.02, gt=-math.pi / 2, lt=math.pi / 2, description="Downhill slope angle gamma [rad].")
    profile: GroundProfile = Field(default_factory=FlatProfile, description="Shape (biped_sim.contact.profile).")


class MaterialConfig(Strict):
    """Elastic constants of one contacting body."""

    youngs_modulus: float = Field(..., gt=0, description="Young's modulus E [Pa].")
    poisson_ratio: float = Field(..., ge=0, lt=0.5, description="Poisson ratio nu [-].")


class MaterialsConfig(Strict):
    """Foot and ground materials; the contact stiffness then follows from Hertz theory."""

    foot: MaterialConfig = Field(
        default_factory=lambda: MaterialConfig(youngs_modulus=50e6, poisson_ratio=0.45),
        description="Default: a polyurethane-like polymer foot.",
    )
    ground: MaterialConfig = Field(
        default_factory=lambda: MaterialConfig(youngs_modulus=10e9, poisson_ratio=0.3),
        description="Default: a hard (wood/laminate) floor.",
    )


IntegratorName = Literal["euler", "rk2", "rk4", "dopri5", "dop853", "radau", "bdf"]


class ContactConfig(Strict):
    """Normal contact force law (MODEL.md 3-4)."""

    model: NormalModelName = Field("flores", description="Normal force law.")
    stiffness: float | None = Field(
        None, gt=0, description="K [N/m^n]; if omitted, computed from `materials` and the foot radius (Hertz)."
    )
    materials: MaterialsConfig | None = Field(
        None,
        description="Young's moduli and Poisson ratios; default materials when neither this nor stiffness is given.",
    )
    exponent: float = Field(1.5, gt=0, description="Force exponent n (Hertz: 3/2). Kelvin-Voigt always uses 1.")
    restitution: float = Field(0.3, gt=0, le=1, description="Coefficient of restitution e.")
    damping: float | None = Field(
        None, ge=0, description="Kelvin-Voigt damping D [N s/m]; if omitted, from e and the walker's effective mass."
    )
    scuffing_guard: bool = Field(True, description="Ignore swing-foot scuffing at mid-stance (MODEL.md 3).")
    impact_velocity_floor: float = Field(
        1e-3,
        gt=0,
        description="Lower bound [m/s] on the remembered impact velocity (avoids division by ~0 on grazing contact).",
    )
    impact_memory: Literal["impact", "touchdown"] = Field(
        "impact",
        description="What the remembered impact velocity belongs to (Hunt-Crossley-type laws): 'impact' keeps it "
        "through a re-contact within recontact_time of the foot's lift-off (a rebound or micro-separation), taking "
        "the larger of the two approach velocities; 'touchdown' makes every touchdown a new impact (the behaviour "
        "before this option).",
    )
    recontact_time: float = Field(
        0.1,
        gt=0,
        description="Longest flight [s] after which a touchdown still continues the same impact (impact_memory: "
        "impact): longer than the rebounds of a heel strike, shorter than a swing.",
    )

    @model_validator(mode="after")
    def _one_stiffness_source(self) -> ContactConfig:
        if self.stiffness is not None and self.materials is not None:
            raise ValueError("stiffness: give either contact.stiffness or contact.materials, not both")
        return self


class FrictionConfig(Strict):
    """Tangential friction law (MODEL.md 5); each law reads the parameters it names."""

    model: FrictionModelName = Field("ambrosio", description="Friction law.")
    mu_kinetic: float = Field(0.6, ge=0, description="Kinetic coefficient mu_k.")
    mu_static: float = Field(0.8, ge=0, description="Static coefficient mu_s (Bengisu-Akay, Brown-McPhee, LuGre).")
    v0: float = Field(
        1e-3,
        gt=0,
        description="Stick threshold [m/s]: Threlfall/Ambrosio v0, Brown-McPhee v_t0, Coulomb regularisation width.",
    )
    v1: float = Field(1e-2, gt=0, description="Ambrosio full-slip velocity v1 [m/s] (> v0).")
    v_stribeck: float = Field(1e-3, gt=0, description="Stribeck velocity v_s [m/s] (Bengisu-Akay, LuGre).")
    stribeck_decay: float = Field(100.0, ge=0, description="Bengisu-Akay decay rate xi [s/m].")
    viscous: float = Field(0.0, ge=0, description="Viscous coefficient [N s/m] (Brown-McPhee mu_v).")
    sigma0: float = Field(1e4, gt=0, description="LuGre bristle stiffness per unit normal load sigma0 [1/m].")
    sigma1: float = Field(20.0, ge=0, description="LuGre bristle damping per unit normal load sigma1 [s/m].")
    sigma2: float = Field(0.0, ge=0, description="LuGre viscous coefficient sigma2 [N s/m].")
    spin_radius: float = Field(
        0.0,
        ge=0,
        description="Effective spin radius r_s [m] of the spin (drilling) friction torque about the contact normal, "
        "the law applied to the speed r_s omega_n (3 pi a / 16 for a Hertzian patch of radius a); 0 = none. "
        "Compliant spatial formulation only.",
    )

    @model_validator(mode="after")
    def _thresholds_ordered(self) -> FrictionConfig:
        if self.model == "ambrosio" and self.v1 <= self.v0:
            raise ValueError("v1: must be greater than friction.v0")
        if self.spin_radius > 0.0 and self.model in ("none", "lugre"):
            raise ValueError(
                f"spin_radius: needs a stateless friction law with friction (friction.model: {self.model})"
            )
        return self


class BaumgarteConfig(Strict):
    """Baumgarte stabilisation gains; alpha = beta = 0 is the standard method (MODEL.md 2)."""

    alpha: float = Field(10.0, ge=0, description="Velocity gain alpha [1/s].")
    beta: float = Field(10.0, ge=0, description="Position gain beta [1/s].")


class FormulationConfig(Strict):
    """Multibody formulation."""

    kind: Literal["planar", "spatial", "minimal"] = Field(
        "planar",
        description="'planar': (x, y, phi) per body; 'spatial': (r, Euler parameters) per body, 3D contact; "
        "'minimal': planar, hip position and one angle per body (no constraints; baumgarte unused).",
    )
    baumgarte: BaumgarteConfig = Field(default_factory=BaumgarteConfig)


MIN_RTOL = 100 * 2.220446049250313e-16  # as scipy's solve_ivp: tighter is below round-off


class IntegratorConfig(Strict):
    """Time integrator (MODEL.md 6)."""

    method: IntegratorName = Field("dopri5", description="Integration method.")
    dt: float = Field(1e-4, gt=0, description="Fixed step [s] (euler, rk2, rk4).")
    rtol: float = Field(
        1e-8,
        gt=0,
        le=1.0,
        description="Relative tolerance (adaptive methods), from 100 machine epsilons (below, the step control "
        "cannot reach it) to 1.",
    )
    atol: float = Field(1e-10, gt=0, description="Absolute tolerance (adaptive methods).")
    max_step: float = Field(1e-2, gt=0, description="Largest step [s] (adaptive methods).")
    adaptive: bool = Field(True, description="Step-size control; false runs dopri5/dop853 at fixed dt (order tests).")

    @model_validator(mode="after")
    def _reachable_tolerance(self) -> IntegratorConfig:
        if self.rtol < MIN_RTOL:
            raise ValueError(f"rtol: below 100 machine epsilons ({MIN_RTOL:.1e}), which the step control cannot reach")
        return self


def _not_a_boolean(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got {quote(value).lower()}")
    return value


Number = Annotated[float, BeforeValidator(_not_a_boolean)]  # YAML's true is not 1.0


class InitialState(Strict):
    """Leg angles from the slope normal, positive when the foot is downhill of the hip (docs/guide/model.md)."""

    stance_angle: float = Field(0.25, description="Stance leg angle theta_st [rad].")
    stance_rate: float = Field(-1.6, description="Stance leg angular rate [rad/s].")
    swing_angle: float = Field(-0.25, description="Swing leg angle theta_sw [rad].")
    swing_rate: float = Field(-0.5, description="Swing leg angular rate [rad/s].")


class Push(Strict):
    """An impulse on the hip (joint 0's point): an instantaneous velocity change consistent with the joints."""

    time: float = Field(..., ge=0, description="When [s]; before simulation.t_end.")
    impulse: tuple[float, float] | tuple[float, float, float] = Field(
        ...,
        description="[px, py] or [px, py, pz] [N s]; slope frame: x downhill (forward), y its normal (vertical), "
        "z = x cross y (lateral, the walker's right): a nonzero pz needs a walker in space.",
    )

    @property
    def lateral(self) -> float:
        """The lateral component pz [N s] (0 for a push given as [px, py])."""
        return self.impulse[2] if len(self.impulse) == 3 else 0.0


MAX_STEPS = 1_000_000_000  # heel strikes: more than any run within the integration budget can take


class SimulationConfig(Strict):
    """What to simulate and when to stop."""

    t_end: float = Field(15.0, gt=0, description="Simulated time [s].")
    max_steps: int | None = Field(
        None, gt=0, le=MAX_STEPS, description="Stop after this many heel strikes (none = run to t_end; at most 1e9)."
    )
    initial: InitialState | dict[str, Number] | Literal["rigid_limit_cycle"] = Field(
        default_factory=InitialState,
        union_mode="left_to_right",  # the README's keys (missing ones defaulted) before a described walker's own
        description="Initial leg angles and rates, or 'rigid_limit_cycle' to start on the rigid model's fixed point; "
        "a walker.description with several bodies per leg names its own keys (WalkerDescription.state_keys).",
    )
    fall_hip_height: float = Field(0.5, gt=0, lt=1, description="Fall when the hip is below this x leg_length.")
    fall_leg_angle: float = Field(1.4, gt=0, description="Fall when a leg is this far from the slope normal [rad].")
    max_wall_time: float | None = Field(
        None, gt=0, description="Wall-clock budget of one run [s], then status 'timeout' (none = no limit)."
    )
    pushes: list[Push] = Field(default_factory=list, description="Impulses on the hip, applied in time order.")


class OutputConfig(Strict):
    """Where and how densely results are written."""

    dir: str | None = Field(None, description="Run directory; default results/runs/<config stem>.")
    sample_rate: float = Field(1000.0, gt=0, description="Trajectory samples per simulated second [Hz].")


class Config(Strict):
    """A complete, validated simulation description."""

    dynamics: Literal["compliant", "rigid"] = Field(
        "compliant", description="'compliant' = penalty contact (the paper); 'rigid' = hybrid impulsive model."
    )
    walker: WalkerConfig = Field(default_factory=CompassWalker)
    gravity: float = Field(
        9.81, gt=0, le=1000.0, description="Gravitational acceleration g [m/s^2] (at most 1000: a walker, not a star)."
    )
    ground: GroundConfig = Field(default_factory=GroundConfig)
    contact: ContactConfig = Field(default_factory=ContactConfig)
    friction: FrictionConfig = Field(default_factory=FrictionConfig)
    formulation: FormulationConfig = Field(default_factory=FormulationConfig)
    integrator: IntegratorConfig = Field(default_factory=IntegratorConfig)
    simulation: SimulationConfig = Field(default_factory=SimulationConfig)
    output: OutputConfig = Field(default_factory=OutputConfig)

    @model_validator(mode="after")
    def _cross_checks(self) -> Config:
        if refused := refusal(self.walker.kind, self.dynamics, self.formulation.kind):
            raise ValueError(": ".join(refused))
        caps = capabilities(self.walker.kind)
        if self.simulation.pushes and not caps.pushes:
            raise ValueError(f"simulation.pushes: the {self.walker.kind} walker takes no pushes")
        if self.ground.profile.kind != "flat" and (reason := self.profile_refusal()):
            raise ValueError(f"ground.profile: {reason}")
        self._described_walker_checks()  # the walker before its start: a start's keys follow from its form
        self._initial_keys_match()
        if any(push.time >= self.simulation.t_end for push in self.simulation.pushes):
            raise ValueError("simulation.pushes: a push's time is not before simulation.t_end")
        in_space = (self.dynamics == "compliant" and self.formulation.kind == "spatial") or self.in_space
        if any(push.lateral for push in self.simulation.pushes) and not in_space:
            raise ValueError(
                "simulation.pushes: a lateral impulse (pz, the third component) needs a walker in space "
                "(formulation.kind: spatial, or rigid dynamics of a described walker in space)"
            )
        if reason := profile_support_error(self.ground, self.dynamics, self.friction.model):
            raise ValueError(f"ground.profile: {reason}")
        hertz = self.contact.materials is not None or self.dynamics == "compliant"
        if self.contact.stiffness is None and hertz and self.walker.point_feet:
            raise ValueError("contact.stiffness: required for point feet (every foot's radius is 0), Hertz needs R > 0")
        if self.friction.model != "none" and math.tan(abs(self.ground.slope)) > max(
            self.friction.mu_static, self.friction.mu_kinetic
        ):
            raise ValueError(
                "ground.slope: steeper than the friction cone (tan(slope) > friction coefficient), "
                "the stance foot cannot hold"
            )
        if self.friction.spin_radius > 0.0 and not (
            self.dynamics == "compliant" and self.formulation.kind == "spatial"
        ):
            raise ValueError("friction.spin_radius: only in space (dynamics: compliant, formulation.kind: spatial)")
        return self

    def _described_walker_checks(self) -> None:
        """A described walker's bodies all carry mass; its features in space only in the spatial formulation."""
        described = self.walker.description
        if described is None:
            return
        if self.in_space:  # the rigid model's form in space (its one-line refusal naming the field)
            form = space_form(described)
            if (form.leg.knee is not None or form.torso is not None) and self.dynamics == "compliant":
                raise ValueError(
                    "simulation.initial: a kneed walker or a torso in space starts its compliant run from its bodies' "
                    "angles (the rigid gait's start takes one-body legs and no torso)"
                )
            return
        in_space = self.dynamics == "compliant" and self.formulation.kind == "spatial"
        if not in_space and (features := described.features_in_space()):
            raise ValueError(f"{features[0]}: only in space ({IN_SPACE}); a planar or rigid model has it not")
        massless = described.massless_bodies()
        if self.dynamics == "rigid" and len(massless) < len(described.bodies):  # held by a locked joint, or light
            one_stop = {j.child for j in described.joints if len(j.stops) == 1}
            massless = [name for name in massless if name in one_stop]  # free while its joint swings: singular
        if massless:
            raise ValueError(
                f"walker.description.bodies.{massless[0]}.mass: a body needs mass (its own or a point mass)"
                + ("; rigid: or a locked joint (two stops at one angle)" if self.dynamics == "rigid" else "")
            )

    def _initial_keys_match(self) -> None:
        initial = self.simulation.initial
        if not isinstance(initial, dict):
            return
        expected, optional = self.initial_keys(), self.optional_initial_keys()
        required = set(expected) - set(optional)
        if not required <= set(initial) <= set(expected) or set(initial) == set(LEG_KEYS):
            also = f" (optional: {', '.join(optional)}; not given: 0)" if optional else ""
            if self._space_form_started() and not self.in_space:
                also += f"; or the rigid gait in space's {', '.join(SPACE_STATE_KEYS)}"
            raise ValueError(f"simulation.initial: expected the keys {', '.join(expected)}{also}")

    def profile_refusal(self) -> str | None:
        """Why the walker walks no ground profile other than flat (a one-line reason), or None: the registry's rule
        of its kind; a walker in space's rigid model reads the plane."""
        if self.dynamics == "rigid" and self.in_space:
            return "a walker in space walks on flat ground only with dynamics: rigid (profiles: dynamics: compliant)"
        return profile_refusal(self.walker.kind, self.dynamics)

    def _space_form_started(self) -> bool:
        """Whether a described walker with a feature of space runs compliant in the spatial formulation (started on
        the rigid gait in space by its keys or rigid_limit_cycle, else from its bodies' angles)."""
        described = self.walker.description
        in_space = described is not None and described_in_space(described)
        return in_space and self.dynamics == "compliant" and self.formulation.kind == "spatial"

    @property
    def in_space(self) -> bool:
        """Whether the walker is a walker in space of the rigid model's form (:mod:`.space_form`): its rigid
        dynamics the rigid model in space, its compliant run started on that model's gait (``simulation.initial``:
        ``rigid_limit_cycle`` or the gait's keys, ``SPACE_STATE_KEYS``) and built from that form. A described
        walker is in space when it has a feature only a model in space represents (a hip width, parts off the
        sagittal plane, a full inertia tensor, round feet other than arcs), in rigid dynamics or so started in the
        spatial formulation; the other trees in space start from their bodies' angles."""
        described = self.walker.description
        if self.dynamics == "rigid":
            return described is not None and described_in_space(described)
        initial = self.simulation.initial
        keys = isinstance(initial, dict) and set(initial) == set(SPACE_STATE_KEYS)
        return self._space_form_started() and (initial == "rigid_limit_cycle" or keys)

    def initial_keys(self) -> tuple[str, ...]:
        """The keys of ``simulation.initial``: a walker in space's gait keys, a described walker's own, else the
        README's four."""
        described = self.walker.description
        if self.in_space:
            return SPACE_STATE_KEYS + self.optional_initial_keys()
        return described.state_keys() if described is not None else LEG_KEYS

    def optional_initial_keys(self) -> tuple[str, ...]:
        """The keys of ``simulation.initial`` that may be left out: those of a described walker's bodies off the
        legs (a torso starts upright and at rest without them)."""
        described = self.walker.description
        if self.in_space:  # a torso's, by the rigid model's names
            return SPACE_TORSO_KEYS if space_form(described).torso is not None else ()  # type: ignore[arg-type]
        return described.off_leg_keys() if described is not None else ()

    def hash(self) -> str:
        """SHA-256 (16 hex digits) of the canonical resolved config, output location excluded."""
        data = self.model_dump(mode="json")
        data["output"].pop("dir", None)
        text = json.dumps(data, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def to_yaml(self) -> str:
        """The fully resolved config as YAML text (every default written out)."""
        return yaml.safe_dump(self.model_dump(mode="json"), sort_keys=False)
