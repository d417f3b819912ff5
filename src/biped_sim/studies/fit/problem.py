"""A fit problem: config keys, a reference of measured steps, and the weighted residual of one simulation.

Each evaluation simulates the config with the parameters set, only as far as the last reference step
(``simulation.max_steps``), in minimal coordinates when the config is planar (the same walker by
construction; its step times agree with the planar formulation's to about 1e-7 s, far below any measured
spread, at a third of the cost). Its outcome (:class:`Outcome`) is what the residuals need: the strike
times, contact points and touchdown angles. Model steps are counted from the release (step j lasts from
strike j - 1 to strike j, the release being strike 0); reference step k meets model step
``skip + origin_offset + k`` (:attr:`~biped_sim.io.references.Reference.origin_offset`).

The residual of a target (one quantity at one step) is ``(model - mean) / sigma``, sigma the standard
error of the mean, ``std / sqrt(n_trials)`` (1 in the quantity's unit when a single-quantity reference
gives no std). A walker that falls, diverges or times out before a step has no value there: its
residual is the finite penalty ``PENALTY_SCALES * scale * (2 - reached) / sigma``, ``scale`` the
target's magnitude and ``reached`` in [0, 1] how far (in time) it got towards that step, so the
penalty shrinks as the walker gets further.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from pydantic import ValidationError

from biped_sim.config import Config, derive, set_dotted
from biped_sim.errors import ConfigError, quote
from biped_sim.io.references import MAX_STEPS, MEASURED_UNITS, Reference
from biped_sim.multibody.dispatch import system_foot_contact
from biped_sim.simulate import simulate, study_formulation
from biped_sim.studies.fit.parameters import FitParameter, check_parameters

PENALTY_SCALES = 2.0  # a missing step costs 2 to 4 of its target's magnitude (see the module docstring)
ANGLE_SCALE = 0.1  # rad: the smallest magnitude a missing angle is charged at
EVALUATION_SAMPLE_RATE = 10.0  # Hz: a fit reads only the strike states, which do not depend on sampling
REACH_MARGIN = 2.0  # an evaluation may run for this many times the reference's duration before giving up


@dataclass(frozen=True)
class Outcome:
    """What residuals need from a run (plain data, so it pickles and stores in a checkpoint).

    ``times[j]`` and ``x[j]`` are the time [s] and contact point along the slope [m] of strike j (0: the
    release); ``stance[j - 1]``, ``swing[j - 1]`` the touchdown angles at strike j [rad]; how it ended and
    how far it got [s].
    """

    times: tuple[float, ...]
    x: tuple[float, ...]
    stance: tuple[float, ...]
    swing: tuple[float, ...]
    status: str
    t_reached: float

    @property
    def strikes(self) -> int:
        return len(self.times) - 1

    def value(self, quantity: str, step: int) -> float:
        """``quantity`` of model step ``step`` (from the release), NaN if the walker never completed it."""
        if not 1 <= step <= self.strikes:
            return math.nan
        period = self.times[step] - self.times[step - 1]
        length = self.x[step] - self.x[step - 1]
        return {
            "step_period": period,
            "step_length": length,
            "step_speed": length / period if period > 0 else math.nan,
            "stance_angle": self.stance[step - 1],
            "swing_angle": self.swing[step - 1],
        }[quantity]

    def to_json(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in vars(self).items()}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Outcome:
        return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in data.items()})


def _release_x(result: Any) -> float:
    """Contact point of the initial stance foot (foot 0) at the release, where the run has a built model."""
    model = getattr(result, "model", None)
    if model is None or not hasattr(model, "y0"):
        return math.nan
    return float(system_foot_contact(model.y0, model.system, 0)[2])


def outcome_of(result: Any) -> Outcome:
    """The :class:`Outcome` of a simulated run (compliant or rigid)."""
    steps = result.steps
    n = len(steps.strike_time)
    x = np.full(n + 1, math.nan)
    x[0] = _release_x(result)
    if n:
        strike_y = getattr(getattr(result, "run", None), "strike_y", None)
        if strike_y is not None:
            system = result.model.system
            x[1:] = [system_foot_contact(strike_y[k], system, int(steps.foot[k]))[2] for k in range(n)]
        else:  # a rigid run: the advances of its step table, from strike 1
            x[1:] = np.concatenate([[0.0], np.cumsum(steps.length[:-1])])
    return Outcome(
        times=(0.0, *map(float, steps.strike_time)),
        x=tuple(map(float, x)),
        stance=tuple(map(float, steps.stance_angle)),
        swing=tuple(map(float, steps.swing_angle)),
        status=str(result.status),
        t_reached=float(result.t_final),
    )


def simulate_outcome(config_data: dict[str, Any]) -> Outcome:
    """Simulate a resolved config (plain data, so it pickles to a worker); a config the schema refuses (a value
    inside the bounds that another rule forbids) is an outcome that got nowhere, never an exception."""
    try:
        result = simulate(Config.model_validate(config_data))
    except (ConfigError, ValidationError) as exc:
        return Outcome((0.0,), (math.nan,), (), (), f"invalid: {str(exc).splitlines()[0][:120]}", 0.0)
    return outcome_of(result)


@dataclass(frozen=True)
class Target:
    """One measured value the fit matches: a quantity at a reference step, its mean and the mean's std error."""

    quantity: str
    step: int  # in the reference's numbering
    model_step: int  # counted from the release
    mean: float
    sigma: float  # std / sqrt(n_trials), or 1 (unit weight)
    n_trials: int

    @property
    def scale(self) -> float:
        """The magnitude a missing value is charged at."""
        return abs(self.mean) if MEASURED_UNITS[self.quantity] != "rad" else max(abs(self.mean), ANGLE_SCALE)


def reference_targets(reference: Reference, skip: int, quantities: tuple[str, ...] | None) -> tuple[Target, ...]:
    """The targets of ``reference`` (of the named quantities; all by default); ConfigError for a zero std."""
    if unknown := [q for q in quantities or () if q not in MEASURED_UNITS]:
        raise ConfigError("quantities", f"unknown quantity {quote(unknown[0])}; known: {', '.join(MEASURED_UNITS)}")
    measured = [m for m in reference.measured() if quantities is None or m.quantity in quantities]
    if not measured:
        raise ConfigError(str(reference.path), "holds no measured step quantities to fit (only published errors?)")
    missing = sorted(set(quantities or ()) - {m.quantity for m in measured})
    if missing:
        raise ConfigError("quantities", f"{missing[0]} is not in {reference.path}")
    unweighted = [m.quantity for m in measured if m.std is None]
    if unweighted and len(measured) > 1:
        raise ConfigError(f"{reference.path}: std", f"{unweighted[0]} has no std: several quantities need a std each")
    offset, out = skip + reference.origin_offset, []
    for m in measured:
        for i, (step, mean, n) in enumerate(zip(m.step_numbers, m.mean, m.trials, strict=True)):
            std = 1.0 if m.std is None else m.std[i]
            if std == 0:
                raise ConfigError(f"{reference.path}: std", f"{m.quantity} entry {i + 1} is 0; a fit weights by 1/std")
            out.append(Target(m.quantity, step, step + offset, mean, std / math.sqrt(n), n))
    return tuple(out)


@dataclass(frozen=True)
class FitProblem:
    """Fit ``parameters`` of ``config`` to ``reference``'s measured steps (``quantities``: all it gives)."""

    config: Config
    reference: Reference
    parameters: tuple[FitParameter, ...]
    skip: int = 0
    quantities: tuple[str, ...] | None = None
    targets: tuple[Target, ...] = field(init=False)

    def __post_init__(self) -> None:
        check_parameters(self.parameters)
        if self.skip < 0:
            raise ConfigError("skip", "must be at least 0")
        object.__setattr__(self, "targets", reference_targets(self.reference, self.skip, self.quantities))
        last = max(self.targets, key=lambda t: t.model_step)
        if last.model_step > MAX_STEPS:
            raise ConfigError(
                "skip", f"reference step {last.step:,} is model step {last.model_step:,}, past the {MAX_STEPS:,} "
                "steps a fit may simulate: it could never be matched",
            )  # fmt: skip
        if len(self.targets) < len(self.parameters):
            raise ConfigError(
                "parameters",
                f"{len(self.parameters)} parameters for {len(self.targets)} reference values: fit at most as many",
            )
        rigid = self.config.dynamics == "rigid"
        if rigid and any(t.model_step == 1 and t.quantity in ("step_length", "step_speed") for t in self.targets):
            raise ConfigError("quantities", "a rigid run has no contact point at the release: drop step 1's length")

    @property
    def weighted(self) -> bool:
        """Whether every target has a measured std (residuals then in units of their standard error)."""
        return all(m.std is not None for m in self.reference.measured() if m.quantity in self.used_quantities)

    @property
    def used_quantities(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(t.quantity for t in self.targets))

    @property
    def sigma(self) -> np.ndarray:
        return np.array([t.sigma for t in self.targets])

    @property
    def model_steps(self) -> int:
        """Heel strikes an evaluation simulates: as far as the last reference step."""
        return max(t.model_step for t in self.targets)

    @cached_property
    def guess_period(self) -> float:
        """A step period to tell when a step is due [s]: the reference's mean period, else a pendulum's half swing."""
        periods = [t.mean for t in self.targets if t.quantity == "step_period"]
        if periods:
            return float(np.mean(periods))
        return 0.5 * math.pi * math.sqrt(self.config.walker.leg_length / self.config.gravity)

    @property
    def evaluation_formulation(self) -> str:
        """The formulation an evaluation runs (:func:`~biped_sim.simulate.study_formulation`)."""
        return study_formulation(self.config)

    def values(self, u: np.ndarray | list[float]) -> dict[str, float]:
        """Parameter values at normalised point ``u``."""
        return {p.key: p.from_unit(float(x)) for p, x in zip(self.parameters, u, strict=True)}

    def config_at(self, values: dict[str, float]) -> Config:
        """The config with ``values`` set (what fitted.yaml holds)."""
        return derive(self.config, values)

    def steps_for(self, rows: np.ndarray | None) -> int:
        """The model steps a run needs for the targets ``rows`` (a mask; None: every target)."""
        if rows is None:
            return self.model_steps
        return max(t.model_step for t, kept in zip(self.targets, rows, strict=True) if kept)

    def evaluation_data(self, u: np.ndarray | list[float], steps: int | None = None) -> dict[str, Any]:
        """The config an evaluation runs (plain data): values set, stopping at model step ``steps`` (by default the
        last reference step; its end time the same whatever ``steps``, so that a run's first strikes are too)."""
        t_end = max(self.config.simulation.t_end, REACH_MARGIN * self.model_steps * self.guess_period)
        data = self.config.model_dump(mode="json")
        values = {
            **self.values(u),
            "simulation.max_steps": self.model_steps if steps is None else steps,
            "simulation.t_end": t_end,
            "output.sample_rate": EVALUATION_SAMPLE_RATE,
            "formulation.kind": self.evaluation_formulation,
        }
        for key, value in values.items():
            set_dotted(data, key, value)
        return data

    def model_values(self, outcome: Outcome) -> np.ndarray:
        """The model's value of each target (NaN where the walker never got there)."""
        return np.array([outcome.value(t.quantity, t.model_step) for t in self.targets])

    def residuals(self, outcome: Outcome) -> np.ndarray:
        """Weighted residuals per target; finite penalties for the steps the walker never reached."""
        model = self.model_values(outcome)
        out = np.empty(len(self.targets))
        for i, (target, value) in enumerate(zip(self.targets, model, strict=True)):
            if math.isfinite(value):
                out[i] = (value - target.mean) / target.sigma
            else:
                reached = min(max(outcome.t_reached / (target.model_step * self.guess_period), 0.0), 1.0)
                out[i] = PENALTY_SCALES * target.scale * (2.0 - reached) / target.sigma
        return out

    def key(self) -> str:
        """A hash of everything an evaluation depends on (a checkpoint is reused only for the same problem)."""
        content = {
            "config": self.config.hash(),
            "targets": [vars(t) for t in self.targets],
            "parameters": [vars(p) for p in self.parameters],
            "formulation": self.evaluation_formulation,
        }
        return hashlib.sha256(json.dumps(content, sort_keys=True).encode()).hexdigest()[:16]
