"""Feet of the walker in space and the gaits' stability: Coleman et al.'s toy on spheres instead of rings (the ring
thickened into a torus on the way), and the Kuo-type compass on feet rounded sideways (docs/guide/rigid.md's
tables)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import Config, load_config
from biped_sim.rigid.space_cycle import space_branch
from tests.conftest import invoke

SPACE = Path(__file__).resolve().parents[1] / "configs" / "space"
FOOT = "walker.description.leg.feet.foot"
TINKERTOY_SPHERE = SPACE / "tinkertoy_sphere.yaml"
RING_RADIUS = 0.1236  # the toy's ring: its radius in the leg's x-z plane (the sagittal radius kept below)
TUBES = (0.04, 0.08, 0.12)  # tori between the ring (tube 0) and the sphere (tube = RING_RADIUS)
TUBE_LARGEST = (0.891851, 0.910494, 0.922031)  # the largest multiplier's modulus of each, along one branch


@pytest.mark.slow
def test_the_tinkertoy_on_spheres_walks_stably() -> None:
    """configs/space/tinkertoy_sphere.yaml, found without a guess by `biped-sim limit-cycle` (the sagittal twin's
    gait continued), a stable gait next to the ring's: the mjcf comparison's stable walker in space."""
    result = invoke("limit-cycle", str(TINKERTOY_SPHERE), "--json")
    assert result.exit_code == 0, result.output
    cycle = json.loads(result.stdout)
    assert cycle["stable"]
    assert cycle["step_period"] == pytest.approx(1.00554930, abs=1e-8)
    assert cycle["step_length"] == pytest.approx(0.46668424, abs=1e-8)
    moduli = sorted(abs(complex(*m)) for m in cycle["multipliers"])
    np.testing.assert_allclose(moduli, [0.20497622, 0.70806333, 0.70806333, 0.78019328, 0.78019328, 0.92287531,
                                        0.92287531], atol=1e-6)  # fmt: skip


def tinkertoy_torus(tube: float) -> Config:
    """The toy with its ring thickened into a torus of ``tube``, its radius in the ring's plane kept (ring radius
    minus tube, so the foot's sagittal radius stays the ring's and its lateral radius is the tube)."""
    foot = [f"{FOOT}.shape=torus", f"{FOOT}.radius={RING_RADIUS - tube}", f"{FOOT}.tube={tube}"]
    return load_config(SPACE / "tinkertoy.yaml", foot)


@pytest.mark.slow
def test_rounding_the_rings_sideways_leaves_the_toy_stable() -> None:
    """Ring -> torus -> sphere along one branch: the largest multiplier grows with the lateral radius (0.8392 ring,
    0.9229 sphere) but stays inside the unit circle."""
    cycles = space_branch([load_config(SPACE / "tinkertoy.yaml"), *(tinkertoy_torus(t) for t in TUBES)])
    assert [c.converged for c in cycles] == [True] * (1 + len(TUBES))
    largest = [c.max_multiplier_modulus for c in cycles[1:]]
    assert largest == pytest.approx(TUBE_LARGEST, abs=1e-5)


KUO = SPACE / "kuo_compass_3d.yaml"
KUO_LATERAL = (0.2, 0.4, 0.6, 0.8, 1.0, 1.2)  # the torus's lateral radius [m]; fore-aft a point (tube 1 mm)
KUO_LATERAL_LARGEST = (4.452758, 2.999402, 2.244578, 1.924145, 1.776766, 1.669714)


def kuo_torus(lateral: float, tube: float = 0.001) -> Config:
    """The Kuo-type compass on a torus in its leg's y-z plane (normal x): fore-aft radius ``tube``, sideways
    ``lateral``; its bottom 1 m below the hip."""
    foot = [f"{FOOT}.shape=torus", f"{FOOT}.radius={lateral - tube}", f"{FOOT}.tube={tube}", f"{FOOT}.plane=lateral",
            f"{FOOT}.centre=[0, {lateral - 1.0}]"]  # fmt: skip
    return load_config(KUO, foot)


@pytest.mark.slow
def test_rounding_the_kuo_compass_sideways_shrinks_its_unstable_mode() -> None:
    """From point feet (1 mm spheres), along one branch: the largest multiplier falls with the feet's lateral radius
    (6.59 -> 1.67 at 1.2 m, past the centre of mass's 0.75 m) but stays outside the unit circle, its eigenvector's
    largest part the roll rate (docs/guide/rigid.md's table)."""
    point = load_config(KUO, ["walker.parameters.foot_radius=0.001"])
    cycles = space_branch([point, *(kuo_torus(v) for v in KUO_LATERAL)])
    assert [c.converged for c in cycles] == [True] * (1 + len(KUO_LATERAL))
    largest = [c.max_multiplier_modulus for c in cycles[1:]]
    assert largest == pytest.approx(KUO_LATERAL_LARGEST, abs=1e-5)
    for cycle in (cycles[1], cycles[-1]):
        values, vectors = np.linalg.eig(cycle.jacobian)
        mode = np.abs(vectors[:, np.argmax(np.abs(values))])
        assert cycle.section_names[int(np.argmax(mode))] == "omega_x"
