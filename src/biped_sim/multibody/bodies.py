"""A rigid body's energy, the one expression every formulation and the rigid model sum over their bodies."""

from __future__ import annotations

from biped_sim.kernel import kernel


@kernel
def body_energy(
    mass: float, inertia: float, vx: float, vy: float, omega: float, px: float, py: float, gx: float, gy: float
) -> tuple[float, float]:
    """(kinetic, potential) energy of a body whose centre of mass is at (px, py), moves at (vx, vy) and turns at
    omega, in gravity (gx, gy): T = m |v|^2 / 2 + I omega^2 / 2 (I about the centre of mass, Koenig's theorem),
    V = -m g . p (zero on the line through the frame's origin normal to g)."""
    return 0.5 * mass * (vx * vx + vy * vy) + 0.5 * inertia * omega * omega, -mass * (gx * px + gy * py)
