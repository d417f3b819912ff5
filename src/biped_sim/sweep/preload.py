"""A Dask worker preload that warms the default walker's compiled kernels when the worker starts.

    dask worker tcp://scheduler:8786 --nthreads 1 --preload biped_sim.sweep.preload

Dask imports this module in each worker and calls :func:`dask_setup` before the worker takes tasks,
so the compiling (or the loading from numba's on-disk cache) happens once at start rather than in
the first task. A sweep's runs warm their own group anyway (:func:`~biped_sim.simulate.warmup.warm_up`
before the first timed run of each formulation and integrator family), so a worker without the
preload gives the same results.
"""

from __future__ import annotations

from biped_sim.simulate.warmup import warm_up, warm_up_configs


def dask_setup(worker: object) -> None:
    """Dask's preload hook: warm the default walker's group in this worker process."""
    for config in warm_up_configs():
        warm_up(config)
