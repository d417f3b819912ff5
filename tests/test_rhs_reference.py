"""The compiled right-hand side agrees with the plain-Python reference on random states."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from biped_sim import config_from_dict
from biped_sim.contact.friction import FRICTION_LAWS
from biped_sim.contact.normal import NORMAL_LAWS
from biped_sim.multibody.dispatch import make_workspace
from biped_sim.multibody.planar import rhs
from biped_sim.multibody.reference import reference_rhs
from biped_sim.walkers import build_model


@pytest.mark.parametrize(("normal", "friction"), list(itertools.product(NORMAL_LAWS, FRICTION_LAWS)))
def test_compiled_rhs_matches_reference(normal: str, friction: str) -> None:
    model = build_model(config_from_dict({}, [f"contact.model={normal}", f"friction.model={friction}"]))
    work = make_workspace(model.system)
    rng = np.random.default_rng(7)
    scale = np.r_[np.full(6, 2e-3), np.full(6, 0.5), np.full(2, 1e-6), np.zeros(2)]
    for _ in range(25):
        y = model.y0 + rng.normal(size=model.y0.shape) * scale
        modes = model.modes0.copy()
        modes[:, 0] = 1.0
        modes[:, 1] = rng.integers(0, 2, size=2)
        modes[:, 2] = rng.uniform(0.01, 1.0, size=2)
        compiled = np.zeros_like(y)
        rhs(0.0, y, model.system, modes, work, compiled)
        expected = reference_rhs(0.0, y, model.system, modes)
        np.testing.assert_allclose(compiled, expected, rtol=1e-12, atol=1e-12 * np.max(np.abs(expected)))
