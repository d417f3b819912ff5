"""Sweep files: grid and zip expansion, ranges, precedence of overrides, run names, and every bad input."""

from __future__ import annotations

from pathlib import Path

import pytest

from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.sweep import check_buildable, load_sweep
from biped_sim.sweep.spec import RangeSpec, short_keys

from .conftest import CONFIGS, DEFAULT_CONFIG


def write_sweep(tmp_path: Path, body: str, base: Path = DEFAULT_CONFIG) -> Path:
    path = tmp_path / "sweep.yaml"
    path.write_text(f"name: test\nbase: {base}\n{body}")
    return path


def test_grid_is_cartesian_product_in_file_order(tmp_path: Path) -> None:
    sweep = load_sweep(
        write_sweep(tmp_path, "grid:\n  ground.slope: [0.01, 0.02]\n  integrator.method: [dopri5, rk4, euler]\n")
    )
    assert [run.params for run in sweep.runs] == [
        {"ground.slope": s, "integrator.method": m} for s in (0.01, 0.02) for m in ("dopri5", "rk4", "euler")
    ]
    assert [run.config.ground.slope for run in sweep.runs] == [0.01] * 3 + [0.02] * 3
    assert [run.config.integrator.method for run in sweep.runs] == ["dopri5", "rk4", "euler"] * 2


def test_zip_moves_lists_together_and_varies_fastest(tmp_path: Path) -> None:
    sweep = load_sweep(
        write_sweep(
            tmp_path,
            "grid:\n  ground.slope: [0.01, 0.02]\n"
            "zip:\n  integrator.method: [rk4, euler]\n  integrator.dt: [1.0e-4, 2.0e-5]\n",
        )
    )
    assert len(sweep.runs) == 4
    pairs = [(r.config.ground.slope, r.config.integrator.method, r.config.integrator.dt) for r in sweep.runs]
    assert pairs == [(0.01, "rk4", 1e-4), (0.01, "euler", 2e-5), (0.02, "rk4", 1e-4), (0.02, "euler", 2e-5)]


def test_range_is_inclusive_and_rounded() -> None:
    assert RangeSpec.model_validate({"from": 0.015, "to": 0.024, "num": 4}).values() == [0.015, 0.018, 0.021, 0.024]
    assert RangeSpec.model_validate({"from": 1e-5, "to": 1e-3, "num": 3, "scale": "log"}).values() == [
        1e-5,
        1e-4,
        1e-3,
    ]
    assert RangeSpec.model_validate({"from": 2.0, "to": 5.0, "num": 1}).values() == [2.0]


def test_range_axis_in_a_sweep_file(tmp_path: Path) -> None:
    sweep = load_sweep(write_sweep(tmp_path, "grid:\n  ground.slope: {from: 0.01, to: 0.02, num: 3}\n"))
    assert [run.config.ground.slope for run in sweep.runs] == [0.01, 0.015, 0.02]


def test_precedence_base_then_set_then_command_line_then_axes(tmp_path: Path) -> None:
    path = write_sweep(
        tmp_path,
        "set:\n  simulation.t_end: 2.0\n  walker.hip_mass: 3.0\ngrid:\n  ground.slope: [0.01]\n",
    )
    sweep = load_sweep(path, ["walker.hip_mass=4.0"])
    config = sweep.runs[0].config
    assert config.simulation.t_end == 2.0  # sweep `set` over the base file (15 s)
    assert config.walker.hip_mass == 4.0  # --set over the sweep's `set`
    assert config.walker.leg_length == 0.5  # from the base file
    assert sweep.overrides == ("walker.hip_mass=4.0",)


def test_base_is_relative_to_the_sweep_file() -> None:
    sweep = load_sweep(CONFIGS / "sweeps" / "slopes_integrators.yaml")
    assert sweep.base_path == DEFAULT_CONFIG.resolve()
    assert sweep.default_output_dir() == Path("results/sweeps/slopes_integrators")


def test_run_names_are_readable_stem_plus_config_hash(tmp_path: Path) -> None:
    sweep = load_sweep(
        write_sweep(tmp_path, "grid:\n  contact.model: [flores, hunt_crossley]\n  friction.model: [coulomb]\n")
    )
    first = sweep.runs[0]
    assert first.name == f"contact.model=flores_friction.model=coulomb-{first.config.hash()}"
    assert sweep.runs[1].stem == "contact.model=hunt-crossley_friction.model=coulomb"
    assert len({run.name for run in sweep.runs}) == 2


def test_short_keys_use_the_last_component_unless_it_clashes() -> None:
    assert short_keys(["ground.slope", "integrator.method"]) == {"ground.slope": "slope", "integrator.method": "method"}
    assert short_keys(["contact.model", "friction.model", "ground.slope"]) == {
        "contact.model": "contact.model",
        "friction.model": "friction.model",
        "ground.slope": "slope",
    }


def test_every_bundled_sweep_expands_and_builds() -> None:
    paths = sorted((CONFIGS / "sweeps").glob("*.yaml"))
    assert [path.stem for path in paths] == [
        "baumgarte",
        "constraint_violation",
        "contact_models",
        "friction_models",
        "slopes_integrators",
    ]
    for path in paths:
        sweep = load_sweep(path)
        assert len(sweep.runs) >= 4, path
        check_buildable(sweep)


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        ("grid: {}\n", "grid: a sweep needs at least one axis in grid or zip"),
        ("grid:\n  ground.slope: []\n", "ground.slope: an axis needs at least one value"),
        ("grid:\n  ground.slope: 0.01\n", "ground.slope: expected a list of values or a range"),
        ("grid:\n  ground.slope: {from: 0.01, to: 0.02}\n", "grid: ground.slope.num: Field required"),
        ("grid:\n  ground.slope: {from: 0.01, to: 0.02, num: 0}\n", "ground.slope.num: Input should be greater"),
        ("grid:\n  ground.slope: {from: 0.01, to: 0.02, num: 2, step: 1}\n", "ground.slope.step: unknown key"),
        ("grid:\n  ground.slope: {from: 0, to: 0.02, num: 2, scale: log}\n", "scale: 'log' needs from > 0"),
        ("zip:\n  integrator.method: [rk4, euler]\n  integrator.dt: [1.0e-4]\n", "zip: lists must have equal lengths"),
        ("grid:\n  ground.slope: [0.01]\nset:\n  ground.slope: 0.02\n", "set: ground.slope is also a sweep axis"),
        ("grid:\n  ground.slope: [0.01]\nzip:\n  ground.slope: [0.02]\n", "zip: ground.slope is also a grid axis"),
        ("grid:\n  'ground..slope': [0.01]\n", "is not a dotted config key"),
        ("grids:\n  ground.slope: [0.01]\n", "grids: unknown key"),
    ],
)
def test_malformed_sweep_file_names_the_field(tmp_path: Path, body: str, expected: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_sweep(write_sweep(tmp_path, body))
    assert str(info.value).startswith(str(tmp_path / "sweep.yaml"))
    assert expected in str(info.value)


def test_bad_run_names_the_run_and_the_field(tmp_path: Path) -> None:
    path = write_sweep(tmp_path, "grid:\n  ground.slope: [0.01, 0.9]\n  integrator.method: [rk4]\n")
    with pytest.raises(ConfigError) as info:
        load_sweep(path)
    message = str(info.value)
    assert "run 2 (slope=0.9_method=rk4)" in message
    assert "ground.slope" in message and "friction cone" in message


def test_unknown_swept_key_names_the_run(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"run 1 \(leg_masss=1\): walker.leg_masss: unknown key"):
        load_sweep(write_sweep(tmp_path, "grid:\n  walker.leg_masss: [1.0]\n"))


def test_unbuildable_run_is_caught_before_the_sweep_starts(tmp_path: Path) -> None:
    sweep = load_sweep(write_sweep(tmp_path, "grid:\n  simulation.initial.stance_angle: [0.2, 1.45]\n"))
    with pytest.raises(ConfigError, match=r"run 2 \(stance_angle=1.45\): simulation.initial.stance_angle"):
        check_buildable(sweep)


def test_command_line_override_of_a_swept_key_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ArgumentError, match=r"^overrides: ground\.slope is a sweep axis"):
        load_sweep(write_sweep(tmp_path, "grid:\n  ground.slope: [0.01]\n"), ["ground.slope=0.02"])


def test_two_runs_with_the_same_config_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="same resolved config as run 1"):
        load_sweep(write_sweep(tmp_path, "grid:\n  ground.slope: [0.02, 0.020]\n"))


def test_missing_files_and_non_mappings(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no such sweep file"):
        load_sweep(tmp_path / "none.yaml")
    with pytest.raises(ConfigError, match="base: no such config file"):
        load_sweep(write_sweep(tmp_path, "grid:\n  ground.slope: [0.01]\n", base=tmp_path / "nobase.yaml"))
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="a sweep file must be a mapping"):
        load_sweep(tmp_path / "list.yaml")
