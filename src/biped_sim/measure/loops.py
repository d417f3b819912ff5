"""The measures of a run over all its samples, each group one compiled call (no Python call per sample).

Each loop calls the formulation's per-sample measure (``multibody.dispatch.system_contact`` ..., resolved at
compile time by the system's type) at every sample and writes it into an array the caller allocated, so the
post-processing of a run costs a fraction of its integration. The per-sample functions are the right-hand
side's equations (one source per equation); the same loops run as plain Python (``.py_func``) are the tests'
reference, bit for bit. A rigid run's energies and hip go through its tree's compiled ``tree_energy`` and ``point``
alike.
"""

from __future__ import annotations

import numpy as np

from biped_sim.kernel import kernel
from biped_sim.multibody.dispatch import system_attitude, system_contact, system_energy, system_hip, system_violation
from biped_sim.rigid.tree_kernels import tree_energy
from biped_sim.rigid.tree_layout import RigidTree, point


@kernel
def _store(out: np.ndarray, values: tuple) -> None:
    """out[k] = values[k]: one sample's measures (a tuple of floats) into its row of a loop's output."""
    for k in range(out.shape[0]):
        out[k] = values[k]


@kernel(reference_counts=False)
def contact_loop(ys: np.ndarray, modes: np.ndarray, system: tuple, out: np.ndarray) -> None:
    """out[k, i, f]: contact channel k (the formulation's ``contact_names``) of foot f at sample i."""
    for i in range(ys.shape[0]):
        for f in range(out.shape[2]):
            _store(out[:, i, f], system_contact(ys[i], system, modes[i], f))


@kernel(reference_counts=False)
def energy_loop(ys: np.ndarray, modes: np.ndarray, system: tuple, out: np.ndarray) -> None:
    """out[i]: (kinetic, potential, elastic) energy at sample i."""
    for i in range(ys.shape[0]):
        _store(out[i], system_energy(ys[i], system, modes[i]))


@kernel(reference_counts=False)
def violation_loop(ys: np.ndarray, system: tuple, out: np.ndarray) -> None:
    """out[i, k]: constraint norm k (the formulation's ``violation_names``) at sample i."""
    for i in range(ys.shape[0]):
        _store(out[i], system_violation(ys[i], system))


@kernel(reference_counts=False)
def hip_loop(ys: np.ndarray, system: tuple, out: np.ndarray) -> None:
    """out[i]: the hip's position in the slope frame at sample i (2 planar, 3 spatial entries)."""
    for i in range(ys.shape[0]):
        _store(out[i], system_hip(ys[i], system))


@kernel(reference_counts=False)
def attitude_loop(ys: np.ndarray, system: tuple, out: np.ndarray) -> None:
    """out[i, b]: (pitch, roll, yaw, pitch rate) of body b at sample i (spatial formulations)."""
    for i in range(ys.shape[0]):
        for b in range(out.shape[1]):
            _store(out[i, b], system_attitude(ys[i], system, b))


@kernel(reference_counts=False)
def rigid_loop(params: RigidTree, states: np.ndarray, hip_row: int, energy: np.ndarray, hip: np.ndarray) -> None:
    """energy[i]: (kinetic, potential) energy, and hip[i]: the hip's position (row ``hip_row`` of the tree) of a
    rigid walker (its tree's ``params``) at sample i, in the frame of its step (the caller moves it to the run's)."""
    n = params.n
    for i in range(states.shape[0]):
        _store(energy[i], tree_energy(params, states[i]))
        _store(hip[i], point(params, hip_row, states[i, :n]))
