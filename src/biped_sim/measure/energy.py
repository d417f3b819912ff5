"""The energy audit of a compliant run: E(t) - E(0) + W_dissipated(t) - W_push(t), which must stay near zero.

The dissipated work (the feet's normal damping and friction, the joint stops' damping, the joint elements') is
integrated as ODE states, so the balance is an independent check of the integration, not a tautology. W_push(t) is the
work of the pushes applied up to t (each its kinetic energy jump, booked from the first sample after it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from biped_sim.integrate.driver import Integration
from biped_sim.measure.loops import energy_loop
from biped_sim.multibody.dispatch import formulation_of
from biped_sim.walkers.model import BuiltModel


@dataclass
class EnergyAudit:
    """Energy terms at the samples; residual = E(t) - E(0) + W_dissipated(t) - W_push(t)."""

    kinetic: np.ndarray
    potential: np.ndarray
    elastic: np.ndarray
    dissipated_normal: np.ndarray
    dissipated_friction: np.ndarray
    dissipated_stops: np.ndarray  # W_stop(t): the joint stops' damping (zero without stops)
    dissipated_elements: np.ndarray  # W_element(t): the joint elements' (dampers') work (zero without elements)
    push_work: np.ndarray  # W_push(t): work of the pushes so far
    residual: np.ndarray


def energy_audit(model: BuiltModel, run: Integration) -> EnergyAudit:
    """Energy balance over the samples (the dissipated work is integrated as ODE states)."""
    ns = len(run.t)
    terms = np.empty((ns, 3))
    energy_loop(run.y, run.modes, model.system, terms)
    layout = formulation_of(model.system).layout_of(model.system)
    w_normal = run.y[:, layout.work_normal]
    w_friction = run.y[:, layout.work_friction]
    w_stop, w_element = (
        run.y[:, k] if k is not None else np.zeros(ns) for k in (layout.work_stop, layout.work_element)
    )
    push_work = np.zeros(ns)
    for _, first_sample, work in run.pushes:
        push_work[int(first_sample) :] += work
    total = terms.sum(axis=1)
    residual = total - total[0] + (w_normal - w_normal[0]) + (w_friction - w_friction[0]) - push_work
    for k, work in ((layout.work_element, w_element), (layout.work_stop, w_stop)):
        if k is not None:
            residual = residual + (work - work[0])
    return EnergyAudit(
        terms[:, 0], terms[:, 1], terms[:, 2], w_normal, w_friction, w_stop, w_element, push_work, residual
    )
