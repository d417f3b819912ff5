"""Warm-up: compile (or load from numba's on-disk cache) the kernels of a run before it is timed or awaited.

A compliant run needs the compiled code of its group only: its formulation's kernels and its
integrator family's loop (every explicit method shares one compiled loop, Radau and BDF share the
scipy driver's compiled right-hand side), specialised for its ground (the flat ground, or a profile) and for
whether its walker has joint stops and whether it has joint elements (a described walker's; one without compiles
none of their code).
Every contact law is part of each group's kernels (the laws are dispatched at run time). Every rigid run
shares one group, the compiled step map (its walker is data), warmed by one step and by a walk of one start (the
basin's walks); a rigid walker in space has its
own (its flow, ``rigid.space_kernels``).
:func:`warm_up` runs a config for a millisecond once per process and group; ``biped-sim warmup`` (and
``make setup``) warms ``BUNDLED_GROUPS``, the groups of the bundled configs (walkers in space too) and sweeps, of
a run on a ground profile (in the plane and in space), of the bundled configs' fits and uncertainty samples, of the
default walker's MFPT (its walks in minimal coordinates on a profile) and of its run with a stiff method (tests keep
the list true), ``--all``
every formulation, integrator family and ground the package has, each group in a process of its own, one per
core at a time (:func:`warm_up_in_processes`); a sweep's workers warm each group before its first timed run,
and a Dask worker can warm itself at start (:mod:`biped_sim.sweep.preload`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from typing import get_args

import numpy as np

from biped_sim._compiled_cache import recording_compilations
from biped_sim.config import Config, FormulationConfig, derive
from biped_sim.config.space_description import SPACE_STATE_KEYS
from biped_sim.integrate.driver import STIFF_METHODS
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import walk_starts
from biped_sim.simulate import simulate
from biped_sim.walkers.describe import describe

WARM_UP_TIME = 0.001  # [s] simulated by a warm-up run
# a profile the warm-up's millisecond never reaches (its code is compiled all the same)
WARM_UP_PROFILE = {"kind": "steps", "steps": [{"at": 100.0, "height": -0.01}]}
GROUNDS = ("flat", "profile")
JOINT_STOPS = " with joint stops"  # a group's ground ends with it when its walkers have joint stops
JOINT_ELEMENTS = " with joint elements"  # ... with this when they have joint elements (after JOINT_STOPS: both)
JOINTS = ("", JOINT_STOPS, JOINT_ELEMENTS, JOINT_STOPS + JOINT_ELEMENTS)
RIGID = ("rigid", "step map")  # the group of every rigid run: one compiled step map for every walker
RIGID_SPACE = ("rigid", "step map in space")  # ... but a walker in space's: its own flow (rigid.space_kernels)
# a walker in space for its group's warm-up: a compass with hip width and point feet, started leaning forward
SPACE_WALKER = {
    "kind": "description",
    "description": {
        "leg": {"bodies": [{"name": "leg", "mass": 1.0, "com": [0.0, -0.5],
                            "inertia_tensor": {"xx": 0.08, "yy": 0.001, "zz": 0.08}}],
                "feet": [{"name": "foot", "body": "leg", "centre": [0.0, -1.0]}]},
        "hip": {"lateral": -0.1},
    },
}  # fmt: skip
SPACE_START = dict.fromkeys(SPACE_STATE_KEYS, 0.0) | {"pitch": -0.2, "swing_angle": 0.4, "omega_y": 1.0}
# (formulation, integrator family, ground) of the bundled configs (configs/ and configs/space/) and sweeps, of a run
# on a profile (in the plane and in space), of the bundled configs' studies (fit and uncertainty run a planar walker
# in minimal coordinates; the default walker's MFPT, on a profile) and of the default walker with a stiff method (a
# golden case's) (the costliest first: the parallel warm-up ends sooner)
BUNDLED_GROUPS = (
    (*RIGID, "flat"), ("spatial", "explicit", "flat"), (*RIGID_SPACE, "flat"), ("spatial", "explicit", "profile"),
    ("planar", "explicit", "profile"), ("minimal", "explicit", "profile"),
    ("planar", "explicit", "flat" + JOINT_STOPS), ("minimal", "explicit", "flat" + JOINT_STOPS),
    ("minimal", "explicit", "flat"), ("minimal", "explicit", "flat" + JOINT_ELEMENTS),
    ("planar", "explicit", "flat" + JOINT_ELEMENTS), ("planar", "stiff", "flat"), ("planar", "explicit", "flat"),
)  # fmt: skip
_WARMED: set[tuple[str, str, str]] = set()


@dataclass(frozen=True)
class WarmUp:
    """What warming one group took: the functions numba compiled (none: all came from the cache), wall time."""

    formulation: str  # or 'rigid'
    family: str  # 'explicit' or 'stiff' (or 'step map')
    ground: str  # 'flat' or 'profile', then JOINT_STOPS, JOINT_ELEMENTS for walkers with joint stops, elements
    method: str  # the integrator the group was warmed with
    compiled: tuple[str, ...]
    seconds: float

    def line(self) -> str:
        """One line for the terminal."""
        how = f"compiled {len(self.compiled)} functions" if self.compiled else "loaded from the cache"
        plain, *joints = self.ground.split(" with ")
        ground = ("" if plain == "flat" else f", on a {plain}") + "".join(f", with {joint}" for joint in joints)
        method = "" if (self.formulation, self.family) in (RIGID, RIGID_SPACE) else f" ({self.method}{ground})"
        return f"{self.formulation} {self.family}{method}: {how} in {self.seconds:.1f} s"


def integrator_family(method: str) -> str:
    """'stiff' (scipy's Radau/BDF over the compiled right-hand side) or 'explicit' (the compiled loop)."""
    return "stiff" if method in STIFF_METHODS else "explicit"


def ground_of(config: Config) -> str:
    """'flat' or 'profile': which specialisation of the kernels a run compiles."""
    return "flat" if config.ground.profile.kind == "flat" else "profile"


def has_joint_stops(config: Config) -> bool:
    """Whether the walker has joint stops (only a described one may): its kernels then compile their code."""
    description = config.walker.description
    return description is not None and any(joint.stops for joint in description.joints)


def has_joint_elements(config: Config) -> bool:
    """Whether the walker has joint elements (only a described one may): its kernels then compile their code."""
    description = config.walker.description
    return description is not None and any(joint.elements for joint in description.joints)


def group_of(config: Config) -> tuple[str, str, str]:
    """A run's group: (formulation, integrator family, ground, then JOINT_STOPS and JOINT_ELEMENTS for a walker that
    has them);
    a rigid run's is ('rigid', 'step map', ground): the step map is one for every walker."""
    if config.dynamics == "rigid":
        return (*(RIGID_SPACE if config.in_space else RIGID), ground_of(config))
    joints = (JOINT_STOPS if has_joint_stops(config) else "") + (JOINT_ELEMENTS if has_joint_elements(config) else "")
    ground = ground_of(config) + joints
    return config.formulation.kind, integrator_family(config.integrator.method), ground


def warm_up(config: Config) -> WarmUp | None:
    """Run ``config`` for a millisecond (a rigid one for one step), once per process and group.

    Returns what it took, or None when there was nothing to do: a group already warmed in this process.
    """
    group = group_of(config)
    if group in _WARMED:
        return None
    if config.dynamics == "rigid":
        short = derive(config, {"simulation.max_steps": 1})
    else:  # at least one step and one sample after the start, so that the short run passes the run's own checks
        t_end = max(WARM_UP_TIME, config.integrator.dt)
        short = derive(config, {"simulation.t_end": t_end, "output.sample_rate": 1 / t_end})
    start = time.perf_counter()
    with recording_compilations() as compiled:
        simulate(short).trajectory()  # the run and every measure of its files (computed when asked)
        if group[:2] == RIGID:  # and the step map's walks of many starts (basins): compiled, none taken
            walker = rigid_walker(short)
            walk_starts(walker, np.zeros((1, 2 * walker.n_q)), 0)
    _WARMED.add(group)
    return WarmUp(*group, config.integrator.method, tuple(compiled), time.perf_counter() - start)


def available_cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def warm_up_in_processes(configs: Sequence[Config], workers: int | None = None) -> list[WarmUp | None]:
    """:func:`warm_up` each config in a process of its own, ``workers`` at a time (default: one per core), in order.

    numba compiles one function at a time in a process (its compiler lock), so groups compile in parallel only
    in separate processes; each writes the on-disk cache, from which this process and every later one load.
    A config whose group this process warmed already is None (nothing to do), as in warm_up.
    """
    groups: dict[tuple[str, str, str], Config] = {}  # the first config of each group still to warm
    for config in configs:
        if group_of(config) not in _WARMED:
            groups.setdefault(group_of(config), config)
    todo = list(groups.values())
    workers = min(len(todo), workers or available_cores())
    if workers <= 1:
        done = {id(config): warm_up(config) for config in todo}
    else:
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
            done = dict(zip(map(id, todo), pool.map(warm_up, todo), strict=True))
        _WARMED.update(group_of(config) for config in todo)
    return [done.get(id(config)) for config in configs]


def group_config(formulation: str, family: str, ground: str) -> Config:
    """The default walker (the schema's defaults) in a group (every formulation models every ground and joint)."""
    if (formulation, family) == RIGID:
        values: dict[str, object] = {"dynamics": "rigid"}
    elif (formulation, family) == RIGID_SPACE:
        values = {"dynamics": "rigid", "walker": SPACE_WALKER, "simulation.initial": SPACE_START}
    else:
        method = Config().integrator.method if family == "explicit" else STIFF_METHODS[0]
        values = {"formulation.kind": formulation, "integrator.method": method}
    if ground.split(" with ")[0] == "profile":
        values["ground.profile"] = WARM_UP_PROFILE
    config = derive(Config(), values)  # the schema's defaults
    return _with_joints(config, JOINT_STOPS in ground, JOINT_ELEMENTS in ground) if " with " in ground else config


def _with_joints(config: Config, stop: bool, element: bool) -> Config:
    """``config``'s walker described, with a stop at its hip that its warm-up never reaches and (or) a hip spring
    (ConfigError under a formulation that does not take a described walker)."""
    description = describe(config).model_dump()
    if stop:
        description["joints"][0]["stops"] = [{"side": "upper", "angle": 1.0}]
    if element:
        description["joints"][0]["elements"] = [{"name": "spring", "law": "linear_spring", "stiffness": 1.0}]
    return derive(config, {"walker": {"kind": "description", "description": description}})


def warm_up_configs(every_group: bool = False) -> list[Config]:
    """The default walker in each of ``BUNDLED_GROUPS``; with ``every_group``, in every formulation x integrator
    family x ground (with and without joint stops and elements) there is, and rigid."""
    if not every_group:
        return [group_config(*group) for group in BUNDLED_GROUPS]
    configs = [group_config(*RIGID, "flat"), group_config(*RIGID_SPACE, "flat")]
    for kind in get_args(FormulationConfig.model_fields["kind"].annotation):
        for family in ("explicit", "stiff"):
            configs += [group_config(kind, family, ground + joints) for ground in GROUNDS for joints in JOINTS]
    return configs
