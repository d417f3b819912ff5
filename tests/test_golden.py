"""Golden summaries: the bundled configs, re-simulated, reproduce their recorded summary.json bit for bit.

tests/data/golden_summaries.json holds, for 14 cases (a bundled config and ``--set`` overrides), the
summary recorded before the refactor of the compiled core: step times and periods, energies dissipated,
the energy residual, constraint violations, step count, status, RHS evaluations and the rest. The
comparison is exact: a refactor that means to keep the numerics must keep every bit; one that changes
them on purpose re-records the file and says why. The short cases (up to 10 s of cheap dynamics) are
in the fast tier, the full-length compliant runs (15 s default walker, 12 s four-legged walker) in the
slow tier.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from biped_sim import load_config, simulate

from .conftest import ROOT

_FILE = json.loads((Path(__file__).parent / "data" / "golden_summaries.json").read_text())
GOLDEN = _FILE["cases"]
TOUCHDOWN_MEMORY = _FILE["touchdown_memory"]["cases"]  # as recorded before contact.impact_memory: impact
FULL_LENGTH = {"round_foot_walker", "four_legged_walker"}  # 2-4 s of wall time each
MISSING = object()


def test_golden_file_has_the_bundled_configs_and_their_short_variants() -> None:
    assert len(GOLDEN) == 14
    assert {Path(case["config"]).stem for case in GOLDEN.values()} == {
        path.stem for path in (ROOT / "configs").glob("*.yaml")
    }
    assert set(GOLDEN) >= FULL_LENGTH


def _tiered(cases: dict[str, Any]) -> list[Any]:
    return [pytest.param(name, marks=pytest.mark.slow) if name in FULL_LENGTH else name for name in cases]


@pytest.mark.parametrize("name", _tiered(GOLDEN))
def test_bundled_config_reproduces_its_golden_summary_exactly(name: str) -> None:
    _assert_reproduces(GOLDEN[name])


@pytest.mark.parametrize("name", _tiered(TOUCHDOWN_MEMORY))
def test_touchdown_impact_memory_reproduces_the_summaries_recorded_before_the_option(name: str) -> None:
    """contact.impact_memory=touchdown is the earlier behaviour, bit for bit, where the new default moved numbers."""
    assert TOUCHDOWN_MEMORY[name]["overrides"][-1] == "contact.impact_memory=touchdown"
    _assert_reproduces(TOUCHDOWN_MEMORY[name])


def _assert_reproduces(case: dict[str, Any]) -> None:
    result = simulate(load_config(ROOT / case["config"], case["overrides"]))
    summary: dict[str, Any] = json.loads(json.dumps(result.summary))  # as summary.json holds it
    differences = {
        key: {"now": summary.get(key, MISSING), "golden": golden}
        for key, golden in case["summary"].items()
        if summary.get(key, MISSING) != golden
    }
    assert differences == {}
