"""The step map's view of a rigid walker's compiled equations (:mod:`.tree_kernels`): the flow, the guards, the
fall functions and the phase count, the per-evaluation ones inlined with their callees."""

from __future__ import annotations

import math

import numpy as np

from biped_sim.kernel import inlined, kernel
from biped_sim.rigid.tree_elements import tree_element_power
from biped_sim.rigid.tree_kernels import (
    tree_guard,
    tree_guard_rate,
    tree_rhs,
)
from biped_sim.rigid.tree_layout import (
    P_FALL,
    P_L,
    T_NELEM,
    T_NOFF,
    T_NPHASE,
    T_NPTS,
    coords,
    fall_angle,
    perm_offset,
    point,
)

FALL_HIP_FRACTION = 0.05  # the hip below this fraction of the leg length is a fall (every rigid walker's)


@kernel
def tree_fall(p: np.ndarray, i: int, x: np.ndarray) -> float:
    """Fall function i (positive while standing): 0, 1: the fall angle minus |each leg's hip body's angle|; 2: the
    hip's height minus 0.05 l; 3 (a walker with bodies off its legs, a torso): the least of their fall angles minus
    their |angles| (each its own)."""
    if i < 2:
        return p[P_FALL] - abs(x[0 if i == 0 else int(p[perm_offset(p)])])
    n = coords(p)
    if i == 3:
        margin = math.inf
        for k in range(n - int(p[T_NOFF]), n):
            margin = min(margin, fall_angle(p, k) - abs(x[k]))
        return margin
    _, hip_y = point(p, int(p[T_NPTS]), x[:n])
    return hip_y - FALL_HIP_FRACTION * p[P_L]


# the step map's per-evaluation kernels inlined with their callees: a call per offset, angle or column would cost
# its arguments' words and reference counts at every evaluation; the flow's solve (inlined twice, with the light
# legs' tier) and the joint elements stay one call each per evaluation: their inlined copies cost more compile time
# than their calls cost run time (docs/architecture.md, "Compiling less")
_rhs = inlined(tree_rhs, calls=frozenset({"_solve", "element_forces"}))
_guard, _fall = inlined(tree_guard), inlined(tree_fall)


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


@kernel
def has_elements(p: np.ndarray) -> bool:
    """The walker has joint elements (springs, dampers): the step integrates their dissipated work."""
    return p[T_NELEM] > 0


@kernel
def element_power(p: np.ndarray, x: np.ndarray) -> float:
    """Power the joint elements dissipate at state x (>= 0), the integrand of their work."""
    return tree_element_power(p, x)
