"""`biped-sim report`: every comparison table (Markdown, CSV, LaTeX) and every figure from the tiny sweep."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from PIL import Image

from biped_sim.io.tables import Column, Table
from biped_sim.testing import TINY_SWEEP_RUNS

from .conftest import invoke, one_line_error

TABLES = ("runs", "by_integrator", "by_normal_model", "by_friction_model", "baumgarte")
FIGURES = (
    "period_vs_slope",
    "violation_vs_slope",
    "wall_time_vs_slope",
    "accuracy_vs_cost",
    "period_vs_step",
    "constraint_violation",
    "contact_forces",
    "energy",
    "slip",
    "phase_portrait",
)
HALF = TINY_SWEEP_RUNS // 2


@pytest.fixture(scope="module")
def report_dir(tiny_sweep_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The report of the tiny sweep (every axis varies: integrators, contact and friction laws, Baumgarte gains)."""
    out = tmp_path_factory.mktemp("report") / "report"
    result = invoke("report", str(tiny_sweep_dir), "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "5 tables" in result.stdout and f"{len(FIGURES)} figures" in result.stdout
    return out


def test_every_table_is_written_three_ways(report_dir: Path) -> None:
    for name in TABLES:
        for suffix in (".md", ".csv", ".tex"):
            assert (report_dir / "tables" / f"{name}{suffix}").is_file(), f"{name}{suffix}"
        rows = pd.read_csv(report_dir / "tables" / f"{name}.csv")
        assert len(rows) == TINY_SWEEP_RUNS, name
        latex = (report_dir / "tables" / f"{name}.tex").read_text()
        assert r"\begin{tabular}" in latex and r"\toprule" in latex and latex.count(r"\\") >= TINY_SWEEP_RUNS + 1
        assert "_" not in latex.replace(r"\_", "").split(r"\begin{tabular}")[1].split(r"\end{tabular}")[0]


def test_integrator_table_states_step_sizes_and_accuracy(report_dir: Path) -> None:
    table = pd.read_csv(report_dir / "tables" / "by_integrator.csv")
    assert list(table["integrator"]) == ["dopri5"] * HALF + ["rk2"] * HALF  # grouped by integrator
    assert set(table["step size / tolerances"]) == {"rtol = 1e-08, atol = 1e-10", "dt = 5e-05 s"}
    deviation = table["max |dT| vs ref. [s]"]
    assert (deviation[table["integrator"] == "dopri5"] == 0).all()  # dopri5 is each group's reference
    assert (deviation[table["integrator"] == "rk2"] > 0).all()
    markdown = (report_dir / "tables" / "by_integrator.md").read_text()
    assert "Accuracy reference for slope=0.015, contact.model=flores" in markdown
    assert r"max \|dT\| vs ref. [s]" in markdown  # a pipe in a header does not split the column


def test_model_and_baumgarte_tables_group_their_axis(report_dir: Path) -> None:
    normal = pd.read_csv(report_dir / "tables" / "by_normal_model.csv")
    assert list(normal["normal force model"]) == ["flores"] * HALF + ["hunt_crossley"] * HALF
    assert (normal["max penetration [m]"] > 0).all() and (normal["peak normal force [N]"] > 0).all()
    friction = pd.read_csv(report_dir / "tables" / "by_friction_model.csv")
    assert list(friction["friction model"]) == ["ambrosio"] * HALF + ["lugre"] * HALF
    baumgarte = pd.read_csv(report_dir / "tables" / "baumgarte.csv")
    assert list(baumgarte["stabilisation"]) == ["Baumgarte"] * HALF + ["standard"] * HALF
    assert list(baumgarte["alpha [1/s]"]) == [10.0] * HALF + [0.0] * HALF


def test_every_figure_is_png_at_200_dpi_and_svg(report_dir: Path) -> None:
    figures = report_dir / "figures"
    for name in FIGURES:
        with Image.open(figures / f"{name}.png") as image:
            assert image.format == "PNG"
            assert round(image.info["dpi"][0]) == 200
            assert image.size[0] == 700  # 3.5 in at 200 dpi: one journal column
        assert (figures / f"{name}.svg").read_text().lstrip().startswith("<?xml")
    assert not [p for p in figures.iterdir() if p.suffix.lower() in (".jpg", ".jpeg")]


def test_report_markdown_links_tables_and_figures(report_dir: Path) -> None:
    text = (report_dir / "report.md").read_text()
    assert text.startswith("# Sweep report: tiny")
    assert f"Runs: {TINY_SWEEP_RUNS} (" in text
    for name in FIGURES:
        assert f"](figures/{name}.png)" in text
    assert text.count("\n## ") == len(TABLES) + 1
    assert "runs at slope = 0.015" in text  # overlays show one slope, the caption says which


def test_report_on_a_directory_that_is_not_a_sweep(tmp_path: Path) -> None:
    result = invoke("report", str(tmp_path))
    assert result.exit_code == 2
    assert one_line_error(result.stderr) == f"error: {tmp_path}: not a sweep directory (no sweep.json and sweep.csv)"
    assert list(tmp_path.iterdir()) == []


def test_report_goes_where_out_says_with_every_table_and_figure(report_dir: Path, tiny_sweep_dir: Path) -> None:
    assert sorted(p.stem for p in (report_dir / "tables").glob("*.csv")) == sorted(TABLES)
    assert {p.stem for p in (report_dir / "figures").glob("*.png")} == set(FIGURES)
    assert not (tiny_sweep_dir / "report").exists()  # --out given: nothing in the default place


def test_table_formats_numbers_units_and_missing_values() -> None:
    table = Table(
        "demo",
        "Demo table",
        [Column("name", "name"), Column("x", "violation", "m", ".1e"), Column("n", "steps", "", "d")],
        [{"name": "a_b", "x": 1.23e-11, "n": 3}, {"name": "c", "x": None, "n": None}],
        ["A note with 50% & more."],
    )
    assert table.csv() == "name,violation [m],steps\na_b,1.23e-11,3\nc,,\n"
    markdown = table.markdown()
    assert "| a_b | 1.2e-11 | 3 |" in markdown and "| c | – | – |" in markdown
    assert "|:---|---:|---:|" in markdown
    latex = table.latex()
    assert r"a\_b & $1.2\times10^{-11}$ & 3 \\" in latex
    assert r"c & -- & -- \\" in latex
    assert r"50\% \& more." in latex
    assert r"\label{tab:demo}" in latex
