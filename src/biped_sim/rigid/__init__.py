"""Rigid (impulsive-impact) reference models of the walkers: flow, heel strike, impact map, runs.

``models`` holds the walkers (one multibody description for the compass and the rimless wheel, MODEL.md
8's equations for Garcia's simplest walker), ``stepping`` the event-located integration of a step,
``run`` a rigid run with the files of ``biped-sim run``.
"""

from __future__ import annotations

from biped_sim.config import Config


def rigid_limit_cycle_initial(config: Config) -> dict[str, float]:
    """The rigid model's period-1 fixed point (just after heel strike) as the four InitialState keys."""
    from biped_sim.analysis.limit_cycle import rigid_limit_cycle_initial as fixed_point

    return fixed_point(config)


__all__ = ["rigid_limit_cycle_initial"]
