"""Shared fixtures: paths to the bundled configs and one simulation of the default walker."""

from __future__ import annotations

from pathlib import Path

import pytest

from biped_sim import load_config, simulate
from biped_sim.simulate import RunResult

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"
DEFAULT_CONFIG = CONFIGS / "round_foot_walker.yaml"


@pytest.fixture(scope="session")
def default_run() -> RunResult:
    """The default walker, as `make run` simulates it (15 s)."""
    return simulate(load_config(DEFAULT_CONFIG))
