"""The rigid walker in space: Kane's equations of the stance phase and the plastic heel strike.

Generalized speeds u = (omega, beta'): the stance leg's angular velocity (slope frame) and the hinge rate (with a
torso, then its rate about the hinge axis through the hinge's midpoint; with knees, then the swing knee's rate
kappa': its axis is the hinge's, through the knee point; while the knee is locked, its rate is 0 and its column
left out of the equations). A torso's springs and dampers add their couples' generalized forces
(:func:`~biped_sim.rigid.space_kernels.torso_elements`). The stance foot's material point at contact has zero
velocity (pinned point foot; a sphere or ring rolling without slip: a nonholonomic constraint, the contact point
moving over the ground and over the foot), so every point's velocity is linear in u: v = A u, and every part's
angular velocity w = B u. With the accelerations a = A u' + b and w' = B u' + e (b and e from the motion of the
contact point and of the hinge axis), Kane's equations are sum A^T m (a - g) + B^T (I w' + w x I w) = 0, i.e.
M u' = F with M = sum m A^T A + B^T I B: the contact force does no work through the partial velocities, so it never
appears. The attitude follows from omega = E (psi', phi', theta')
(:func:`~biped_sim.rigid.space_model.rate_matrix`) and the contact point from the geometric contact point's
velocity.

The strike is plastic: the landing foot sticks (and then rolls), the trailing foot leaves. The impulse at the
new contact and the hinge's have no moment about the new contact point (whole walker) nor about the hinge axis
(trailing leg; a torso's joint none about it either), and with the new configuration's partial velocities A', B'
these balances are M' u+ = sum A'^T m v- + B'^T I w-. The walker is then mirrored (y -> -y) so that the new stance
leg is the left leg again. The knee strike is the same balance in one configuration: the locked walker's speeds keep
their generalized momentum, (M u+)_i = (M u-)_i for the speeds that stay (:func:`knee_strike`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from biped_sim.rigid.space_kernels import space_params, torso_elements, torso_elements_energy
from biped_sim.rigid.space_model import (
    ELLIPSOID,
    EZ,
    KNEE_ANGLE,
    KNEE_RATE,
    MIRROR,
    Pose,
    SpaceModel,
    attitude_angles,
    bottom_direction_rate,
    foot_bottom,
    pose,
    rate_matrix,
)
from biped_sim.walkers.space_geometry import cross


def _skew(v: np.ndarray) -> np.ndarray:
    """[v]x: [v]x w = v x w."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@dataclass(frozen=True)
class PartMotion:
    """One part's motion: position from the contact point r, world inertia, velocity v = A u, angular velocity
    w = B u, and the accelerations' parts that do not depend on u' (b, e)."""

    mass: float
    r: np.ndarray
    inertia: np.ndarray
    a_matrix: np.ndarray
    b_matrix: np.ndarray
    v: np.ndarray
    w: np.ndarray
    b: np.ndarray
    e: np.ndarray


def contact_point_velocity(model: SpaceModel, where: Pose, omega: np.ndarray) -> np.ndarray:
    """Velocity of the geometric stance contact point over the ground (the material point's is zero): the foot's
    centre, at -(radius d - tube z) from it (an ellipsoid's: -d), turns about it, and the bottom moves over the foot
    with d."""
    foot = model.feet[0]
    d_dot = bottom_direction_rate(foot, where.rotations[0], omega)
    scale = 1.0 if foot.shape == ELLIPSOID else foot.radius
    return cross(omega, foot.tube * EZ - scale * where.stance_d) + scale * d_dot


def speeds(model: SpaceModel, x: np.ndarray) -> np.ndarray:
    """The generalized speeds u: the stance leg's angular velocity, the hinge rate, the torso's rate, the swing
    knee's rate (those the walker has)."""
    torso = [x[model.torso_angle + 1]] if model.torso else []
    return np.concatenate((x[4:8], torso, [x[KNEE_RATE]] if model.knee else []))


def free_speeds(model: SpaceModel, knee_free: bool) -> int:
    """How many of the speeds (:func:`speeds`) are free: all but a locked knee's rate, the last."""
    return 4 + (1 if model.torso else 0) + (1 if model.knee and knee_free else 0)


def set_speeds(model: SpaceModel, x: np.ndarray, u: np.ndarray) -> None:
    """Write the free speeds ``u`` (the leading ones of :func:`speeds`) into state ``x``, in place."""
    x[4:8] = u[:4]
    if model.torso:
        x[model.torso_angle + 1] = u[4]
    if model.knee and len(u) == free_speeds(model, knee_free=True):
        x[KNEE_RATE] = u[-1]


def _joints(model: SpaceModel, where: Pose, x: np.ndarray) -> list[list[tuple[np.ndarray, np.ndarray, int]]]:
    """Per frame, the joints that turn its parts (all about the hinge axis): each one's point, that point's velocity
    and its speed's index in :func:`speeds` (the hinge's 3, the torso's 4, the knee's the last)."""
    omega, n, midpoint = x[4:7], len(speeds(model, x)), where.origin
    hinge = (midpoint, cross(omega, midpoint), 3)
    paths = [[], [hinge], [hinge], [(*hinge[:2], 4)]]  # the torso's joint: the hinge's midpoint, its own speed
    if model.knee:
        at = where.point(1, model.knee.point)
        paths[2] = [hinge, (at, cross(omega, at) + x[7] * cross(where.hinge, at - midpoint), n - 1)]
    return paths


def part_motions(model: SpaceModel, x: np.ndarray) -> list[PartMotion]:
    """Every part's motion in state ``x`` (:class:`PartMotion`), over every speed (a locked knee's rate is 0)."""
    where = pose(model, x)
    omega, axis, u = x[4:7], where.hinge, speeds(model, x)
    p_dot = contact_point_velocity(model, where, omega)
    spin = cross(omega, axis)  # every joint's axis turns with the stance leg
    paths = _joints(model, where, x)
    motions = []
    for part in model.parts:
        r = where.point(part.frame, part.com)
        a_matrix, b_matrix = np.zeros((3, len(u))), np.zeros((3, len(u)))
        a_matrix[:, :3], b_matrix[:, :3] = -_skew(r), np.eye(3)
        path = paths[part.frame]  # the hinge turns the swing leg, the knee its shank too; the torso its own joint
        for at, _, k in path:
            a_matrix[:, k], b_matrix[:, k] = cross(axis, r - at), axis
        v, w = a_matrix @ u, b_matrix @ u
        b, e = cross(omega, v - p_dot), np.zeros(3)
        for at, v_at, k in path:  # d/dt of rate_k axis x (r - at), the joint's point moving with the parts above it
            b += u[k] * (cross(spin, r - at) + cross(axis, v - v_at))
            e += u[k] * spin
        turn = where.rotations[part.frame]
        inertia = turn @ part.inertia @ turn.T
        motions.append(PartMotion(part.mass, r, inertia, a_matrix, b_matrix, v, w, b, e))
    return motions


def mass_matrix(motions: list[PartMotion]) -> np.ndarray:
    """Kane's generalized mass matrix sum m A^T A + B^T I B (symmetric positive definite)."""
    return sum(m.mass * m.a_matrix.T @ m.a_matrix + m.b_matrix.T @ m.inertia @ m.b_matrix for m in motions)


def flow(model: SpaceModel, x: np.ndarray, knee_free: bool = False) -> np.ndarray:
    """dx/dt of the stance phase (:mod:`biped_sim.rigid.space_model`'s state), the swing knee free or locked."""
    motions = part_motions(model, x)
    gravity = model.gravity_vector
    n = free_speeds(model, knee_free)
    force = np.zeros(motions[0].a_matrix.shape[1])
    for m in motions:
        force += m.a_matrix.T @ (m.mass * (gravity - m.b))
        force -= m.b_matrix.T @ (m.inertia @ m.e + cross(m.w, m.inertia @ m.w))
    x_dot = np.zeros(model.n_state)
    if model.torso:  # its elements' couples (the compiled law, the one source of each law)
        on_torso, on_hinge, power = torso_elements(space_params(model), x)
        force[4] += on_torso
        force[3] += on_hinge
        at = model.torso_angle
        x_dot[at], x_dot[at + 2] = x[at + 1], power
    x_dot[:3] = np.linalg.solve(rate_matrix(x[0], x[1]), x[4:7])
    x_dot[3] = x[7]
    x_dot[8:10] = contact_point_velocity(model, pose(model, x), x[4:7])[:2]
    if model.knee:
        x_dot[KNEE_ANGLE] = x[KNEE_RATE]
    set_speeds(model, x_dot, np.linalg.solve(mass_matrix(motions)[:n, :n], force[:n]))  # the speeds' rates
    return x_dot


def knee_strike(model: SpaceModel, x_minus: np.ndarray) -> np.ndarray:
    """The state just after the swing knee's plastic strike: locked straight, the impulse at the knee and at the
    stance contact keeping the generalized momentum of the locked system's speeds (``(M u-)`` of all but the knee's,
    the configuration unchanged: Kane's impulsive balance, as :func:`strike`)."""
    x = np.array(x_minus, dtype=float)
    x[KNEE_ANGLE] = 0.0  # located to rounding: the lock holds it exactly
    mass = mass_matrix(part_motions(model, x))
    momentum = mass @ speeds(model, x_minus)
    n = free_speeds(model, knee_free=False)
    set_speeds(model, x, np.linalg.solve(mass[:n, :n], momentum[:n]))
    x[KNEE_RATE] = 0.0
    return x


def ground_point(x: np.ndarray) -> np.ndarray:
    """The stance contact point (slope frame)."""
    return np.array([x[8], x[9], 0.0])


def energy_terms(model: SpaceModel, x: np.ndarray) -> tuple[float, float]:
    """(kinetic, potential) energy (potential zero at the slope frame's origin; with a torso, its springs' energy
    too)."""
    base = ground_point(x)
    gravity = model.gravity_vector
    motions = part_motions(model, x)
    kinetic = sum(0.5 * m.mass * m.v @ m.v + 0.5 * m.w @ m.inertia @ m.w for m in motions)
    springs = torso_elements_energy(space_params(model), x) if model.torso else 0.0
    return float(kinetic), float(sum(-m.mass * gravity @ (base + m.r) for m in motions) + springs)


def energy(model: SpaceModel, x: np.ndarray) -> float:
    """Kinetic plus potential energy (potential zero at the slope frame's origin)."""
    return sum(energy_terms(model, x))


def angular_momentum(motions: list[PartMotion], about: np.ndarray) -> np.ndarray:
    """The walker's angular momentum about ``about`` (a point from the stance contact point)."""
    return sum(cross(m.r - about, m.mass * m.v) + m.inertia @ m.w for m in motions)


def swing_foot_point(model: SpaceModel, x: np.ndarray) -> np.ndarray:
    """The swing foot's lowest point from the stance contact point."""
    where, frame = pose(model, x), model.swing_foot_frame
    return where.origins[frame] + foot_bottom(model.feet[1], where.rotations[frame])[0]


def landed(model: SpaceModel, x_minus: np.ndarray) -> np.ndarray:
    """The configuration after the strike, mirrored: the landing leg is the stance leg, velocities zero (a torso
    keeps its attitude: its angle from the new stance leg is the old less the hinge angle; the elements' work
    carries on)."""
    where = pose(model, x_minus)
    psi, phi, theta = attitude_angles(MIRROR @ where.rotations[1] @ MIRROR)
    contact = MIRROR @ (ground_point(x_minus) + swing_foot_point(model, x_minus))
    x = np.zeros(model.n_state)
    x[:4] = psi, phi, theta, -x_minus[3]
    x[8:10] = contact[:2]
    if model.torso:
        at = model.torso_angle
        x[at], x[at + 2] = x_minus[at] - x_minus[3], x_minus[at + 2]
    return x


def strike(model: SpaceModel, x_minus: np.ndarray) -> np.ndarray:
    """The state just after the plastic strike, mirrored (the landing leg the left, stance leg). The knees are
    locked through it (the new swing knee unlocks after it, at rest: its rate 0)."""
    before = part_motions(model, x_minus)
    before = [before[k] for k in model.swapped]  # the landing leg is the new stance leg
    x_plus = landed(model, x_minus)
    after = part_motions(model, x_plus)
    momentum = np.zeros(len(speeds(model, x_plus)))
    for old, new in zip(before, after, strict=True):
        momentum += new.a_matrix.T @ (old.mass * (MIRROR @ old.v))
        momentum += new.b_matrix.T @ (new.inertia @ (-MIRROR @ old.w))
    n = free_speeds(model, knee_free=False)
    set_speeds(model, x_plus, np.linalg.solve(mass_matrix(after)[:n, :n], momentum[:n]))
    return x_plus


def hip_push(
    model: SpaceModel, x: np.ndarray, impulse: np.ndarray, knee_free: bool = False
) -> tuple[np.ndarray, float]:
    """(the state just after an impulse on the hinge's midpoint, the ground's normal impulse). The stance foot and
    the hinge hold (and a locked knee): Kane's impulsive balance M du = A_hip^T p, A_hip the midpoint's partial
    velocities (it is on the hinge axis: the joints' rates do not move it); the ground's impulse is the walker's
    momentum change minus p (its normal part negative: the push would lift the stance foot)."""
    motions = part_motions(model, x)
    n = free_speeds(model, knee_free)
    a_hip = np.zeros((3, n))
    a_hip[:, :3] = -_skew(pose(model, x).origin)
    du = np.linalg.solve(mass_matrix(motions)[:n, :n], a_hip.T @ impulse)
    after = np.array(x, dtype=float)
    set_speeds(model, after, speeds(model, x)[:n] + du)
    momentum = sum(m.mass * m.a_matrix[:, :n] @ du for m in motions)
    return after, float(momentum[2] - impulse[2])
