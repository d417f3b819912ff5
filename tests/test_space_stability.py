"""What keeps a compass in space laterally stable: Coleman et al.'s toy morphed into the Kuo-type compass along one
branch of gaits loses its stability early, and larger rings give it back there, feet rounded sideways and splay do not
(docs/guide/rigid.md's tables)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import Config, load_config
from biped_sim.rigid.limit_cycle import RIGID_TOLERANCE, map_jacobian, newton_fixed_point
from biped_sim.rigid.space_cycle import SpaceMap, space_branch, space_walker_model

TINKERTOY = Path(__file__).resolve().parents[1] / "configs" / "space" / "tinkertoy.yaml"
SPLAYED = TINKERTOY.with_name("tinkertoy_splayed.yaml")
LEG = "walker.description.leg"
# the toy's parameters (share 0) and the Kuo-type compass's made dimensionless (share 1: leg length 1, g = 1, the
# walker's mass 2: legs of 0.5 and 1 at the hip; a ring of 1 mm for its 1 mm spheres)
TOY = {"slope": 0.0702, "hip_width": 0.3624, "hip_mass": 0.0, "mass": 1.0, "com_y": 0.6969, "com_z": -0.6863,
       "xx": 0.1982, "yy": 0.0186, "zz": 0.1802, "xy": 0.0071, "xz": -0.0023, "yz": 0.0573,
       "radius": 0.1236}  # fmt: skip
KUO = {"slope": 0.0523598775598, "hip_width": 0.1, "hip_mass": 1.0, "mass": 0.5, "com_y": 0.0, "com_z": -0.5,
       "xx": 0.01, "yy": 0.0, "zz": 0.01, "xy": 0.0, "xz": 0.0, "yz": 0.0, "radius": 0.001}  # fmt: skip
SHARES = (0.0, 0.05, 0.1, 0.15, 0.2)
SHARE_LARGEST = (0.839156, 0.928384, 0.920254, 0.904529, 1.061926)  # the largest multiplier's modulus, one branch
LATERAL, LATERAL_LARGEST = 0.05, 1.075138  # at share 0.2: a torus of lateral radius 0.05, its sagittal radius kept
RINGS = (0.12, 0.15, 0.2)  # at share 0.2: the rings' radius (their sagittal radius; 0.09908 on the way)
RING_LARGEST = (0.935947, 0.931237, 1.106819)
# at share 0.2: its gait (the branch's fixed point, post-strike keys) and the legs splayed, outward and inward, along
# one branch from it in steps of 0.01 rad: the largest modulus
SHARE_GAIT = {
    "heading": 0.14307089,
    "bank": -0.0161079,
    "pitch": -0.21252614,
    "swing_angle": 0.3969457,
    "omega_x": -0.10070367,
    "omega_y": 0.41945524,
    "omega_z": -0.10356673,
    "swing_rate": -0.27126061,
}
SPLAYS = (tuple(0.01 * k for k in range(1, 9)), (-0.01, -0.02))
SPLAY_LARGEST = {0.01: 1.066630, 0.02: 1.073855, 0.04: 1.090199, 0.08: 1.111208, -0.02: 1.072386}
# the body frame's (x', y' up, z' out) tensor of the leg frame's (x, y out, z up) entries
BODY = {"xx": "xx", "yy": "zz", "zz": "yy", "xy": "xz", "xz": "xy", "yz": "yz"}


def interpolated(share: float) -> dict[str, float]:
    """Every parameter at ``share`` of the way from the toy (0) to the Kuo-type compass (1), linearly."""
    return {key: (1.0 - share) * TOY[key] + share * KUO[key] for key in TOY}


def toy_to_kuo(share: float, lateral: float = 0.0, ring: float | None = None) -> Config:
    """The walker at ``share`` of the way from the toy to the Kuo-type compass, every parameter interpolated linearly
    (ring feet whose radius goes from 0.1236 to 1 mm, their bottom 1 below the hip); ``ring``: another ring radius;
    ``lateral`` > 0: the ring made a torus of that tube (lateral radius), its sagittal radius (radius + tube) kept."""
    q = interpolated(share)
    q["radius"] = q["radius"] if ring is None else ring
    inertia = ", ".join(f"{key}: {q[leg]}" for key, leg in BODY.items())
    overrides = [f"ground.slope={q['slope']}", f"walker.parameters.hip_width={q['hip_width']}",
                 f"walker.parameters.hip_mass={q['hip_mass']}", f"{LEG}.bodies.leg.mass={q['mass']}",
                 f"{LEG}.bodies.leg.com=[0, {q['com_z']}]", f"{LEG}.bodies.leg.com_lateral={q['com_y']}",
                 f"{LEG}.bodies.leg.inertia_tensor={{{inertia}}}", f"{LEG}.feet.foot.radius={q['radius'] - lateral}",
                 f"{LEG}.feet.foot.centre=[0, {q['radius'] - 1.0}]"]  # fmt: skip
    if lateral:
        overrides += [f"{LEG}.feet.foot.shape=torus", f"{LEG}.feet.foot.tube={lateral}"]
    return load_config(TINKERTOY, overrides)


def splayed(share: float, splay: float) -> Config:
    """The walker at ``share`` (:func:`toy_to_kuo`) with each leg turned outward by ``splay`` about its forward axis
    through its hip point, written as plain geometry (configs/space/tinkertoy_splayed.yaml, the leg's numbers given
    unsplayed in its body frame)."""
    q = interpolated(share)
    parameters = {
        "splay": splay,
        "hip_width": q["hip_width"],
        "foot_radius": q["radius"],
        "hip_mass": q["hip_mass"],
        "com_along": q["com_z"],
        "com_out": q["com_y"],
    } | {f"I{key}": q[leg] for key, leg in BODY.items()}
    overrides = [f"ground.slope={q['slope']}", f"{LEG}.bodies.leg.mass={q['mass']}"]
    return load_config(SPLAYED, overrides + [f"walker.parameters.{name}={value}" for name, value in parameters.items()])


@pytest.mark.slow
def test_the_toy_loses_its_stability_on_the_way_to_the_kuo_compass_and_larger_feet_give_it_back() -> None:
    """Along one branch from the toy: the largest multiplier leaves the unit circle between share 0.15 and 0.2 (a
    complex pair: hinge rate, yaw rate and pitch). There, rounding the feet sideways only (a torus) does not bring it
    back; a larger ring (the sagittal radius) does, in a window: stable at 0.12 and 0.15, a flip past -1 at 0.2."""
    share = SHARES[-1]
    walkers = [toy_to_kuo(s) for s in SHARES] + [toy_to_kuo(share, LATERAL), toy_to_kuo(share)]
    walkers += [toy_to_kuo(share, ring=r) for r in RINGS]
    cycles = space_branch(walkers)
    assert [c.converged for c in cycles] == [True] * len(walkers)
    largest = [c.max_multiplier_modulus for c in cycles]
    assert largest[: len(SHARES)] == pytest.approx(SHARE_LARGEST, abs=1e-5)
    assert largest[len(SHARES)] == pytest.approx(LATERAL_LARGEST, abs=1e-5)
    assert largest[-len(RINGS) :] == pytest.approx(RING_LARGEST, abs=1e-5)
    assert largest[len(SHARES) - 2] < 1.0 < largest[len(SHARES) - 1] < largest[len(SHARES)]
    assert max(largest[-len(RINGS) : -1]) < 1.0 < largest[-1]


def test_splay_at_share_0_2_raises_the_largest_multiplier_either_way() -> None:
    """At share 0.2, just past the loss: the splayed walker written as data is, unsplayed, the homotopy's to the
    bit, and its gait the branch's (1.061926); the legs splayed outward (to 0.08 rad) or inward (to -0.02) along one
    branch from it, in steps of 0.01, the largest modulus grows: splay does not give stability back there."""
    share = SHARES[-1]
    assert repr(splayed(share, 0.0).walker.space) == repr(toy_to_kuo(share).walker.space)
    found = {}
    for splays in SPLAYS:
        z = SpaceMap(space_walker_model(splayed(share, 0.0))).section.of_keys(SHARE_GAIT)
        for splay in (0.0, *splays):
            step_map = SpaceMap(space_walker_model(splayed(share, splay)))
            z, converged, _, _ = newton_fixed_point(step_map, z, RIGID_TOLERANCE)
            assert converged
            found[round(splay, 10)] = float(max(abs(np.linalg.eigvals(map_jacobian(step_map, z)))))
    assert found[0.0] == pytest.approx(SHARE_LARGEST[-1], abs=1e-5)
    assert {splay: found[splay] for splay in SPLAY_LARGEST} == pytest.approx(SPLAY_LARGEST, abs=1e-5)
    outward = [found[splay] for splay in sorted(found) if splay >= 0.0]
    assert outward == sorted(outward) and found[-0.02] > found[0.0]
