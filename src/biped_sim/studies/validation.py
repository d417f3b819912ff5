"""``biped-sim validate``: every physics check against published or analytic numbers, as one report.

Each check returns rows of (check, expected, obtained, tolerance, pass). Published numbers come from
``configs/references/rigid_walkers.yaml`` (each with its citation and where in the source); analytic
ones are derived here. The report is ``results/validation/report.md`` (and ``report.json``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from biped_sim.config import config_from_dict, load_config, parse_yaml
from biped_sim.io.atomic import write_json_atomic, write_text_atomic
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.simulate import simulate
from biped_sim.studies.checks import CONFIGS, Check, close, simplest_config
from biped_sim.studies.continuation import period_doubling_slope
from biped_sim.studies.drop_test import drop_test_table
from biped_sim.studies.friction_checks import incline_checks
from biped_sim.studies.garcia import simplest_variational_jacobian
from biped_sim.studies.lugre_checks import lugre_checks
from biped_sim.studies.uncertainty.checks import uncertainty_checks
from biped_sim.studies.validation_studies import (
    basin_checks,
    convergence_checks,
    fit_recovery_checks,
    step_down_checks,
)

ROOT = Path(__file__).resolve().parents[3]
REFERENCES = ROOT / "configs" / "references" / "rigid_walkers.yaml"


def load_rigid_references(path: Path = REFERENCES) -> dict[str, Any]:
    """The published rigid-walker numbers (with their citations)."""
    return parse_yaml(path.read_text(), source=str(path))


def garcia_checks(refs: dict[str, Any]) -> list[Check]:
    """Simplest walker at 0.009: fixed point, stability, multipliers two ways, period-doubling slope."""

    ref = refs["garcia1998"]
    fp = ref["fixed_point"]
    config = simplest_config(fp["slope"])
    cycle = rigid_limit_cycle(config)
    group = "Garcia et al. 1998, simplest walker"
    rows = [
        close(group, "theta* at slope 0.009", fp["stance_angle"], cycle.fixed_point["stance_angle"], 1e-8),
        close(group, "thetadot* at slope 0.009", fp["stance_rate"], cycle.fixed_point["stance_rate"], 1e-8),
        Check(
            group,
            "period-1 gait at 0.009 is stable",
            "max |lambda| < 1",
            f"{cycle.max_multiplier_modulus:.6f}",
            "-",
            cycle.stable,
        ),
    ]
    variational = np.linalg.eigvals(simplest_variational_jacobian(rigid_walker(config), cycle.section_point))
    gap = float(np.max(np.abs(np.sort_complex(variational) - np.sort_complex(cycle.multipliers))))
    rows.append(
        Check(
            group,
            "multipliers: finite differences vs variational equations",
            " ".join(f"{m.real:.8f}{m.imag:+.8f}i" for m in np.sort_complex(variational)),
            f"max difference {gap:.1e}",
            "1e-6",
            gap <= 1e-6,
        )
    )
    pd = ref["period_doubling"]
    slope, _ = period_doubling_slope(config, fp["slope"], 0.03)
    half_digit = 0.5 * 10 ** (math.floor(math.log10(pd["slope"])) - pd["digits"] + 1)
    rows.append(
        Check(
            group,
            "slope where the period-1 gait loses stability (multiplier through -1)",
            f"{pd['slope']} (abstract, p. 281)",
            f"{slope:.6f}",
            f"{half_digit:g} (published to {pd['digits']} digits)",
            abs(slope - pd["slope"]) <= half_digit,
        )
    )
    return rows


def rimless_wheel_checks() -> list[Check]:
    """Analytic rolling fixed point (MODEL.md 8) and multiplier cos^2(2 alpha), 2 slopes x 2 spoke counts."""

    rows = []
    group = "Rimless wheel (analytic)"
    for spokes in (8, 12):
        for slope in (0.1, 0.2):
            config = config_from_dict(
                {
                    "dynamics": "rigid",
                    "walker": {"kind": "rimless_wheel", "spokes": spokes, "leg_length": 1.0},
                    "ground": {"slope": slope},
                }
            )
            alpha = math.pi / spokes
            g_over_l = config.gravity / config.walker.leg_length
            rate = math.sqrt(4.0 * g_over_l * math.sin(alpha) * math.sin(slope)) / math.tan(2.0 * alpha)
            cycle = rigid_limit_cycle(
                config, {"stance_angle": alpha, "stance_rate": -rate * 1.2, "swing_angle": 0.0, "swing_rate": 0.0}
            )
            tag = f"N={spokes}, slope {slope}"
            # MODEL.md 8 measures theta from the vertical, positive with the hub ahead: theta_README = gamma - theta
            theta_model = slope - cycle.fixed_point["stance_angle"]
            rows.append(close(group, f"theta* = gamma - alpha ({tag})", slope - alpha, theta_model, 1e-8))
            rows.append(
                close(
                    group,
                    f"thetadot* = cot(2a) sqrt(4 g/l sin a sin g) ({tag})",
                    rate,
                    -cycle.fixed_point["stance_rate"],
                    1e-8,
                )
            )
            rows.append(
                close(
                    group,
                    f"multiplier = cos^2(2 alpha) ({tag})",
                    math.cos(2 * alpha) ** 2,
                    float(cycle.multipliers[0].real),
                    1e-6,
                )
            )
    return rows


def goswami_checks(refs: dict[str, Any]) -> list[Check]:
    """Goswami's compass gait, rigid, at 3 degrees: a stable period-1 limit cycle exists (reported)."""

    config = load_config(CONFIGS / "compass_goswami.yaml", ["dynamics=rigid"])
    cycle = rigid_limit_cycle(config)
    fp = cycle.fixed_point
    multipliers = ", ".join(f"{abs(m):.4f}" for m in cycle.multipliers)
    obtained = (
        f"theta_st {fp['stance_angle']:.8f}, rates {fp['stance_rate']:.8f} / {fp['swing_rate']:.8f}, "
        f"T {cycle.step_period:.6f} s, |lambda| {multipliers}"
    )
    return [
        Check(
            "Goswami et al. 1998, compass gait",
            "stable period-1 gait at 3 deg (rigid)",
            "exists, stable",
            obtained,
            "-",
            cycle.stable,
        )
    ]


def rigid_physics_checks() -> list[Check]:
    """Energy conserved during a rigid swing; angular momentum about the new contact conserved at impact."""

    config = load_config(CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid"])
    walker = rigid_walker(config)
    cycle = rigid_limit_cycle(config)
    step = rigid_step(walker, walker.from_section(cycle.section_point), sample_rate=2000.0)
    energy = np.array([sum(walker.energy(x)) for x in step.samples_x])
    scale = walker.reference_mass * walker.gravity * walker.leg_length
    drift = float(np.ptp(energy) / scale)
    x_minus, x_plus = step.x_minus, walker.impact(step.x_minus)
    foot_x, _ = walker.swing_foot(x_minus, 0.0, 0.0)
    contact = np.array([foot_x, 0.0])  # the landing foot's contact point, in the frame of x_minus
    # the post-impact state is in the new stance foot's frame: shift it onto the same contact point
    shift = contact - walker.contact_point(x_plus[: walker.n_q])
    before_l = walker.angular_momentum(x_minus, contact)
    after_l = walker.angular_momentum(x_plus, contact - shift)
    group = "Rigid model physics (round-foot walker)"
    return [
        Check(group, "energy drift during a step / (m g l)", "0", f"{drift:.1e}", "1e-10", drift <= 1e-10),
        Check(
            group,
            "angular momentum about the new contact point through the impact (relative)",
            "conserved",
            f"{abs(after_l - before_l) / abs(before_l):.1e}",
            "1e-12",
            abs(after_l - before_l) <= 1e-12 * abs(before_l),
        ),
    ]


def contact_law_checks() -> list[Check]:
    """The drop-test claims of the user guide (docs/guide/contact.md): effective restitution of each normal law."""

    rows = drop_test_table()
    out = []
    group = "Contact laws (drop test)"
    for r in rows:
        model, e, eff = r["model"], float(r["nominal_restitution"]), float(r["effective_restitution"])
        if model == "hertz":
            out.append(close(group, f"hertz is elastic (e = {e})", 1.0, eff, 1e-3))
        elif model == "flores":
            out.append(close(group, f"flores tracks e = {e}", e, eff, 0.05))
        elif model in ("hunt_crossley", "lankarani_nikravesh") and e == 0.9:
            out.append(close(group, f"{model} near e = 0.9", e, eff, 0.02))
        elif model == "kelvin_voigt":
            out.append(
                Check(group, f"kelvin_voigt loses less than nominal (e = {e})", f"> {e}", f"{eff:.4f}", "-", eff > e)
            )
    return out


def energy_balance_checks() -> list[Check]:
    """The core's strongest check: E(t) - E(0) + W(t) over 10 s of the default walker (rtol 1e-9)."""

    config = load_config(
        CONFIGS / "round_foot_walker.yaml", ["simulation.t_end=10", "integrator.rtol=1e-9", "integrator.atol=1e-11"]
    )
    result = simulate(config)
    scale = result.model.total_mass * config.gravity * config.walker.leg_length
    residual = float(np.max(np.abs(result.energy.residual)) / scale)
    return [
        Check(
            "Energy balance (compliant core)",
            "max |E - E0 + W| / (m g l) over 10 s",
            "0",
            f"{residual:.1e}",
            "1e-5",
            residual < 1e-5,
        )
    ]


def run_validation(
    out_dir: Path,
    progress: Callable[[str], None] | None = None,
    extra: Sequence[tuple[str, Callable[[], list[Check]]]] = (),
) -> tuple[list[Check], dict[str, Any]]:
    """Run every check (then the ``extra`` stages: (name, checks) of the layers above, as the MuJoCo comparison),
    write report.md and report.json into ``out_dir``; returns the checks and extras."""
    refs = load_rigid_references()
    start = time.perf_counter()
    checks: list[Check] = []
    extras: dict[str, Any] = {}
    stages: list[tuple[str, Callable[[], list[Check]]]] = [
        ("Garcia simplest walker", lambda: garcia_checks(refs)),
        ("rimless wheel", rimless_wheel_checks),
        ("Goswami compass gait", lambda: goswami_checks(refs)),
        ("rigid physics", rigid_physics_checks),
        ("simplest walker's basin", basin_checks),
        ("contact laws", contact_law_checks),
        ("friction laws' dry limits on an incline", incline_checks),
        ("LuGre against Canudas de Wit et al. 1995", lugre_checks),
        ("energy balance", energy_balance_checks),
        ("fit recovery", fit_recovery_checks),
        ("uncertainty: Sobol indices, mean period, rimless wheel MFPT", uncertainty_checks),
        *extra,
    ]
    for name, stage in stages:
        if progress:
            progress(name)
        checks.extend(stage())
    if progress:
        progress("compliant -> rigid convergence")
    conv_checks, extras["convergence"] = convergence_checks()
    checks.extend(conv_checks)
    if progress:
        progress("compliant -> rigid largest step down")
    step_checks, extras["step_down"] = step_down_checks()
    checks.extend(step_checks)
    extras["wall_time_s"] = time.perf_counter() - start
    write_report(checks, extras, refs, out_dir)
    return checks, extras


def write_report(checks: list[Check], extras: dict[str, Any], refs: dict[str, Any], out_dir: Path) -> None:
    """report.md (tables) and report.json."""
    out_dir.mkdir(parents=True, exist_ok=True)
    n_pass = sum(c.passed for c in checks)
    lines = [
        "# biped-sim validation report",
        "",
        f"{n_pass} of {len(checks)} checks pass; wall time {extras['wall_time_s']:.0f} s.",
        "",
        "| group | check | expected | obtained | tolerance | pass |",
        "|---|---|---|---|---|---|",
    ]
    for c in checks:
        lines.append(
            f"| {c.group} | {c.check} | {c.expected} | {c.obtained} | {c.tolerance} | {'yes' if c.passed else 'NO'} |"
        )
    lines += [
        "",
        "## Compliant -> rigid convergence (round_foot_walker)",
        "",
        "Contact stiffness K, restitution e, LuGre bristle stiffness sigma0; differences of the last of 20 "
        "compliant steps started on the rigid limit cycle against the rigid gait (touchdown state, max over "
        "the four leg variables; step period).",
        "",
        "| K [N/m^1.5] | e | sigma0 [1/m] | touchdown diff | period diff [s] | settled | slip [m] |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in extras["convergence"]:
        lines.append(
            f"| {r['stiffness']:.3e} | {r['restitution']:.4f} | {r['bristle_stiffness']:.0e} | "
            f"{r['touchdown_difference']:.2e} | {r['period_difference']:.2e} | {r['settled']:.1e} | {r['slip']:.1e} |"
        )
    lines += [
        "",
        "## Compliant -> rigid largest step down (round_foot_walker)",
        "",
        "Started on the rigid limit cycle (the compliant walker after 10 steps of settling); contact stiffness K "
        "x10 per level, restitution 0.3 / sqrt(10)^k; searches to 1e-3 leg lengths.",
        "",
        "| K [N/m^1.5] | compliant [l] | rigid [l] |",
        "|---|---|---|",
    ]
    lines += [f"| {r['stiffness']:.3e} | {r['compliant']:.4f} | {r['rigid']:.4f} |" for r in extras["step_down"]]
    lines += ["", "## Sources", ""]
    for key in ("garcia1998", "goswami1998"):
        lines.append(f"* {refs[key]['citation']}")
    lines.append(f"* Period-doubling slope: {refs['garcia1998']['period_doubling']['where']}")
    lines.append(f"* Fixed point: {refs['garcia1998']['fixed_point']['where']}")
    lines.append(
        "* LuGre: C. Canudas de Wit, H. Olsson, K. J. Astrom, P. Lischinsky, IEEE TAC 40(3) (1995) 419-425, Table I; "
        "the set-ups as reconstructed in github.com/auralius/LuGre (demo1.m), checked against analytic properties."
    )
    lines.append(
        "* Rimless wheel: analytic (MODEL.md 8); its multiplier cos^2(2 alpha) follows from the same energy balance."
    )
    write_text_atomic(out_dir / "report.md", "\n".join(lines) + "\n")
    write_json_atomic(out_dir / "report.json", {"checks": [asdict(c) for c in checks], **extras})


__all__ = ["Check", "run_validation"]
