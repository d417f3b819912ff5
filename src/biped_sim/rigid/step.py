"""One rigid step's result and the tolerances every rigid step map shares (compiled and scipy's reference).

A step runs from a post-impact state to the next heel strike, integrated at rtol = atol = ``RTOL`` = ``ATOL``,
each guard polished to ``GUARD_TOLERANCE``; one that takes longer than ``MAX_STEP_TIME`` natural periods
sqrt(l / g) stalls.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

RTOL = 1e-12
ATOL = 1e-12
MAX_STEP_TIME = 20.0  # in units of sqrt(l / g)
GUARD_TOLERANCE = 1e-14

StepStatus = Literal["strike", "fell", "stalled", "tripped", "stiff"]


@dataclass
class RigidStep:
    """A step from a post-impact state to the next strike."""

    status: StepStatus
    x_start: np.ndarray
    x_minus: np.ndarray  # just before the strike (or the state when the step ended otherwise)
    x_plus: np.ndarray | None  # just after the strike
    period: float
    length: float
    rhs_evals: int
    samples_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    samples_x: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    accepted_steps: int = 0  # DOP853 steps taken
    pushes: list[tuple[float, float, float]] = field(default_factory=list)  # applied: (t, work, ground normal impulse)
    stop_strikes: list[tuple[float, float]] = field(default_factory=list)  # joint stops struck: (t, energy lost)
    element_work: float = 0.0  # the joint elements' (dampers') dissipated work over the step, integrated with it
    samples_work: np.ndarray = field(default_factory=lambda: np.zeros(0))  # the same since the step's start
