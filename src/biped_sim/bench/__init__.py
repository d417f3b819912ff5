"""Performance benchmark: the compiled loops against a solve_ivp baseline and MuJoCo.

``runner`` measures (wall times, RHS counts, accuracy against a tight reference, compile and
start-up times, sweep throughput), ``baseline`` is the solve_ivp + plain-Python driver,
``mujoco_walker`` builds the same walker as MJCF (``mujoco_contact`` matches its contact to ours), ``report``
writes bench.md and bench.json.
This package is imported only by ``biped-sim bench``: nothing here is on the simulation path.
"""
