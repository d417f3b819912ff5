"""The step map's view of a rigid walker's compiled equations (:mod:`.tree_kernels`): the flow, the guards, the
fall functions and the phase count, the per-evaluation ones inlined with their callees."""

from __future__ import annotations

import math

import numpy as np

from biped_sim.integrate.dense import dop853_extra_stage_input
from biped_sim.integrate.stepper import Scratch, propagate, stage_input
from biped_sim.integrate.tableaus import Tableau
from biped_sim.kernel import inlined, kernel
from biped_sim.rigid.tree_elements import tree_element_power
from biped_sim.rigid.tree_kernels import (
    tree_guard,
    tree_guard_rate,
    tree_rhs,
)
from biped_sim.rigid.tree_layout import RigidTree, hip, point

FALL_HIP_FRACTION = 0.05  # the hip below this fraction of the leg length is a fall (every rigid walker's)


@kernel
def tree_fall(tree: RigidTree, i: int, x: np.ndarray) -> float:
    """Fall function i (positive while standing): 0, 1: the fall angle minus |each leg's hip body's angle|; 2: the
    hip's height minus 0.05 l; 3 (a walker with bodies off its legs, a torso): the least of their fall angles minus
    their |angles| (each its own)."""
    if i < 2:
        return tree.fall - abs(x[0 if i == 0 else tree.coords[0].perm])
    n = tree.n
    if i == 3:
        margin = math.inf
        for k in range(n - tree.n_off, n):
            margin = min(margin, tree.coords[k].fall_angle - abs(x[k]))
        return margin
    _, hip_y = point(tree, hip(tree), x[:n])
    return hip_y - FALL_HIP_FRACTION * tree.leg_length


# the step map's per-evaluation kernels inlined with their callees: a call per offset, angle or column would cost
# its arguments' words and reference counts at every evaluation; the flow's solve (inlined twice, with the light
# legs' tier) and the joint elements stay one call each per evaluation: their inlined copies cost more compile time
# than their calls cost run time (docs/architecture.md, "Compiling less"); they count no references: each read of
# one of the tree's arrays would otherwise count one at every evaluation
_rhs = inlined(tree_rhs, calls=frozenset({"_solve", "element_forces"}))
_guard, _fall = inlined(tree_guard), inlined(tree_fall)


FLOW, STAGES, DENSE = 0, 1, 2  # flow_kernel's tasks: f at one state, a step's stages, DOP853's dense stages


@kernel(reference_counts=False, literal_arguments=False)
def flow_kernel(
    tree: RigidTree, tab: Tableau, sc: Scratch, h: float, y: np.ndarray, task: int, row: int, elements: bool
) -> tuple[bool, float]:
    """Every evaluation of the step map's flow, the only copy of it (inlined): ``FLOW``, f(y) into ``sc.k[row]``;
    ``STAGES``, the stages of an explicit Runge-Kutta step of length h from y (their flows in ``sc.k[1:]``,
    ``k[0]`` = f(y) given), its end state in ``sc.y_new`` and the flow there in ``k[stages]``; ``DENSE``, DOP853's
    three extra dense-output stages of that step. Returns whether the step's end state is finite and, for a walker
    with joint elements (``elements``), the step's quadrature of the power they dissipate (the method's weights b at
    its stages; times h, their work over the step). One kernel: the tree's arrays are passed once per step, not
    once per stage, and the flow's code is compiled once, not once per caller."""
    finite = True
    power = tab.b[0] * element_power(tree, y) if elements and task == STAGES else 0.0
    count = 1 if task == FLOW else (3 if task == DENSE else tab.stages)
    for s in range(1, count + 1):
        at, out = sc.y_stage, s
        if task == FLOW:
            at, out = y, row
        elif task == DENSE:
            out = dop853_extra_stage_input(tab, h, y, sc, s - 1)
        elif s < tab.stages:
            stage_input(tab.a, s, h, y, sc.k, at)
        else:
            at = sc.y_new
            finite = propagate(tab.b, tab.stages, h, y, sc.k, at)
        _rhs(tree, at, sc.k[out])
        if elements and task == STAGES and s < tab.stages:
            power += tab.b[s] * element_power(tree, at)
    return finite, power


@kernel(reference_counts=False)
def guard(tree: RigidTree, phase: int, x: np.ndarray) -> float:
    """The phase's guard (its downward zero ends the phase)."""
    return _guard(tree, phase, x)


@kernel(reference_counts=False)
def guard_rate(tree: RigidTree, phase: int, x: np.ndarray, f: np.ndarray) -> float:
    """Time derivative of :func:`guard` along the flow."""
    return tree_guard_rate(tree, phase, x)


@kernel
def n_phases(tree: RigidTree) -> int:
    return tree.phases.shape[0]


@kernel
def n_fall_checks(tree: RigidTree) -> int:
    """The legs' two, the hip's, and one for the bodies off the legs (a torso) if any."""
    return 4 if tree.n_off > 0 else 3


@kernel(reference_counts=False)
def fall_check(tree: RigidTree, i: int, x: np.ndarray) -> float:
    """Fall function i at x (:func:`tree_fall`, inlined: the event search evaluates it often)."""
    return _fall(tree, i, x)


@kernel
def has_elements(tree: RigidTree) -> bool:
    """The walker has joint elements (springs, dampers): the step integrates their dissipated work."""
    return tree.elements.shape[0] > 0


@kernel(reference_counts=False)
def element_power(tree: RigidTree, x: np.ndarray) -> float:
    """Power the joint elements dissipate at state x (>= 0), the integrand of their work."""
    return tree_element_power(tree, x)
