"""Golden summaries: the bundled configs, re-simulated, reproduce their recorded summary.json.

tests/data/golden_summaries.json holds, for 24 cases (a bundled config and ``--set`` overrides), the summary
of their run and what its arithmetic goes through (``arithmetic``), which says how it is compared (the file's
``classes``). A case whose numbers come from the project's compiled loops alone (``compiled``) must match bit
for bit on any x86 CPU: a refactor that means to keep the numerics must keep every bit, and one that changes
them on purpose re-records the file (``python -m tests.record_golden``) and says why. A case that goes through
scipy, BLAS or LAPACK, whose kernels the CPU chooses, must match its physical quantities to the class's
relative tolerance (per element, some keys with their own), its noise-floor quantities (energy residuals,
constraint violations) must stay below ``noise_floor`` times the recorded value, and its solver counters within
``counters`` (relative): a step accepted on one CPU may be rejected on another. Strings, statuses, step counts
and feet are exact in every class. The short cases are in the fast tier, the full-length compliant runs in the
slow tier. The same tier runs under ``make test-older-cpu`` (numpy's dispatch and OpenBLAS limited to an AVX2
CPU), which is how these classes were checked. The ``*_touchdown_memory`` cases are the compliant ones with
``contact.impact_memory=touchdown``: the behaviour before that option, pinned to the numbers recorded before it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from .conftest import ROOT
from .record_golden import GOLDEN_PATH, read_golden, record, simulated_summary

GOLDEN = read_golden()
CASES = GOLDEN["cases"]
FULL_LENGTH = {"round_foot_walker", "four_legged_walker", "kneed_walker_compliant"}  # 2-9 s of wall time each
TOUCHDOWN = "_touchdown_memory"  # suffix of the cases pinned to the behaviour before contact.impact_memory
COUNTERS = ("rhs_evals", "accepted_steps", "rejected_steps", "events")
NOISE_FLOOR = ("energy_residual_max", "energy_residual_max_relative", "constraint_violation_max")
MISSING = object()


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _close(now: Any, golden: Any, key: str, rules: dict[str, Any]) -> bool:
    """Whether one recorded value (a number, a list, a mapping or anything else) holds, by the class's ``rules``."""
    if rules.get("exact"):
        return now == golden
    if isinstance(golden, dict):
        return (
            isinstance(now, dict)
            and set(now) >= set(golden)
            and all(_close(now[k], golden[k], key, rules) for k in golden)
        )
    if isinstance(golden, list):
        return (
            isinstance(now, list)
            and len(now) == len(golden)
            and all(_close(a, b, key, rules) for a, b in zip(now, golden, strict=True))
        )
    if key in NOISE_FLOOR:
        return _number(now) and now <= rules["noise_floor"] * golden
    if key in COUNTERS:
        return _number(now) and abs(now - golden) <= rules["counters"] * golden
    if isinstance(golden, float) and _number(now):
        return math.isclose(now, golden, rel_tol=rules.get(key, rules["relative"]), abs_tol=0.0)
    return now == golden


def differences(now: dict[str, Any], case: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The recorded keys whose values do not hold: {key: {'now': ..., 'golden': ...}}."""
    rules = GOLDEN["classes"][case["arithmetic"]]
    return {
        key: {"now": now.get(key, MISSING), "golden": golden}
        for key, golden in case["summary"].items()
        if not _close(now.get(key, MISSING), golden, key, rules)
    }


def test_golden_file_has_the_bundled_configs_their_short_variants_and_a_class_each() -> None:
    assert len(CASES) == 25
    touchdown = {name for name in CASES if name.endswith(TOUCHDOWN)}
    assert {name.removesuffix(TOUCHDOWN) for name in touchdown} <= {  # the compiled cases the default moved
        name for name, case in CASES.items() if case["arithmetic"] == "compiled" and name not in touchdown
    }
    assert all(CASES[name]["overrides"][-1] == "contact.impact_memory=touchdown" for name in touchdown)
    assert {Path(case["config"]).stem for case in CASES.values()} == {
        path.stem for path in (ROOT / "configs").glob("*.yaml")
    }
    assert set(CASES) >= FULL_LENGTH
    assert {case["arithmetic"] for case in CASES.values()} <= set(GOLDEN["classes"])
    # the cases that run the project's compiled loops alone (the rigid runs from a given start too) are pinned bit
    # for bit; a start on the rigid limit cycle goes through LAPACK (Newton's solve)
    assert {name for name, case in CASES.items() if case["arithmetic"] != "compiled"} == {
        "kneed_walker", "radau_short", "rigid_cycle_start"
    }  # fmt: skip


def test_a_class_tolerates_what_it_says_and_no_more() -> None:
    case = {"arithmetic": "scipy", "summary": {"step_times": [1.0, 2.0], "rhs_evals": 10_000, "n_steps": 2,
            "energy_residual_max": 1e-12, "status": "walking"}}  # fmt: skip
    ulps = {"step_times": [1.0 + 4e-16, 2.0], "rhs_evals": 10_005, "n_steps": 2, "energy_residual_max": 5e-12,
            "status": "walking"}  # fmt: skip
    assert differences(ulps, case) == {}
    moved = {**ulps, "step_times": [1.0 + 1e-11, 2.0], "rhs_evals": 10_020, "n_steps": 3, "energy_residual_max": 1e-9}
    assert set(differences(moved, case)) == {"step_times", "rhs_evals", "n_steps", "energy_residual_max"}
    assert set(differences(ulps, {**case, "arithmetic": "compiled"})) == {"step_times", "rhs_evals",
                                                                          "energy_residual_max"}  # fmt: skip


def test_re_recording_a_compiled_case_moves_nothing(tmp_path: Path) -> None:
    """``python -m tests.record_golden CASE`` on a copy: the case's summary again, bit for bit, the rest kept."""
    copy = tmp_path / "golden.json"
    copy.write_text(GOLDEN_PATH.read_text())
    assert record(["rk4_short"], copy) == {"rk4_short": []}
    again = read_golden(copy)
    assert again["cases"] == GOLDEN["cases"] and again["classes"] == GOLDEN["classes"]


@pytest.mark.parametrize(
    "name",
    [pytest.param(n, marks=pytest.mark.slow) if n.removesuffix(TOUCHDOWN) in FULL_LENGTH else n for n in CASES],
)
def test_bundled_config_reproduces_its_golden_summary(name: str) -> None:
    case = CASES[name]
    assert differences(simulated_summary(case), case) == {}


def test_the_compliant_kneed_walker_takes_its_golden_first_steps() -> None:
    """The fast tier's short version of the full-length kneed case (slow tier): its first two steps, run alone, bit
    for bit (a run's arithmetic up to a strike does not depend on where it ends)."""
    case = CASES["kneed_walker_compliant"]
    short = simulated_summary({**case, "overrides": [*case["overrides"], "simulation.t_end=1.2"]})
    assert len(short["step_times"]) == 2
    for key in ("step_times", "step_feet", "step_periods", "step_lengths"):
        assert short[key] and short[key] == case["summary"][key][: len(short[key])], key
