"""The bundled walker kinds as walker descriptions (:class:`~biped_sim.config.WalkerDescription`).

``describe(config)`` is the one place where a bundled kind's parameters become bodies, joints and feet; a
``walker.kind: description`` config is its own description. Every model is built from the result: rigid
(:mod:`biped_sim.rigid.build`) and compliant (:mod:`biped_sim.walkers.described`, lifted into the spatial formulation by
:mod:`biped_sim.walkers.spatial_described`). Body and foot names: ``leg0``, ``foot0``, ...

A preset stays a typed record of its parameters (the schema's member of its kind, ``walker.parameters.NAME``
addressing its fields) expanded here, rather than a description template of named parameters: its fields carry
units, bounds and cross-checks (a foot radius below the leg length, a centre of mass within reach) that a
description's named parameters, plain numbers, do not; the rimless wheel's spoke count makes feet, which no
arithmetic expression can; and its resolved config stays the few numbers a user wrote.
"""

from __future__ import annotations

import math

from biped_sim.config import BodySpec, Config, FootSpec, JointSpec, PointMassSpec, WalkerDescription
from biped_sim.walkers.four_legged import BODY_NAMES, FOOT_BODY, FOOT_NAMES, FOOT_SIDE, leg_pairs


def _compass(config: Config) -> WalkerDescription:
    """Two legs (mass m at c along and w across, inertia I) hinged at the hip, half the hip mass on each, feet
    arcs of radius R centred l - R along and d across the leg."""
    w = config.walker
    legs = ["leg0", "leg1"]
    return WalkerDescription(
        bodies=[BodySpec(name=n, mass=w.leg_mass, inertia=w.leg_inertia, com=(w.leg_com_offset, -w.leg_com_from_hip))
                for n in legs],
        point_masses=[PointMassSpec(name=f"hip{i}", body=n, mass=0.5 * w.hip_mass) for i, n in enumerate(legs)],
        joints=[JointSpec(name="hip", parent="leg0", child="leg1")],
        feet=[FootSpec(name=f"foot{i}", body=n, centre=(w.foot_offset, -(w.leg_length - w.foot_radius)),
                       radius=w.foot_radius) for i, n in enumerate(legs)],
        legs=[["leg0"], ["leg1"]],
    )  # fmt: skip


def _simplest(config: Config) -> WalkerDescription:
    """Garcia's simplest walker: massless legs of length 1, a unit hip mass, point feet (its infinitesimal foot
    masses are the limit the rigid model's own equations take, MODEL.md 8)."""
    legs = ["leg0", "leg1"]
    return WalkerDescription(
        bodies=[BodySpec(name=n, mass=0.0) for n in legs],
        point_masses=[PointMassSpec(name="hip", body="leg0", mass=1.0)],
        joints=[JointSpec(name="hip", parent="leg0", child="leg1")],
        feet=[FootSpec(name=f"foot{i}", body=n, centre=(0.0, -1.0)) for i, n in enumerate(legs)],
        legs=[["leg0"], ["leg1"]],
    )


def _rimless_wheel(config: Config) -> WalkerDescription:
    """One body, a unit point mass at the hub, N massless spokes of length l ending in point feet."""
    w = config.walker
    spokes = [2.0 * math.pi * k / w.spokes for k in range(w.spokes)]
    return WalkerDescription(
        bodies=[BodySpec(name="wheel", mass=1.0)],
        feet=[FootSpec(name=f"spoke{k}", body="wheel", centre=(w.leg_length * math.sin(a), -w.leg_length * math.cos(a)))
              for k, a in enumerate(spokes)],
        legs=[["wheel"]],
    )  # fmt: skip


def _four_legged(config: Config) -> WalkerDescription:
    """Liu's machine: each pair of legs one body (its mass, centre of mass and inertia tensor, the cross bar and half
    the hip mass folded in), two feet per pair at one sagittal place, either side of it along the axle."""
    w = config.walker
    masses, offsets, inertia = leg_pairs(config)
    spacing = (w.foot_spacing_outer, w.foot_spacing_inner)
    return WalkerDescription(
        bodies=[BodySpec(name=n, mass=float(masses[b]), inertia=float(inertia[b, 2, 2]),
                         spatial_inertia=(float(inertia[b, 0, 0]), float(inertia[b, 1, 1]), float(inertia[b, 0, 1])),
                         com=(offsets[b][1], -offsets[b][0])) for b, n in enumerate(BODY_NAMES)],
        joints=[JointSpec(name="hip", parent=BODY_NAMES[0], child=BODY_NAMES[1])],
        feet=[FootSpec(name=n, body=BODY_NAMES[FOOT_BODY[k]], centre=(w.foot_offset, -(w.leg_length - w.foot_radius)),
                       radius=w.foot_radius, lateral=FOOT_SIDE[k] * 0.5 * spacing[FOOT_BODY[k]])
              for k, n in enumerate(FOOT_NAMES)],
        legs=[[BODY_NAMES[0]], [BODY_NAMES[1]]],
    )  # fmt: skip


DESCRIBERS = {"compass": _compass, "simplest": _simplest, "rimless_wheel": _rimless_wheel, "four_legged": _four_legged}


def describe(config: Config) -> WalkerDescription:
    """The walker of ``config`` as a description: its own for ``walker.kind: description``, else its kind's."""
    if config.walker.description is not None:
        return config.walker.description
    return DESCRIBERS[config.walker.kind](config)
