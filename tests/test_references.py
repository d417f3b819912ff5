"""Reference files: the bundled published errors, and a one-line error naming the field for each malformed file."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from biped_sim.errors import ConfigError
from biped_sim.io.references import load_reference

from .conftest import CONFIGS

CORRAL = CONFIGS / "references" / "corral2020_liu_errors.yaml"

# A well-formed step-period reference. The numbers are FICTITIOUS test data, not a measurement.
VALID = {
    "experiment": "liu_round_foot_walker",
    "description": "FICTITIOUS test data",
    "citation": {"authors": ["A. Tester", "B. Tester"], "title": "Test", "year": 2024, "doi": "10.1234/test.5"},
    "source": {"kind": "table", "label": "Table 1", "page": 3},
    "quantity": {"name": "step_period", "unit": "s", "statistic": "mean", "n_trials": 4},
    "values": [0.5, 0.4, 0.25],
    "std": [0.01, 0.02, 0.0],
}


def write(tmp_path: Path, data: object, name: str = "ref.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_bundled_corral_errors_are_the_published_numbers() -> None:
    reference = load_reference(CORRAL)
    assert reference.values == [8.02, 0.42, 1.69, 2.56, 7.69, 0.00, 4.00]  # MODEL.md section 8
    assert reference.steps == [1, 2, 3, 4, 5, 6, 7]
    assert not reference.is_periods
    spec = reference.spec
    assert spec.quantity.name == "step_period_relative_error" and spec.quantity.unit == "percent"
    assert spec.citation.doi == "10.3390/app10072342" and spec.citation.year == 2020
    assert spec.source.label is None  # the paper's table/figure number is not available here
    assert reference.short_name == "Corral et al. 2020"
    assert "https://doi.org/10.3390/app10072342" in reference.citation_text()


def test_valid_period_reference_links_published_errors(tmp_path: Path) -> None:
    path = write(tmp_path, {**VALID, "published_errors": [str(CORRAL)]})
    reference = load_reference(path)
    assert reference.is_periods and reference.values == [0.5, 0.4, 0.25]
    assert reference.source_text() == "Table 1, p. 3"
    assert [r.short_name for r in reference.published_errors] == ["Corral et al. 2020"]


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"experiment": None}, "experiment: Input should be a valid string"),
        ({"citation": {"title": "x", "year": 2020}}, "citation.authors: Field required"),
        ({"citation": {"authors": [], "title": "x", "year": 2020}}, "citation.authors: List should have at least 1"),
        ({"citation": {"authors": ["A"], "title": "x", "year": 2020, "doi": "doi:10.1/x"}}, "citation.doi"),
        ({"source": {"kind": "tabel"}}, "source.kind: Input should be 'table', 'figure' or 'text'"),
        ({"quantity": {"name": "step_period", "unit": "ms"}}, "quantity.unit"),
        ({"quantity": {"name": "step_period", "unit": "percent"}}, "quantity.unit: step_period is in 's'"),
        ({"quantity": {"name": "step_length", "unit": "s"}}, "quantity.name"),
        ({"values": []}, "values: List should have at least 1 item"),
        ({"values": [0.5, "fast", 0.4]}, "values.1: Input should be a valid number"),
        ({"values": [0.5, -0.4, 0.3]}, "values: entry 2 is a step period and must be > 0"),
        ({"values": [0.5, float("nan"), 0.3]}, "values: entry 2 is not a finite number"),
        ({"std": [0.1]}, "std: 1 entries for 3 values"),
        ({"std": [0.1, -0.1, 0.1]}, "std: entries must be finite and >= 0"),
        ({"steps": [1, 3, 2]}, "steps: must be increasing step numbers"),
        ({"steps": [1, 2]}, "steps: 2 step numbers for 3 values"),
        ({"trials": 5}, "trials: unknown key"),
        ({"published_errors": ["missing.yaml"]}, "published_errors: no such reference file"),
    ],
)
def test_malformed_reference_names_the_field(tmp_path: Path, change: dict[str, object], expected: str) -> None:
    path = write(tmp_path, {**VALID, **change})
    with pytest.raises(ConfigError) as info:
        load_reference(path)
    assert str(info.value).startswith(f"{path}: ")
    assert expected in str(info.value)


def test_published_errors_must_be_errors_of_the_same_experiment(tmp_path: Path) -> None:
    other = write(tmp_path, {**VALID, "experiment": "another_walker"}, "periods.yaml")
    with pytest.raises(ConfigError, match=r"published_errors: periods\.yaml does not hold step_period_relative_error"):
        load_reference(write(tmp_path, {**VALID, "published_errors": ["periods.yaml"]}))
    errors = yaml.safe_load(CORRAL.read_text())
    write(tmp_path, {**errors, "experiment": "another_walker"}, "errors.yaml")
    with pytest.raises(ConfigError, match="is about experiment 'another_walker'"):
        load_reference(write(tmp_path, {**VALID, "published_errors": ["errors.yaml"]}))
    assert other.exists()


def test_not_a_file_not_yaml_not_a_mapping(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no such reference file"):
        load_reference(tmp_path / "none.yaml")
    (tmp_path / "bad.yaml").write_text("values: [0.5, 0.4\n")
    with pytest.raises(ConfigError, match="malformed YAML"):
        load_reference(tmp_path / "bad.yaml")
    (tmp_path / "list.yaml").write_text("- 0.5\n")
    with pytest.raises(ConfigError, match="a reference file must be a mapping"):
        load_reference(tmp_path / "list.yaml")
