"""The step map's view of a rigid walker's compiled equations: every rigid walker is a tree (:mod:`.tree_kernels`).

``kind`` is kept in the signatures for the step map's callers; it is always ``TREE``.
"""

from __future__ import annotations

import numpy as np

from biped_sim.kernel import inlined, kernel
from biped_sim.rigid.tree_kernels import (
    FALL_HIP_FRACTION,
    after_phase,
    begin_step,
    skip_phase,
    tree_fall,
    tree_guard,
    tree_guard_rate,
    tree_impact,
    tree_rhs,
)
from biped_sim.rigid.tree_layout import (
    T_NPHASE,
)

TREE = 3
# the step map's per-evaluation kernels inlined with their callees: a call per offset, angle or column would cost
# its arguments' words and reference counts at every evaluation
_rhs, _guard, _fall = inlined(tree_rhs), inlined(tree_guard), inlined(tree_fall)
__all__ = ["FALL_HIP_FRACTION", "TREE"]


@kernel
def rigid_rhs(kind: int, p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = dx/dt."""
    _rhs(p, x, out)


@kernel
def guard(kind: int, p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """The phase's guard (its downward zero ends the phase)."""
    return _guard(p, phase, x)


@kernel
def guard_rate(kind: int, p: np.ndarray, phase: int, x: np.ndarray, f: np.ndarray) -> float:
    """Time derivative of :func:`guard` along the flow."""
    return tree_guard_rate(p, phase, x)


@kernel
def first_phase(kind: int) -> int:
    return 0


@kernel
def n_phases(kind: int, p: np.ndarray) -> int:
    return int(p[T_NPHASE])


@kernel
def start_step(kind: int, p: np.ndarray) -> None:
    begin_step(p)


@kernel
def phase_skipped(kind: int, p: np.ndarray, phase: int, x: np.ndarray) -> bool:
    return skip_phase(p, phase, x)


@kernel
def end_phase(kind: int, p: np.ndarray, phase: int, x: np.ndarray, out: np.ndarray) -> None:
    after_phase(p, phase, x, out)


@kernel
def n_fall_checks(kind: int, p: np.ndarray) -> int:
    return 3


@kernel
def fall_check(kind: int, p: np.ndarray, i: int, x: np.ndarray) -> float:
    return _fall(p, i, x)


@kernel
def rigid_impact(kind: int, p: np.ndarray, x: np.ndarray, q_work: np.ndarray, out: np.ndarray) -> None:
    tree_impact(p, x, True, out)
