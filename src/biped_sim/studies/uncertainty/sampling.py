"""Where in the unit cube the samples go: scrambled Sobol points or a Latin hypercube, seeded; or the Saltelli
design that Sobol indices need.

``sobol``: scipy.stats.qmc's scrambled Sobol sequence, ``2^m`` points (a power of two keeps its balance
properties); ``lhs``: scipy's Latin hypercube, any count. ``saltelli``: SALib's design for first-order and
total indices (Saltelli 2002, with the Sobol sequence): base count N a power of two, ``N (d + 2)`` rows laid
out in blocks of ``d + 2`` (A, the d mixed rows AB_i, B), one block per base point. The same seed gives the
same design bit for bit.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

from biped_sim.errors import ArgumentError

METHODS = ("sobol", "lhs", "saltelli")


def is_power_of_two(n: int) -> bool:
    """Whether ``n`` is 1, 2, 4, 8, ..."""
    return n >= 1 and n & (n - 1) == 0


def check_count(samples: int, method: str) -> None:
    """ArgumentError naming ``samples`` or ``method`` for a count the design cannot take."""
    if method not in METHODS:
        raise ArgumentError("method", f"unknown sampling method {method!r}; expected one of {', '.join(METHODS)}")
    if samples < 2:
        raise ArgumentError("samples", "need at least 2 samples")
    if method in ("sobol", "saltelli") and not is_power_of_two(samples):
        what = "Sobol indices (Saltelli's design)" if method == "saltelli" else "a Sobol sequence"
        hint = "" if method == "saltelli" else "; or the Latin hypercube, method lhs, which takes any count"
        raise ArgumentError("samples", f"{samples} is not a power of two, which {what} needs (e.g. 256, 512{hint})")


def block_size(method: str, dimensions: int) -> int:
    """Rows per base point: ``d + 2`` for the Saltelli design, else 1."""
    return dimensions + 2 if method == "saltelli" else 1


def unit_problem(dimensions: int) -> dict[str, object]:
    """SALib's description of the unit cube in ``dimensions`` dimensions (the distributions map it afterwards)."""
    return {"num_vars": dimensions, "names": [f"x{i}" for i in range(dimensions)], "bounds": [[0.0, 1.0]] * dimensions}


def unit_design(samples: int, dimensions: int, method: str, seed: int) -> np.ndarray:
    """The design in [0, 1)^d: ``samples`` rows (``samples (d + 2)`` for ``saltelli``)."""
    check_count(samples, method)
    if method == "lhs":
        return qmc.LatinHypercube(d=dimensions, seed=np.random.default_rng(seed)).random(samples)
    if method == "sobol":
        return qmc.Sobol(d=dimensions, scramble=True, seed=np.random.default_rng(seed)).random_base2(
            int(samples).bit_length() - 1
        )
    from SALib.sample import sobol as saltelli  # SALib: only the Sobol-index studies need it

    return np.asarray(
        saltelli.sample(unit_problem(dimensions), samples, calc_second_order=False, scramble=True, seed=seed)
    )
