"""The validation report's rows and the configs its checks share (:mod:`.validation`, :mod:`.validation_studies`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from biped_sim.config import Config, config_from_dict

CONFIGS = Path(__file__).resolve().parents[3] / "configs"


@dataclass
class Check:
    """One line of the validation report."""

    group: str
    check: str
    expected: str
    obtained: str
    tolerance: str
    passed: bool

    def __post_init__(self) -> None:
        self.passed = bool(self.passed)  # numpy booleans are not JSON


def close(group: str, check: str, expected: float, obtained: float, tolerance: float) -> Check:
    ok = bool(math.isfinite(obtained) and abs(obtained - expected) <= tolerance)
    return Check(group, check, f"{expected:.14g}", f"{obtained:.14g}", f"{tolerance:g}", ok)


def simplest_config(slope: float) -> Config:
    """Garcia's simplest walker on ``slope`` (rigid), started near its gait."""
    return config_from_dict(
        {
            "dynamics": "rigid",
            "walker": {"kind": "simplest"},
            "ground": {"slope": slope},
            "simulation": {
                "initial": {"stance_angle": 0.2, "stance_rate": -0.2, "swing_angle": -0.2, "swing_rate": -0.18}
            },
        }
    )
