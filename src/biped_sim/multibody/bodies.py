"""A rigid body's share of a walker's equations, written once for the compliant tree (:mod:`.tree`) and the rigid
step map (:mod:`biped_sim.rigid.tree_kernels`): its energy, and its terms of the mass matrix and generalized forces
``M = sum_b m_b J_b^T J_b + I_b e_b e_b^T`` and ``Q = sum_b J_b^T F_b`` in any generalized coordinates, given the
nonzero columns of the Jacobian J_b of its centre of mass (each side computes J_b and the force F_b its own way: a
floating hip, or a pinned or rolling stance foot)."""

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
def lever_terms(lx: float, ly: float, rate: float, bx: float, by: float) -> tuple[float, float, float, float]:
    """One lever's share of a point's Jacobian and bias acceleration. A point of a planar tree of bodies is
    r = c + sum_k l_k, each lever l_k = A(theta_k) w_k turning with one coordinate theta_k (w_k constant in its body):
    its Jacobian's column k is d r / d theta_k = perp(l_k) = (-l_ky, l_kx), and the velocity products of its
    acceleration, the bias Jdot qd = -sum_k thetadot_k^2 l_k. Returns column k and (bx, by) with lever k's term
    added, (bx, by) - rate^2 (lx, ly): the compliant tree sums it down the tree (:mod:`.tree`), the rigid step map
    over a point's coordinates (:mod:`biped_sim.rigid.tree_kernels`)."""
    r2 = rate * rate
    return -ly, lx, bx - r2 * lx, by - r2 * ly


@kernel
def add_body_terms(
    matrix: np.ndarray,
    forces: np.ndarray,
    levers: np.ndarray,
    columns: np.ndarray,
    count: int,
    mass: float,
    inertia: float,
    own: int,
    fx: float,
    fy: float,
    with_forces: bool,
) -> None:
    """Add a body's terms to the lower triangle of ``matrix`` (M += m J^T J + I e_own e_own^T; :func:`mirror_lower`
    fills the upper one where a solve reads it) and, ``with_forces``, J^T (fx, fy) to ``forces``. The Jacobian of
    its centre of mass is zero but in ``count`` columns, ``columns[:count]`` in descending order, column
    ``columns[a]`` being ``levers[a]``: a body's terms touch only the pairs of its own columns (a tree's body, those
    of its path to the root). A massless body adds its inertia alone (its Jacobian is not read). Each entry gets the
    same terms in the same order as from the whole Jacobian, less the zero columns' zeros: the same bits."""
    matrix[own, own] += inertia
    if mass == 0.0:
        return
    for a in range(count):
        k = columns[a]
        jkx, jky = levers[a, 0], levers[a, 1]
        if with_forces:
            forces[k] += jkx * fx + jky * fy
        for c in range(a, count):
            matrix[k, columns[c]] += mass * (jkx * levers[c, 0] + jky * levers[c, 1])


@kernel
def mirror_lower(matrix: np.ndarray, n: int) -> None:
    """Copy the lower triangle of the leading (n x n) block of ``matrix`` into its upper one (M is symmetric)."""
    for k in range(n):
        for col in range(k + 1, n):
            matrix[k, col] = matrix[col, k]
