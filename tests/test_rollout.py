"""The compiled integration loop against the same loop run as plain Python, bit for bit.

As MuJoCo checks its C rollout against a Python loop: the plain-Python run executes the ``.py_func``
of every compiled function of the engine (contact laws, formulation kernels, the loop itself), so
both runs have one source. Compiled and interpreted arithmetic agree bit for bit here: numba emits
plain IEEE double operations in source order (no fast-math: no reassociation, no fused
multiply-adds) and calls the same libm (pow, sqrt, sin, cos, exp, tanh) as Python. The buffers of
the loop grow without changing a bit either.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

from biped_sim import load_config
from biped_sim.integrate import driver, recorder
from biped_sim.integrate.driver import Integration, integrate_model
from biped_sim.walkers import BuiltModel, build_model

from .conftest import DEFAULT_CONFIG, plain_engine

RESULTS = ("t", "y", "modes", "strike_t", "strike_foot", "strike_y", "strike_modes", "contact_log")
COUNTERS = ("status", "t_final", "rhs_evals", "accepted_steps", "rejected_steps", "events")


def assert_bit_identical(a: Integration, b: Integration) -> None:
    for field in RESULTS:
        x, y = getattr(a, field), getattr(b, field)
        assert x.shape == y.shape, field
        assert x.tobytes() == y.tobytes(), field
    assert [getattr(a, f) for f in COUNTERS] == [getattr(b, f) for f in COUNTERS]


@pytest.fixture(scope="module")
def walker() -> tuple[BuiltModel, object]:
    config = load_config(DEFAULT_CONFIG)
    return build_model(config), config.integrator


def test_compiled_loop_is_the_plain_python_loop_bit_for_bit(walker) -> None:
    model, integrator = walker
    # start 10 ms before the first heel strike: a few hundred dopri5 steps cross its touchdown
    approach = integrate_model(model.system, model.y0, model.modes0, integrator, 1.0, 1000.0, max_strikes=1)
    start = int(np.searchsorted(approach.t, approach.strike_t[0] - 0.01))
    y0, modes0 = approach.y[start], approach.modes[start]
    compiled = integrate_model(model.system, y0, modes0, integrator, 0.03, 1000.0)
    with plain_engine():
        assert driver.advance.__module__ == "biped_sim.integrate.explicit" and not isinstance(
            driver.advance, CPUDispatcher
        )
        python = integrate_model(model.system, y0, modes0, integrator, 0.03, 1000.0)
    assert compiled.accepted_steps > 200 and len(compiled.strike_t) == 1
    assert (compiled.contact_log[:, 2] == 1.0).any()  # a touchdown
    assert_bit_identical(compiled, python)


def test_contact_log_and_strike_buffers_grow_without_changing_a_bit(walker, monkeypatch: pytest.MonkeyPatch) -> None:
    model, integrator = walker
    roomy = integrate_model(model.system, model.y0, model.modes0, integrator, 3.0, 200.0)
    make_recorder = recorder.make_recorder
    monkeypatch.setattr(recorder, "LOG_CAPACITY", 1)
    monkeypatch.setattr(driver, "make_recorder", lambda ny, nf, ns, nk, foot: make_recorder(ny, nf, ns, 1, foot))
    cramped = integrate_model(model.system, model.y0, model.modes0, integrator, 3.0, 200.0)
    assert len(cramped.strike_t) >= 5 and len(cramped.contact_log) >= 10
    assert_bit_identical(roomy, cramped)
