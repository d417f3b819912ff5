"""Measures of one run: heel strikes and steps, the energy audit, constraint drift, contact channels.

Everything here is post-processing over what an integration recorded, using the same compiled
kinematics and force functions as the right-hand side (one source of truth per equation), reached
through the formulation's :class:`~biped_sim.multibody.dispatch.Measures`, so planar and spatial runs
are measured alike.
"""
