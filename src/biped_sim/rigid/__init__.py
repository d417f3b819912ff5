"""Rigid (impulsive-impact) models of the walkers: flow, strikes, the compiled step map, limit cycles.

Every rigid walker is its description's tree (``tree``: the model, ``tree_build``: its records,
``tree_layout`` and ``tree_kernels``: the compiled equations), stepped by one compiled step map (``compiled``,
``integration``; ``ground``: the strike on a ground profile), whose fixed points and multipliers ``limit_cycle``
finds; ``start`` is a rigid run's validated start, ``strike_check`` whether the plastic strike is the stiff
contact's limit.
The rigid run itself (many steps, measured and written) is :mod:`biped_sim.simulate.rigid`.
"""
