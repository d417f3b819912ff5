"""Big compiled callees called by a stable symbol (biped_sim._symbol_calls): the symbol is the same in every
process, a cached caller loads its callees first, a callee that cannot be had makes the caller compile again, and a
cold run's code loads warm in a new process without a compile, its outputs unchanged."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from biped_sim import _symbol_calls
from biped_sim._symbol_calls import CalledBySymbol, StaleCalleeError, stable_symbol
from biped_sim.integrate.stepper import make_scratch
from biped_sim.testing import default_walker

ROOT = Path(__file__).resolve().parents[1]


def _symbol_of_a_scratch() -> str:
    args = (numba.typeof(make_scratch(3, 2, 1)), numba.typeof(np.zeros(3)), numba.types.literal(4))
    return stable_symbol("kernel", "biped_sim.integrate.dense", "dense_eval", args)


def test_the_numba_internals_it_relies_on_are_there() -> None:
    assert _symbol_calls.missing_internals() == []


def test_a_callees_symbol_is_the_same_in_another_process() -> None:
    code = "from tests.test_symbol_calls import _symbol_of_a_scratch; print(_symbol_of_a_scratch())"
    other = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert other.stdout.strip() == _symbol_of_a_scratch()


def test_a_type_spelled_with_an_address_has_no_stable_symbol() -> None:
    class Unstable:
        def __str__(self) -> str:
            return "<object at 0x7f00>"

    with pytest.raises(ValueError, match="at 0x"):
        stable_symbol("kernel", "biped_sim.x", "f", (Unstable(),))


def test_a_callee_that_cannot_be_had_makes_its_cached_caller_count_as_missing(monkeypatch: pytest.MonkeyPatch) -> None:
    missing = CalledBySymbol("kernel", "biped_sim.integrate.dense", "no_such_kernel", (), "biped_sim_callee_none")
    with pytest.raises(StaleCalleeError, match="no_such_kernel"):
        missing()

    def rebuild_needing_it(*args: object) -> object:
        missing()
        return "loaded"

    monkeypatch.setattr(_symbol_calls, "_numba_load_overload", rebuild_needing_it)
    assert _symbol_calls._load_overload(None, None, None) is None  # compiled again, not loaded with address 0


def _called_by_symbol(kernel: object) -> set[str]:
    """The callees that ``kernel``'s Python twin (compiled or loaded) calls by symbol."""
    return {
        item.qualname
        for cres in kernel.twin().overloads.values()  # type: ignore[attr-defined]
        for item in cres.reload_init
        if isinstance(item, CalledBySymbol)
    }


def test_the_rigid_phase_calls_its_flow_by_symbol_and_the_loop_inlines_its_right_hand_side() -> None:
    """The mechanism is on where it pays: the rigid stance phase in space calls its flow (a few array arguments) by
    symbol; the compliant loop keeps its right-hand side (the system's arrays at every stage) linked and inlined, and
    calls the kernels marked ``by_symbol`` (the checks' audit, the event's mode update) by symbol though their calls
    pass the system's arrays too."""
    from biped_sim import load_config, simulate
    from biped_sim.integrate.explicit import advance
    from biped_sim.rigid.space_integration import space_phase

    simulate(load_config(ROOT / "configs/space/tinkertoy.yaml", ["simulation.t_end=0.3"]))
    assert "space_flow" in _called_by_symbol(space_phase)
    simulate(default_walker(t_end=0.01))
    loop_calls = _called_by_symbol(advance)
    assert not any(name.startswith("rhs") for name in loop_calls)
    assert {"audit_overload", "system_update_modes"} <= loop_calls


@pytest.mark.slow
def test_a_cold_runs_code_loads_warm_in_another_process_with_the_same_outputs(tmp_path: Path) -> None:
    """On an empty cache, then again: the second process compiles nothing and writes the same numbers."""
    code = (
        "import json, sys\n"
        "from biped_sim._compiled_cache import recording_compilations\n"
        "from biped_sim import load_config, simulate\n"
        "with recording_compilations() as compiled:\n"
        "    result = simulate(load_config('configs/space/tinkertoy_compliant.yaml', ['simulation.t_end=1.5']))\n"
        "print(json.dumps({'compiled': len(compiled), 'y': result.run.y[-1].tolist()}))\n"
    )
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    runs = [
        json.loads(
            subprocess.run(
                [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True
            ).stdout.splitlines()[-1]
        )
        for _ in range(2)
    ]
    assert runs[0]["compiled"] > 0
    assert runs[1]["compiled"] == 0
    assert runs[1]["y"] == runs[0]["y"]


_LINKING_A_CACHED_CALLEE = """
import json, sys
from biped_sim._symbol_calls import CalledBySymbol
from biped_sim.config import Config
from biped_sim.integrate import blowup
from biped_sim.kernel import compile_for
from biped_sim.simulate import aside
fall, args = aside.loop_callees(Config(), aside._draft(Config())).check[0]
if sys.argv[1] == "callee":
    compile_for(blowup._check_now, args[:-1])
else:
    compile_for(fall, args)
    (cres,) = fall.overloads.values()
    print(json.dumps(sorted(c.qualname for c in cres.reload_init if isinstance(c, CalledBySymbol))))
"""


def test_a_caller_linking_a_cached_callee_lists_the_callees_it_calls_by_symbol(tmp_path: Path) -> None:
    """One process caches the checks (which call the audit by symbol); another compiles the fall kernel, which links
    the cached checks: the fall kernel lists the audit too, so a third process loading it loads the audit first (numba
    leaves a cached entry's list off its library: a segmentation fault at address 0, before the fix)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    outputs = [
        subprocess.run(
            [sys.executable, "-c", _LINKING_A_CACHED_CALLEE, role], cwd=ROOT, env=env, capture_output=True, text=True
        )
        for role in ("callee", "caller")
    ]
    assert all(out.returncode == 0 for out in outputs), outputs[-1].stderr
    assert "audit_overload" in json.loads(outputs[-1].stdout.splitlines()[-1])
