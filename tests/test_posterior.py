"""Posterior files: what a fit writes is what the uncertainty study reads; damaged files are one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from biped_sim.errors import ConfigError
from biped_sim.io.posterior import POSTERIOR_FILE, Posterior, read_posterior, write_posterior


def test_posterior_round_trips_through_its_file(tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    posterior = Posterior(
        ("walker.leg_inertia", "contact.restitution"), rng.normal(size=(50, 2)), rng.normal(size=50), "a: 1\n"
    )
    write_posterior(tmp_path / POSTERIOR_FILE, posterior, {"config_hash": "abc"})
    back = read_posterior(tmp_path)  # a fit directory is enough
    assert back.parameters == posterior.parameters and back.config_yaml == "a: 1\n"
    assert np.array_equal(back.samples, posterior.samples)
    assert np.array_equal(back.log_probability, posterior.log_probability)


def test_missing_or_foreign_posterior_is_a_one_line_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no posterior here"):
        read_posterior(tmp_path)
    (tmp_path / POSTERIOR_FILE).write_bytes(b"not hdf5")
    with pytest.raises(ConfigError, match="not a posterior file"):
        read_posterior(tmp_path)


def test_posterior_shape_must_match_its_parameters() -> None:
    with pytest.raises(ValueError, match="samples must be"):
        Posterior(("a",), np.zeros((3, 2)), np.zeros(3), "")
