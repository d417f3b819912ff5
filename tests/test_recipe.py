"""The guide's recipe "a new walker is one YAML file" (docs/guide/rigid.md) as a user follows it: its YAML block
written to my_walker.yaml, its shell block run from that file's folder with the environment's ``biped-sim``."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from biped_sim.config import load_config

from .conftest import ROOT

GUIDE = ROOT / "docs" / "guide" / "rigid.md"


def recipe() -> tuple[str, str]:
    """(the walker's YAML, the commands) of the recipe."""
    section = GUIDE.read_text().split("**A new walker is one YAML file.**", 1)[1]
    walker = re.search(r"```yaml\n(.*?)```", section, re.S)
    commands = re.search(r"```sh\n(.*?)```", section, re.S)
    assert walker is not None and commands is not None, "the recipe has a yaml and a sh block"
    return walker.group(1), commands.group(1)


def test_the_recipes_walker_loads_and_has_every_parameter_its_commands_vary(tmp_path: Path) -> None:
    walker, commands = recipe()
    (tmp_path / "my_walker.yaml").write_text(walker)
    config = load_config(tmp_path / "my_walker.yaml")
    names = {p.name for p in config.walker.parameters}  # type: ignore[union-attr]
    varied = set(re.findall(r"walker\.parameters\.(\w+)", commands))
    assert varied and varied <= names
    assert "my_walker.yaml" in commands and "torso_angle" in config.initial_keys()


@pytest.mark.slow  # every study of the recipe on its walker: a sweep, 16 samples, a fit (minutes on a loaded machine)
def test_the_recipe_runs_as_written(tmp_path: Path) -> None:
    walker, commands = recipe()
    (tmp_path / "my_walker.yaml").write_text(walker)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    done = subprocess.run(
        ["bash", "-e", "-c", commands], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=3600
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "results" / "sweeps" / "radius" / "sweep.csv").exists()
    assert (tmp_path / "results" / "uncertainty").is_dir()
    found = re.search(r"walker\.parameters\.torso_mass = ([0-9.]+);", done.stdout)  # the fit's line
    assert found is not None and float(found.group(1)) == pytest.approx(1.1, abs=1e-3), done.stdout[-2000:]
    assert "not identifiable" not in done.stdout
