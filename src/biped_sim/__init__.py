"""biped-sim: passive dynamic walkers with compliant, dissipative foot-ground contact and friction.

The public API::

    from biped_sim import load_config, simulate, run
    result = simulate(load_config("configs/round_foot_walker.yaml", ["ground.slope=0.03"]))
"""

from __future__ import annotations

from biped_sim._compiled_cache import configure_cache_dir, configure_optimisation, lock_cache_writes

configure_optimisation()  # first: numba's reload of its settings resets the cache directory
configure_cache_dir()
lock_cache_writes()

from biped_sim._symbol_calls import install as call_big_callees_by_symbol  # noqa: E402

call_big_callees_by_symbol()

from biped_sim.config import Config, config_from_dict, load_config  # noqa: E402
from biped_sim.errors import ConfigError  # noqa: E402
from biped_sim.simulate import RunResult, run, simulate  # noqa: E402

__version__ = "0.1.0"
__all__ = ["Config", "ConfigError", "RunResult", "config_from_dict", "load_config", "run", "simulate"]
