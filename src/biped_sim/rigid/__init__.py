"""Rigid (impulsive-impact) reference models of the walkers: flow, heel strike, impact map, limit cycles.

``models`` holds the walkers (one multibody description for the compass and the rimless wheel, MODEL.md
8's equations for Garcia's simplest walker), ``stepping`` the event-located integration of a step,
``limit_cycle`` the step map's fixed points and multipliers, ``start`` a rigid run's validated start.
The rigid run itself (many steps, measured and written) is :mod:`biped_sim.simulate.rigid`.
"""
