"""The walker registry: what each walker kind supports, declared once (as a propagator declares its capabilities).

For each ``walker.kind``: the formulations it runs in under each dynamics (compliant: planar, minimal, spatial;
rigid: the reduced planar model), whether it walks on ground profiles and takes pushes, the studies it
supports, and what else differs between walkers (units, massless legs, the strike check). The schema's
cross-checks, the ground-profile rules and the studies' guards read :func:`refusal`, :func:`supports_study` and
:func:`capabilities`, so a rule lives here and nowhere else: nothing outside this module branches on a walker's
kind (``tests/test_walker_model.py`` scans the package); what follows from a walker's structure (a wheel: one
leg of several spokes) is read from its model instead. (It sits in the config layer because the schema reads it;
the builders live in :mod:`biped_sim.walkers`.)
"""

from __future__ import annotations

from dataclasses import dataclass

from biped_sim.errors import ConfigError

DYNAMICS = ("compliant", "rigid")
STUDIES = ("limit_cycle", "bifurcation", "basin", "robustness", "converge", "compliant_limit_cycle")
RIGID_STUDIES = ("limit_cycle", "bifurcation", "basin", "robustness")


@dataclass(frozen=True)
class WalkerCapabilities:
    """What one walker kind supports."""

    formulations: dict[str, tuple[str, ...]]  # dynamics -> formulation kinds
    profiles: tuple[str, ...]  # the dynamics in which it walks ground profiles other than flat
    pushes: bool  # simulation.pushes
    studies: tuple[str, ...]  # names from STUDIES
    nondimensional: bool = False  # written in units of g = l = hip mass = 1 (Garcia's): rigid gravity 1, no SI units
    light_legs: bool = False  # legs of no mass: a strike sets the swing leg from the stance leg (Garcia's relations)
    energy_per_kg: bool = False  # its mass is no parameter (the wheel's hub): energies per kg of it
    strike_check: bool = False  # the plastic strike's stiff-contact check covers it (studies.convergence)

    @property
    def dynamics(self) -> tuple[str, ...]:
        """The dynamics the walker has a model in."""
        return tuple(self.formulations)


WALKERS: dict[str, WalkerCapabilities] = {
    "compass": WalkerCapabilities(
        {"compliant": ("planar", "minimal", "spatial"), "rigid": ("planar",)},
        DYNAMICS,
        True,
        STUDIES,
        strike_check=True,
    ),
    "simplest": WalkerCapabilities(
        {"rigid": ("planar",)}, ("rigid",), True, RIGID_STUDIES, nondimensional=True, light_legs=True
    ),
    "rimless_wheel": WalkerCapabilities({"rigid": ("planar",)}, ("rigid",), True, RIGID_STUDIES, energy_per_kg=True),
    # Liu's machine: its sagittal motion in minimal coordinates, the whole machine in spatial ones
    "four_legged": WalkerCapabilities({"compliant": ("spatial", "minimal")}, ("compliant",), True, ("basin",)),
    "description": WalkerCapabilities(
        {"compliant": ("planar", "minimal", "spatial"), "rigid": ("planar",)},
        DYNAMICS,
        True,
        (*RIGID_STUDIES, "converge"),
    ),
}


def capabilities(kind: str) -> WalkerCapabilities:
    """The registry's entry of ``walker.kind``."""
    return WALKERS[kind]


def refusal(kind: str, dynamics: str, formulation: str) -> tuple[str, str] | None:
    """(field, reason) when walker ``kind`` has no model in this dynamics and formulation, else None."""
    caps = WALKERS[kind]
    if dynamics not in caps.formulations:
        only = " and ".join(caps.dynamics)
        return "walker.kind", f"{kind!r} is available with dynamics: {only} only"
    if formulation in caps.formulations[dynamics]:
        return None
    offered = [d for d in DYNAMICS if any(formulation in c.formulations.get(d, ()) for c in WALKERS.values())]
    if dynamics not in offered:  # no walker has it in this dynamics: the formulation is the mistake
        return "formulation.kind", f"{formulation!r} is available with dynamics: {' and '.join(offered)} only"
    kinds = " or ".join(caps.formulations[dynamics])
    return "walker.kind", f"{kind!r} needs formulation.kind: {kinds} with dynamics: {dynamics}"


def profile_refusal(kind: str, dynamics: str) -> str | None:
    """Why walker ``kind`` walks no ground profile other than flat in ``dynamics`` (a one-line reason), or None."""
    walks = WALKERS[kind].profiles
    if dynamics in walks:
        return None
    if not walks:
        return f"the {kind} walker walks on flat ground only"
    return f"the {kind} walker walks on flat ground only with dynamics: {dynamics} (profiles: dynamics: {walks[0]})"


def supports_study(kind: str, study: str) -> bool:
    """Whether walker ``kind`` supports ``study`` (a name from STUDIES)."""
    return study in WALKERS[kind].studies


def require_study(kind: str, study: str, what: str) -> None:
    """ConfigError naming walker.kind when ``kind`` does not support ``study``; ``what`` says what it needs."""
    if not supports_study(kind, study):
        raise ConfigError("walker.kind", f"{what} (the {kind} walker does not support it)")
