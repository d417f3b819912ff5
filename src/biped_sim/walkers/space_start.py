"""The start of a described walker in space whose joints turn about other axes than the lateral (hip roll, hip yaw).

The planar start (:func:`~biped_sim.walkers.described_start.build_described`) knows only sagittal angles. A body hung
on a joint about another axis reads its initial-state keys as that joint's angle and rate about its axis, relative to
its parent (:class:`~biped_sim.config.description.JointSpec`'s ``axis``): the planar start takes it along with its
parent (:func:`held_initial`: the joint at 0), and :func:`turn_joints` then turns the body and everything below it
about the joint's axis through the joint's point by that angle and gives them that rate, parents first, so that a
joint below another sees its parent already turned. A joint above the stance foot starts at 0 (its turn would lift
the foot off the ground or sink it): ConfigError naming the key otherwise.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from biped_sim.config import InitialState
from biped_sim.errors import ConfigError
from biped_sim.walkers.described import Tree, stance_feet
from biped_sim.walkers.described_start import angle_key, body_angles
from biped_sim.walkers.space_geometry import cross, euler_parameters


def turned_bodies(tree: Tree) -> list[int]:
    """The bodies hung on a joint about another axis than z', parents first."""
    return [
        c for c in range(1, len(tree.names)) if not (tree.joint_axis[c][2] > 0.0 and not np.any(tree.joint_axis[c][:2]))
    ]


def held_initial(
    tree: Tree, initial: InitialState | Mapping[str, float], keys: tuple[str, ...]
) -> InitialState | Mapping[str, float]:
    """``initial`` for the planar start: each turned body's angle and rate its parent's (its joint at 0), ``initial``
    itself when no body is turned."""
    turned = turned_bodies(tree)
    if not turned:
        return initial
    values = initial.model_dump() if isinstance(initial, InitialState) else dict(initial)
    angles = body_angles(tree, values, list(keys))
    for c in turned:
        angles[c] = angles[tree.parent[c]]
        key = angle_key(tree, list(keys), c)[0]
        values[key], values[key.removesuffix("angle") + "rate"] = float(angles[c, 0]), float(angles[c, 1])
    return values


def turn_joints(
    tree: Tree,
    keys: tuple[str, ...],
    initial: InitialState | Mapping[str, float],
    on_parent: Mapping[int, np.ndarray],
    q: np.ndarray,
    qd: np.ndarray,
) -> None:
    """Turn each turned body's subtree in (q, qd) (rows (r, p) and (rdot, pdot)) by its joint's initial angle and
    rate (``on_parent``: each child's joint point on its parent, the parent's frame from its centre of mass)."""
    turned = turned_bodies(tree)
    if not turned:
        return
    values = initial.model_dump() if isinstance(initial, InitialState) else dict(initial)
    joint_state = body_angles(tree, values, list(keys))
    stance_body = int(tree.foot_body[stance_feet(tree)[0]])
    for c in turned:
        theta, rate = joint_state[c]
        subtree = _subtree(tree, c)
        if stance_body in subtree and (theta or rate):
            key = angle_key(tree, list(keys), c)[0]
            raise ConfigError(
                f"simulation.initial.{key}", "a joint about another axis above the stance foot starts at 0"
            )
        _turn(q, qd, int(tree.parent[c]), on_parent[c], tree.joint_axis[c], theta, rate, subtree)


def _subtree(tree: Tree, c: int) -> list[int]:
    """Body c and every body below it."""
    below = [c]
    for b in range(c + 1, len(tree.names)):  # parents first
        if tree.parent[b] in below:
            below.append(b)
    return below


def _attitude(row: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(A, omega) of a body's Euler parameters and their rates: omega = 2 E pdot."""
    from scipy.spatial.transform import Rotation  # here: scipy.spatial adds 0.15 s to every command's start-up

    e0, e = row[3], row[4:7]
    tilde = np.array([[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]])
    big_e = np.column_stack((-e, tilde + e0 * np.eye(3)))
    return Rotation.from_quat([*e, e0]).as_matrix(), 2.0 * big_e @ rates[3:7]


def _turn(
    q: np.ndarray, qd: np.ndarray, parent: int, point: np.ndarray, axis: np.ndarray, theta: float, rate: float,
    subtree: list[int],
) -> None:  # fmt: skip
    """Turn the ``subtree``'s bodies by theta about the parent's ``axis`` through its joint ``point`` (both in the
    parent's frame from its centre of mass), their motion relative to the parent turned alike, plus the rate."""
    from scipy.spatial.transform import Rotation  # here: scipy.spatial adds 0.15 s to every command's start-up

    a_p, w_p = _attitude(q[parent], qd[parent])
    n = a_p @ axis
    joint = q[parent, :3] + a_p @ point
    v_joint = qd[parent, :3] + cross(w_p, a_p @ point)
    turn = Rotation.from_rotvec(theta * n).as_matrix()
    for b in subtree:
        a_b, w_b = _attitude(q[b], qd[b])
        d = turn @ (q[b, :3] - joint)
        relative = qd[b, :3] - v_joint - cross(w_p, q[b, :3] - joint)
        velocity = v_joint + cross(w_p, d) + turn @ relative + rate * cross(n, d)
        p, pdot = euler_parameters(turn @ a_b, w_p + turn @ (w_b - w_p) + rate * n)
        q[b] = [*(joint + d), *p]
        qd[b] = [*velocity, *pdot]
