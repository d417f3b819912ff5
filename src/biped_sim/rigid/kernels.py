"""The step map's view of a rigid walker's compiled equations (:mod:`.tree_kernels`): the flow, the guards, the
fall functions and the phase count, the per-evaluation ones inlined with their callees."""

from __future__ import annotations

import numpy as np

from biped_sim.kernel import inlined, kernel
from biped_sim.rigid.tree_kernels import (
    tree_fall,
    tree_guard,
    tree_guard_rate,
    tree_rhs,
)
from biped_sim.rigid.tree_layout import T_NOFF, T_NPHASE

# the step map's per-evaluation kernels inlined with their callees: a call per offset, angle or column would cost
# its arguments' words and reference counts at every evaluation
_rhs, _guard, _fall = inlined(tree_rhs), inlined(tree_guard), inlined(tree_fall)


@kernel
def rigid_rhs(p: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = dx/dt."""
    _rhs(p, x, out)


@kernel
def guard(p: np.ndarray, phase: int, x: np.ndarray) -> float:
    """The phase's guard (its downward zero ends the phase)."""
    return _guard(p, phase, x)


@kernel
def guard_rate(p: np.ndarray, phase: int, x: np.ndarray, f: np.ndarray) -> float:
    """Time derivative of :func:`guard` along the flow."""
    return tree_guard_rate(p, phase, x)


@kernel
def n_phases(p: np.ndarray) -> int:
    return int(p[T_NPHASE])


@kernel
def n_fall_checks(p: np.ndarray) -> int:
    """The legs' two, the hip's, and one for the bodies off the legs (a torso) if any."""
    return 4 if p[T_NOFF] > 0 else 3


@kernel
def fall_check(p: np.ndarray, i: int, x: np.ndarray) -> float:
    return _fall(p, i, x)
