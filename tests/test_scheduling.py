"""How pytest-xdist shares the tests out (tests/conftest.py): the units it hands out first must name tests that
exist, or a renamed test would silently lose its place at the head of the slow tier."""

from __future__ import annotations

import importlib

import pytest

from tests.conftest import LONGEST_FIRST, ROOT, SHARED_FIXTURE_MODULES, work_unit


def parametrised_ids(function: object) -> set[str] | None:
    """The ids of ``function``'s parametrised cases (those given as plain strings), or None if not parametrised."""
    marks = [mark for mark in getattr(function, "pytestmark", []) if mark.name == "parametrize"]
    return {str(value) for mark in marks for value in mark.args[1]} if marks else None


@pytest.mark.parametrize("unit", [unit for unit in LONGEST_FIRST if unit not in SHARED_FIXTURE_MODULES.values()])
def test_every_unit_handed_out_first_names_a_module_or_a_test_that_exists(unit: str) -> None:
    path, _, test = unit.partition("::")
    assert (ROOT / path).is_file(), unit
    if test:
        name, _, case = test.removesuffix("]").partition("[")
        function = getattr(importlib.import_module(path.removesuffix(".py").replace("/", ".")), name, None)
        assert function is not None, unit
        assert (case or None) in (parametrised_ids(function) or {None}), unit
        assert work_unit(unit) == unit


def test_other_tests_go_by_module_or_by_shared_fixture() -> None:
    assert work_unit("tests/test_fit_recovery_kneed.py::test_the_parametrised_kneed_walker_is_the_bundled_one") == (
        "tests/test_fit_recovery_kneed.py"
    )
    assert work_unit("tests/test_report.py::test_x") == "tiny_sweep"
