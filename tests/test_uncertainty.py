"""biped-sim uncertainty: distributions and their errors, the design, resume, failed samples, and its files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from biped_sim import load_config
from biped_sim.errors import ConfigError
from biped_sim.studies.uncertainty.distributions import check_distributions, parse_param, read_spec
from biped_sim.studies.uncertainty.samples import run_sample
from biped_sim.studies.uncertainty.sampling import unit_design
from biped_sim.studies.uncertainty.sobol import sobol_study
from biped_sim.studies.uncertainty.statistics import statistics, wilson_interval

from .conftest import CONFIGS, invoke, one_line_error

SIMPLEST = CONFIGS / "simplest_walker.yaml"
SHORT = ("--set", "simulation.t_end=20")
SLOPE = "ground.slope=uniform:0.006:0.012"


@pytest.mark.parametrize(
    ("text", "kind", "median"),
    [
        ("ground.slope=uniform:0.004:0.012", "uniform", 0.008),
        ("ground.slope=normal:0.02:0.002", "normal", 0.02),
        ("contact.restitution=lognormal:0.3:0.1", "lognormal", 0.3),
        ("ground.slope=triangular:0.01:0.02:0.04", "triangular", None),
        ("ground.slope=interval:0.01:0.03", "interval", 0.02),
    ],
)
def test_each_distribution_parses_and_maps_the_unit_interval_onto_its_values(
    text: str, kind: str, median: float | None
) -> None:
    dist = parse_param(text)
    assert dist.kind == kind
    values = dist.values(np.array([0.0, 0.5, 1.0]))
    assert np.all(np.isfinite(values)) and values[0] < values[1] < values[2]
    if median is not None:
        assert values[1] == pytest.approx(median)


def test_a_yaml_section_gives_the_same_distributions_in_either_form(tmp_path: Path) -> None:
    path = tmp_path / "u.yaml"
    path.write_text(
        "uncertainty:\n  samples: 64\n  parameters:\n    ground.slope: normal:0.02:0.002\n"
        "    walker.leg_inertia: {distribution: uniform, lo: 0.004, hi: 0.006}\n"
    )
    found, options = read_spec(str(path))
    assert [d.text() for d in found] == ["normal:0.02:0.002", "uniform:0.004:0.006"]
    assert options == {"samples": 64}


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (("--param", "ground.slope=gamma:1:2"), "ground.slope"),
        (("--param", "ground.slope=normal:0.01:-0.001"), "ground.slope"),
        (("--param", "ground.slope=uniform:0.012:0.006"), "ground.slope"),
        (("--param", "ground.slope=uniform:a:0.006"), "ground.slope"),
        (("--param", "walker.kind=uniform:0:1"), "walker.kind"),
        (("--param", "walker.no_such_key=uniform:0:1"), "walker.no_such_key"),
        (("--param", "ground.slope"), "parameters"),
        (("--param", SLOPE, "--samples", "100"), "--samples"),
        (("--param", SLOPE, "--samples", "12", "--sobol"), "--samples"),
        (("--param", SLOPE, "--method", "grid"), "--method"),
        (("--param", SLOPE, "--surrogate", "0"), "--surrogate"),
        (("--param", SLOPE, "--from-fit", "no_such_fit"), "no_such_fit"),
        ((), "parameters"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path: Path, args: tuple[str, ...], field: str) -> None:
    out = tmp_path / "u"
    result = invoke("uncertainty", str(SIMPLEST), *args, "--out", str(out))
    assert result.exit_code == 2, result.stderr
    assert field in one_line_error(result.stderr)
    assert not out.exists()


def test_a_presets_parameter_under_both_spellings_is_one_key() -> None:
    config = load_config(CONFIGS / "round_foot_walker.yaml")
    both = [parse_param("walker.leg_inertia=uniform:0.004:0.006"),
            parse_param("walker.parameters.leg_inertia=uniform:0.004:0.006")]  # fmt: skip
    with pytest.raises(ConfigError, match="is given twice"):
        check_distributions(config, both)


def test_designs_are_seeded_and_sized() -> None:
    assert np.array_equal(unit_design(16, 3, "sobol", 4), unit_design(16, 3, "sobol", 4))
    assert not np.array_equal(unit_design(16, 3, "sobol", 4), unit_design(16, 3, "sobol", 5))
    assert unit_design(10, 3, "lhs", 0).shape == (10, 3)
    assert unit_design(8, 3, "saltelli", 0).shape == (8 * 5, 3)


def test_a_value_the_schema_refuses_is_an_invalid_sample_not_an_error() -> None:
    record = run_sample(load_config(SIMPLEST), ("walker.leg_length",), np.array([-1.0]))
    assert record["status"] == "invalid" and "walker.leg_length" in record["reason"]
    assert math.isnan(record["steady_period"])


def _records(statuses: list[str], periods: list[float]) -> list[dict[str, object]]:
    pairs = zip(statuses, periods, strict=True)
    return [{"status": s, "steady_period": p, "speed": p, "periods": [p], "n_steps": 1} for s, p in pairs]


def test_failed_samples_are_counted_and_indices_say_their_subset() -> None:
    rng = np.random.default_rng(0)
    base, d = 16, 2
    statuses = ["walking"] * (base * (d + 2))
    statuses[1] = statuses[9] = "fell"  # two blocks of four have a fallen sample
    records = _records(statuses, list(rng.random(base * (d + 2))))
    stats = statistics(records, ("steady_period",))
    assert stats["status_counts"] == {"fell": 2, "walking": 62}
    assert stats["outputs"]["steady_period"]["n"] == 62
    indices = sobol_study(records, ("a", "b"), base, seed=0)
    period = indices.outputs[0]
    assert (period.blocks_used, period.blocks) == (14, 16) and period.indices is not None
    assert indices.outputs[-1].subset == "every sample"


def test_a_study_whose_samples_mostly_fall_reports_no_indices_but_says_why() -> None:
    base, d = 8, 2
    statuses = ["fell" if i % 3 else "walking" for i in range(base * (d + 2))]
    indices = sobol_study(_records(statuses, [1.0] * len(statuses)), ("a", "b"), base, seed=0)
    assert indices.outputs[0].indices is None and "most samples fell" in (indices.outputs[0].reason or "")
    assert any("most samples fell" in note for note in indices.notes)


def test_wilson_interval_covers_the_proportion_and_stays_in_0_1() -> None:
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == pytest.approx(1.0)
    low, high = wilson_interval(30, 100)
    assert low < 0.3 < high


def test_the_cli_writes_its_files_reports_indices_and_a_rerun_resumes(tmp_path: Path) -> None:
    out = tmp_path / "u"
    inertia = "contact.restitution=uniform:0.2:0.9"  # unused by the rigid model
    args = ("uncertainty", str(SIMPLEST), "--param", SLOPE, "--param", inertia, "--samples", "4", "--sobol",
            "--surrogate", "1", *SHORT, "--jobs", "1", "--out", str(out), "--json")  # fmt: skip
    first = invoke(*args)
    assert first.exit_code == 0, first.stderr
    doc = json.loads(first.stdout)
    assert doc["runs"] == 16 and doc["chunks_reused"] == 0
    assert doc["statistics"]["status_counts"] == {"walking": 16}
    assert doc["sobol"]["outputs"]["steady_period"]["ranking_total"] == ["ground.slope", "contact.restitution"]
    unused = doc["sobol"]["outputs"]["steady_period"]["indices"]["contact.restitution"]
    assert unused["ST"] == pytest.approx(0, abs=1e-9)
    surrogate = doc["surrogate"]["steady_period"]["indices"]
    assert surrogate["ground.slope"]["ST"] > 0.99 and surrogate["contact.restitution"]["ST"] < 0.01
    names = {p.name for p in out.iterdir()}
    assert {"uncertainty.h5", "samples.csv", "bands.png", "bands.svg", "histograms.svg", "sobol.svg"} <= names
    with h5py.File(out / "uncertainty.h5") as f:
        assert f["values"].shape == (16, 2) and f["periods"].shape[0] == 16
        assert np.all(np.isfinite(f["floquet_max"][()]))
    assert len((out / "samples.csv").read_text().splitlines()) == 17
    again = json.loads(invoke(*args).stdout)
    assert again["chunks_reused"] == 1 and again["statistics"] == doc["statistics"]
    (out / "samples" / "chunk_000000.json").write_text("{")  # a chunk cut short by an interruption: run again
    resumed = json.loads(invoke(*args).stdout)
    assert resumed["chunks_reused"] == 0 and resumed["statistics"] == doc["statistics"]


def test_parse_param_names_the_key_in_its_errors() -> None:
    with pytest.raises(ConfigError, match=r"ground\.slope: triangular"):
        parse_param("ground.slope=triangular:0.03:0.01:0.02")


def test_from_fit_runs_evenly_spaced_posterior_draws(tmp_path: Path) -> None:
    from biped_sim.io.posterior import Posterior, write_posterior

    draws = np.linspace(0.007, 0.011, 40)[:, None]
    write_posterior(tmp_path / "posterior.h5", Posterior(("ground.slope",), draws, np.zeros(40), "{}"), {})
    out = tmp_path / "u"
    result = invoke("uncertainty", str(SIMPLEST), "--from-fit", str(tmp_path), "--samples", "5", *SHORT,
                    "--out", str(out), "--json")  # fmt: skip
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["source"] == "posterior" and doc["runs"] == 5 and doc["sobol"] is None
    with h5py.File(out / "uncertainty.h5") as f:
        assert f["values"][()][:, 0] == pytest.approx(draws[[0, 10, 20, 29, 39], 0])


def test_sobol_indices_of_a_posterior_are_refused_naming_from_fit(tmp_path: Path) -> None:
    from biped_sim.io.posterior import Posterior, write_posterior

    write_posterior(
        tmp_path / "posterior.h5", Posterior(("ground.slope",), np.full((8, 1), 0.009), np.zeros(8), "{}"), {}
    )
    result = invoke("uncertainty", str(SIMPLEST), "--from-fit", str(tmp_path), "--sobol", "--out", str(tmp_path / "u"))
    assert result.exit_code == 2 and result.stderr.strip().startswith("error: --from-fit: Sobol indices"), result.stderr
    assert not (tmp_path / "u").exists()


def test_the_polynomial_chaos_surrogate_is_exact_on_a_polynomial() -> None:
    from biped_sim.studies.uncertainty.distributions import Distribution
    from biped_sim.studies.uncertainty.surrogate import surrogate_indices

    # f = x1 + x2 x3 on [-1, 1]^3: V = 1/3 + 1/9, so S1 = (3/4, 0, 0) and ST = (3/4, 1/4, 1/4), degree 2 exact
    dists = [Distribution(f"x{i}", "uniform", (-1.0, 1.0)) for i in range(3)]
    x = -1.0 + 2.0 * unit_design(64, 3, "sobol", 0)
    found = surrogate_indices("f", dists, x, x[:, 0] + x[:, 1] * x[:, 2], order=2)
    assert found.s1 == pytest.approx([0.75, 0.0, 0.0], abs=1e-10) and found.st == pytest.approx([0.75, 0.25, 0.25])
    assert found.holdout_error is not None and found.holdout_error < 1e-10


def test_the_indices_read_from_the_coefficients_are_chaospy_s_sensitivities() -> None:
    import chaospy

    from biped_sim.studies.uncertainty.surrogate import coefficient_indices

    joint = chaospy.J(chaospy.Uniform(-1.0, 1.0), chaospy.Normal(0.0, 1.0))  # norms other than 1: not normalised
    expansion, norms = chaospy.generate_expansion(2, joint, retall=True)
    x = joint.sample(30, rule="sobol", seed=1)
    model, coefficients = chaospy.fit_regression(expansion, x, np.sin(x[0]) * np.exp(x[1] / 2) + x[1] ** 3, retall=1)
    s1, st = coefficient_indices(expansion, np.asarray(norms) * np.asarray(coefficients) ** 2)
    assert s1 == pytest.approx(chaospy.Sens_m(model, joint), rel=1e-9)
    assert st == pytest.approx(chaospy.Sens_t(model, joint), rel=1e-9)


@pytest.mark.slow  # a degree-8 expansion in chaospy
def test_the_polynomial_chaos_surrogate_recovers_ishigami_s_indices() -> None:
    from biped_sim.studies.uncertainty.checks import ISHIGAMI, ishigami
    from biped_sim.studies.uncertainty.distributions import Distribution
    from biped_sim.studies.uncertainty.surrogate import surrogate_indices

    dists = [Distribution(f"x{i}", "uniform", (-math.pi, math.pi)) for i in range(3)]
    x = -math.pi + 2 * math.pi * unit_design(1024, 3, "sobol", 0)
    found = surrogate_indices("f", dists, x, ishigami(x), order=8)
    assert found.s1 == pytest.approx(ISHIGAMI["S1"], abs=0.01) and found.st == pytest.approx(ISHIGAMI["ST"], abs=0.01)
    assert found.holdout_error is not None and found.holdout_error < 0.05
    few = surrogate_indices("f", dists, x[:100], ishigami(x[:100]), order=8)
    assert few.st is None and "too few" in (few.reason or "")
