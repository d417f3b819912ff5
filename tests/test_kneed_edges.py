"""The kneed walker's edges (issue 31): the guess in the walker's own keys, a failed gait search as a failure, the
touchdown's labels with a bent knee stop, the hip-to-foot lines, a radius of gyration, and McGeer's free trailing knee
through the heel strike (its four-coordinate section, its strike's momenta)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from biped_sim.config import load_config
from biped_sim.errors import ConfigError
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.compiled import rigid_step
from biped_sim.rigid.limit_cycle import rigid_limit_cycle
from biped_sim.rigid.tree import RigidWalker
from biped_sim.simulate import simulate
from biped_sim.studies.limit_cycle import guess_keys, parse_guess
from biped_sim.walkers.described import resolve_tree

from .conftest import CONFIGS, invoke, one_line_error

KNEED = CONFIGS / "kneed_walker.yaml"
CHEN_STOP = "stops: [{side: upper, angle: 0.0}]"
KNEED_KEYS = (
    "stance_thigh_angle", "stance_thigh_rate", "stance_shank_angle", "stance_shank_rate",
    "swing_thigh_angle", "swing_thigh_rate", "swing_shank_angle", "swing_shank_rate",
)  # fmt: skip
SECTION = ("stance_thigh_angle", "stance_thigh_rate", "swing_thigh_rate")  # just after the heel strike
BENT = 0.2  # [rad] a knee stop off the straight leg
THIGH = 0.5  # [m] Chen's thigh: the knee 0.5 m below the hip


def kneed_yaml(tmp_path: Path, stop: str, name: str = "kneed.yaml", first_stop: str | None = None) -> Path:
    """configs/kneed_walker.yaml with both knees' stops written as ``stop`` (the first knee's as ``first_stop``)."""
    text = KNEED.read_text()
    text = text.replace(CHEN_STOP, first_stop or stop, 1).replace(CHEN_STOP, stop)
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_guess_is_the_walkers_own_keys_or_its_sections_in_order_or_by_name() -> None:
    config = load_config(KNEED)
    cycle = rigid_limit_cycle(config)
    fixed, keys = cycle.fixed_point, guess_keys(config)
    assert keys == (KNEED_KEYS, SECTION)
    values = [fixed[k] for k in KNEED_KEYS]
    assert parse_guess(json.dumps(values), *keys) == parse_guess(json.dumps(fixed), *keys) == fixed
    section = dict(zip(SECTION, cycle.section_point.tolist(), strict=True))
    assert parse_guess(json.dumps(list(section.values())), *keys) == parse_guess(json.dumps(section), *keys) == section
    for guess in (values, list(section.values())):
        out = invoke("limit-cycle", str(KNEED), "--guess", json.dumps(guess), "--settle-steps", "0", "--json")
        doc = json.loads(out.stdout)
        assert out.exit_code == 0 and doc["converged"] and doc["start"] == "the guess" and doc["iterations"] <= 1
    bad = invoke("limit-cycle", str(KNEED), "--guess", "[0.24,-1.1,-0.24,-0.06]")  # the compass's four: a traceback
    assert bad.exit_code == 2 and one_line_error(bad.stderr) == (
        f"error: --guess: expected the 8 keys {', '.join(KNEED_KEYS)} (or 8 numbers in that order), or the section's "
        f"3: {', '.join(SECTION)}"
    )
    unknown = invoke("limit-cycle", str(KNEED), "--guess", "{stance_angle: 0.2, stance_rate: -1, swing_angle: -0.2}")
    assert unknown.exit_code == 2 and ", ".join(KNEED_KEYS) in one_line_error(unknown.stderr)


def test_a_failed_gait_search_exits_1_naming_its_starts_and_prints_no_gait() -> None:
    args = ["limit-cycle", str(KNEED), "--set", "ground.slope=0.3", "--settle-steps", "0"]  # no gait this steep
    table = invoke(*args)
    line = one_line_error(table.stderr)
    assert table.exit_code == 1 and table.stdout == ""
    assert line.startswith("error: no rigid limit cycle: Newton did not converge (best residual ")
    assert line.endswith(", tolerance 1e-10) from the 3 generic starts")
    as_json = invoke(*args, "--json")
    doc = json.loads(as_json.stdout)
    assert as_json.exit_code == 1 and one_line_error(as_json.stderr) == line
    assert doc["status"] == "not_converged" and doc["tried"] == "the 3 generic starts" and not doc["converged"]
    assert not {"fixed_point", "touchdown", "step_period", "multipliers", "stable"} & set(doc)
    falls = invoke("limit-cycle", str(KNEED), "--guess", "[0.2, 3.0, 0.0]", "--settle-steps", "0")  # thrown back
    assert falls.exit_code == 1 and falls.stdout == ""
    assert one_line_error(falls.stderr) == "error: no rigid limit cycle: the walker falls from the guess"


def test_the_touchdown_names_the_landing_legs_bodies_with_a_bent_knee_stop(tmp_path: Path) -> None:
    config = load_config(kneed_yaml(tmp_path, f"stops: [{{side: upper, angle: {BENT}}}]"))
    cycle = rigid_limit_cycle(config)
    walker = rigid_walker(config)
    x_minus = rigid_step(walker, walker.from_section(cycle.section_point)).x_minus  # swing leg: coordinates 2, 3
    touchdown = cycle.touchdown
    assert cycle.converged and touchdown["stance_shank_angle"] - touchdown["stance_thigh_angle"] == pytest.approx(BENT)
    for role, k in (("stance_thigh", 2), ("stance_shank", 3), ("swing_thigh", 0), ("swing_shank", 1)):
        assert (touchdown[f"{role}_angle"], touchdown[f"{role}_rate"]) == (x_minus[k], x_minus[4 + k]), role
    # the lines from the hip to the feet: symmetric about the slope normal at the strike, the legs' bend between
    for where in ("fixed_point", "touchdown"):
        lines = cycle.lines[where]
        assert lines["stance_line_angle"] == pytest.approx(-lines["swing_line_angle"], abs=1e-10)
        assert lines["inter_leg_angle"] == pytest.approx(2.0 * lines["stance_line_angle"], abs=1e-10)
        thigh, shank = cycle.fixed_point["stance_thigh_angle"], cycle.fixed_point["stance_shank_angle"]
        assert thigh < cycle.lines["fixed_point"]["stance_line_angle"] < shank


def test_the_leg_lines_of_a_round_foot_are_its_angle_plus_its_feet_lean() -> None:
    config = load_config(CONFIGS / "round_foot_walker.yaml", ["dynamics=rigid", "walker.foot_offset=0.02"])
    cycle = rigid_limit_cycle(config)
    lean = rigid_walker(config).lean
    assert lean > 0.0
    lines, legs = cycle.lines["fixed_point"], cycle.fixed_point
    assert lines["stance_line_angle"] == pytest.approx(legs["stance_angle"] + lean, abs=1e-12)
    assert lines["swing_line_angle"] == pytest.approx(legs["swing_angle"] + lean, abs=1e-12)


def test_a_body_takes_its_radius_of_gyration_or_its_inertia_not_both(tmp_path: Path) -> None:
    gyration = KNEED.read_text().replace("mass: 0.5, inertia: 0.0,", "mass: 0.5, radius_of_gyration: 0.1,")  # thighs
    path = tmp_path / "gyration.yaml"
    path.write_text(gyration)
    inertia = tmp_path / "inertia.yaml"
    inertia.write_text(gyration.replace("radius_of_gyration: 0.1,", "inertia: 0.005,"))  # m r^2 = 0.5 x 0.01
    by_radius, by_inertia = load_config(path), load_config(inertia)
    rigid = [rigid_walker(c).params for c in (by_radius, by_inertia)]
    np.testing.assert_allclose(rigid[0].rows["inertia"], rigid[1].rows["inertia"], rtol=1e-14, atol=0)
    assert np.array_equal(rigid[0].w, rigid[1].w) and np.array_equal(rigid[0].rows["mass"], rigid[1].rows["mass"])
    trees = [resolve_tree(c.walker.description) for c in (by_radius, by_inertia)]  # the compliant model's bodies
    np.testing.assert_allclose(trees[0].inertia, trees[1].inertia, rtol=1e-15, atol=0)
    assert trees[0].inertia.max() > 0.005
    both = tmp_path / "both.yaml"
    both.write_text(gyration.replace("radius_of_gyration: 0.1,", "radius_of_gyration: 0.1, inertia: 0.005,"))
    with pytest.raises(ConfigError, match="radius_of_gyration: give inertia or radius_of_gyration, not both"):
        load_config(both)
    out = invoke("limit-cycle", str(both))
    assert out.exit_code == 2 and "radius_of_gyration" in one_line_error(out.stderr)


# --- McGeer's free trailing knee -------------------------------------------------------------------------------

FREE_STOP = "stops: [{side: upper, angle: 0.0, release_at_heel_strike: true}]"


def _momentum(walker: RigidWalker, x: np.ndarray, about: np.ndarray, coordinates: set[int] | None) -> float:
    return walker.angular_momentum(x, np.asarray(about), coordinates)


def test_a_free_trailing_knee_has_a_four_coordinate_section_and_a_gait(tmp_path: Path) -> None:
    config = load_config(kneed_yaml(tmp_path, FREE_STOP))
    cycle = rigid_limit_cycle(config)
    assert cycle.section_names == ("stance_thigh_angle", "stance_thigh_rate", "swing_thigh_rate", "swing_shank_rate")
    assert cycle.converged and cycle.stable and len(cycle.multipliers) == 4
    legs = cycle.fixed_point
    assert legs["swing_shank_rate"] < legs["swing_thigh_rate"]  # the trailing knee leaves the strike flexing
    assert legs["stance_shank_rate"] == legs["stance_thigh_rate"]  # the landing knee held
    # the knee strike ends the landing leg's swing with one rate: the map's image is 3-dimensional
    assert sorted(abs(cycle.multipliers))[0] < 1e-6
    held = rigid_limit_cycle(load_config(KNEED))
    assert cycle.step_period != pytest.approx(held.step_period, rel=1e-3)
    result = simulate(load_config(kneed_yaml(tmp_path, FREE_STOP), ["simulation.max_steps=6"]))
    assert result.status == "walking" and len(result.step_periods) == 5  # the steps between the 6 strikes
    assert result.summary["energy_residual_max_relative"] < 1e-9  # the strikes' losses booked
    np.testing.assert_allclose(result.step_periods, cycle.step_period, rtol=1e-8)


def test_the_free_knee_strike_keeps_the_momenta_a_free_knee_keeps(tmp_path: Path) -> None:
    walker = rigid_walker(load_config(kneed_yaml(tmp_path, FREE_STOP)))
    cycle = rigid_limit_cycle(walker.config)
    x = rigid_step(walker, walker.from_section(cycle.section_point)).x_minus  # just before the heel strike
    n = walker.n_q
    plus = walker.impact(x)  # the new stance foot at the origin, the roles exchanged
    foot = np.array([walker.swing_foot(x, 0.0, 0.0)[0], 0.0])
    hip, new_hip = walker.hip(x[:n]), walker.hip(plus[:n])
    knee, new_knee = (h + THIGH * np.array([np.sin(a), -np.cos(a)]) for h, a in ((hip, x[0]), (new_hip, plus[2])))
    # the whole walker about the landing foot, the trailing leg about the hip, its shank about the knee
    cases = [(foot, np.zeros(2), None, None), (hip, new_hip, {0, 1}, {2, 3}), (knee, new_knee, {1}, {3})]
    for about, after, rows_before, rows_after in cases:
        want = _momentum(walker, x, about, rows_before)
        assert _momentum(walker, plus, after, rows_after) == pytest.approx(want, rel=1e-12)
    assert plus[n + 2] != plus[n + 3] and plus[n] == plus[n + 1]  # the trailing knee free, the landing one held


def test_a_free_knee_that_would_close_on_its_stop_is_held_through_the_strike(tmp_path: Path) -> None:
    free = rigid_walker(load_config(kneed_yaml(tmp_path, FREE_STOP)))
    x = rigid_step(free, free.from_section(rigid_limit_cycle(free.config).section_point)).x_minus
    lower = "stops: [{side: lower, angle: 0.0, release_at_heel_strike: true}]"  # the knee may only flex forward
    closing = rigid_walker(load_config(kneed_yaml(tmp_path, lower, "lower.yaml")))
    held = rigid_walker(load_config(kneed_yaml(tmp_path, "stops: [{side: lower, angle: 0.0}]", "held.yaml")))
    assert free.impact(x)[7] < free.impact(x)[6] - 1.0  # free, the trailing knee flexes: closing on a lower stop
    np.testing.assert_array_equal(closing.impact(x), held.impact(x))


def test_a_free_trailing_knee_on_one_leg_only_is_refused(tmp_path: Path) -> None:
    config = load_config(kneed_yaml(tmp_path, CHEN_STOP, first_stop=FREE_STOP))
    with pytest.raises(ConfigError, match="release_at_heel_strike: rigid dynamics needs it on every leg stop or none"):
        rigid_walker(config)
