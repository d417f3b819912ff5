"""A rigid body's share of a walker's equations, written once for the compliant tree (:mod:`.tree`) and the rigid
step map (:mod:`biped_sim.rigid.tree_kernels`): its energy, and its terms of the mass matrix and generalized forces
``M = sum_b m_b J_b^T J_b + I_b e_b e_b^T`` and ``Q = sum_b J_b^T F_b`` in any generalized coordinates, given the
Jacobian J_b of its centre of mass (each side computes J_b and the force F_b its own way: a floating hip, or a
pinned or rolling stance foot)."""

from __future__ import annotations

import numpy as np

from biped_sim.kernel import kernel


@kernel
def body_energy(
    mass: float, inertia: float, vx: float, vy: float, omega: float, px: float, py: float, gx: float, gy: float
) -> tuple[float, float]:
    """(kinetic, potential) energy of a body whose centre of mass is at (px, py), moves at (vx, vy) and turns at
    omega, in gravity (gx, gy): T = m |v|^2 / 2 + I omega^2 / 2 (I about the centre of mass, Koenig's theorem),
    V = -m g . p (zero on the line through the frame's origin normal to g)."""
    return 0.5 * mass * (vx * vx + vy * vy) + 0.5 * inertia * omega * omega, -mass * (gx * px + gy * py)


@kernel
def add_body_terms(
    matrix: np.ndarray,
    forces: np.ndarray,
    jacobian: np.ndarray,
    mass: float,
    inertia: float,
    own: int,
    fx: float,
    fy: float,
    with_forces: bool,
) -> None:
    """Add a body's terms to the upper triangle of ``matrix`` (M += m J^T J + I e_own e_own^T; :func:`mirror_upper`
    fills the lower one once every body is in) and, ``with_forces``, J^T (fx, fy) to ``forces``: ``jacobian[k]``
    is column k of the Jacobian of its centre of mass, ``own`` the coordinate its inertia turns with. A massless
    body adds its inertia alone (its Jacobian is not read)."""
    matrix[own, own] += inertia
    if mass == 0.0:
        return
    n = jacobian.shape[0]
    for k in range(n):
        jkx, jky = jacobian[k, 0], jacobian[k, 1]
        if with_forces:
            forces[k] += jkx * fx + jky * fy
        for col in range(k, n):
            matrix[k, col] += mass * (jkx * jacobian[col, 0] + jky * jacobian[col, 1])


@kernel
def mirror_upper(matrix: np.ndarray, n: int) -> None:
    """Copy the upper triangle of the leading (n x n) block of ``matrix`` into its lower one (M is symmetric)."""
    for k in range(n):
        for col in range(k + 1, n):
            matrix[col, k] = matrix[k, col]
