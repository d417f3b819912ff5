"""The benchmark's baseline: what the paper did in MATLAB and what most Python code does.

``scipy.integrate.solve_ivp(method="RK45")`` calls the plain-Python reference right-hand side
(:func:`~biped_sim.multibody.reference.reference_rhs`); contact onset and scuffing-guard switches
are terminal events on the plain-Python event functions, and at each event the mode update and
heel-strike bookkeeping run as plain Python (``.py_func`` of the compiled functions) before the
integration restarts. It simulates the same walker as the compiled loop, so its step periods
agree with ``dopri5`` at the same tolerances.
"""

from __future__ import annotations

import numpy as np

from biped_sim.config import IntegratorConfig
from biped_sim.integrate.driver import Integration, finish_integration, recorder_for
from biped_sim.integrate.recorder import apply_events
from biped_sim.integrate.stiff import integrate_scipy
from biped_sim.multibody import planar
from biped_sim.multibody.dispatch import contact_buffers
from biped_sim.multibody.events import system_event_functions
from biped_sim.multibody.reference import reference_rhs
from biped_sim.walkers import BuiltModel


def integrate_baseline(
    model: BuiltModel,
    integrator: IntegratorConfig,
    t_end: float,
    sample_rate: float,
    max_strikes: int | None = None,
) -> Integration:
    """Integrate the planar ``model`` with solve_ivp RK45 over the reference RHS (``integrator``'s tolerances)."""
    if not isinstance(model.system, planar.PlanarSystem):
        raise TypeError("the baseline's reference right-hand side exists for the planar formulation only")
    system = model.system
    y = np.array(model.y0, dtype=np.float64)
    modes = np.array(model.modes0, dtype=np.float64)
    rec, interval = recorder_for(y.shape[0], modes.shape[0], integrator, t_end, sample_rate, max_strikes, 0)

    def fun(t: float, state: np.ndarray) -> np.ndarray:
        return reference_rhs(t, state, system, modes)

    rec = integrate_scipy(
        system, rec, y, modes, contact_buffers(system), "RK45", integrator.rtol, integrator.atol,
        integrator.max_step, t_end, interval, max_strikes or 0, None, fun,
        event_values=system_event_functions.py_func, apply_events=apply_events.py_func,
    )  # fmt: skip
    return finish_integration(rec, interval, max_strikes)
