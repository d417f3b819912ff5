"""The failure path a fault probe walked: bad input of every size is one short line, a sweep's failures show in its
exit code, a full disk stops it, usage errors are one line, help shows its text (interrupts: test_faults)."""

from __future__ import annotations

import errno
import itertools
import os
import subprocess
import threading
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import pandas as pd
import pytest

from biped_sim import config_from_dict, simulate
from biped_sim.cli.common import COMMAND_ORDER
from biped_sim.errors import ArgumentError, ConfigError
from biped_sim.io import run_files
from biped_sim.simulate import result as result_module
from biped_sim.studies.basin import BasinSpec, parse_axis
from biped_sim.sweep import load_sweep, run_sweep
from biped_sim.testing import write_sweep

from .conftest import CLI, CONFIGS, DEFAULT_CONFIG, MEMORY_BOUND, allocation_peak, child_env, invoke, one_line_error

SIMPLEST = str(CONFIGS / "simplest_walker.yaml")


def alias_bomb(levels: int = 9) -> str:
    """A few hundred bytes of YAML whose value expands to 9^levels strings (the billion laughs)."""
    rows = ["&a [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for previous, name in itertools.pairwise("abcdefghijklmnop"[:levels]):
        rows.append(f"&{name} [" + ", ".join([f"*{previous}"] * 9) + "]")
    return "[" + ", ".join(rows) + "]"


# bad input of any size: one short line


@pytest.mark.parametrize("value", ["1e30", "1e10"])
def test_an_absurd_max_steps_is_one_line(value: str, tmp_path: Path) -> None:
    result = invoke("run", str(DEFAULT_CONFIG), "--set", f"simulation.max_steps={value}", "--out", str(tmp_path / "o"))
    assert result.exit_code == 2
    assert one_line_error(result.stderr).startswith("error: simulation.max_steps: ")


def test_the_largest_max_steps_runs_with_buffers_sized_by_its_duration() -> None:
    summary = simulate(config_from_dict({}, ["simulation.max_steps=1e9", "simulation.t_end=0.5"])).summary
    assert summary["status"] == "walking" and summary["n_steps"] >= 1


@pytest.mark.parametrize("where", ["--set", "file"])
def test_an_alias_bomb_as_walker_kind_is_one_short_line_at_once(where: str, tmp_path: Path) -> None:
    path = tmp_path / "bomb.yaml"
    path.write_text(f"walker:\n  kind: {alias_bomb()}\n" if where == "file" else "{}\n")
    extra = ["--set", f"walker.kind={alias_bomb()}"] if where == "--set" else []
    result, peak = allocation_peak(lambda: invoke("run", str(path), *extra, "--out", str(tmp_path / "o")))
    assert peak < MEMORY_BOUND  # the expansion (10 GB of text) is never built
    line = one_line_error(result.stderr)
    assert result.exit_code == 2 and line.startswith("error: walker.kind: unknown name [[") and len(line) < 300


def test_a_megabyte_string_is_quoted_short() -> None:
    with pytest.raises(ConfigError) as caught:
        config_from_dict({}, ["contact.model=" + "x" * 1_000_000])
    assert str(caught.value).startswith("contact.model: unknown name 'xxx") and len(str(caught.value)) < 300


def test_an_alias_bomb_as_a_sweep_axis_is_one_short_line(tmp_path: Path) -> None:
    path = tmp_path / "bomb.yaml"
    path.write_text(f"name: bomb\nbase: {DEFAULT_CONFIG}\ngrid:\n  walker.kind: {alias_bomb()}\n")
    with pytest.raises(ConfigError, match=r"run 1 \(kind=lol-lol-lol-lol-\.\.\.\): walker\.kind: unknown name"):
        load_sweep(path)


# studies get the sweep's run limit; basin options mean what they say


def test_a_basin_of_a_billion_by_a_billion_cells_is_refused_at_once(tmp_path: Path) -> None:
    args = ["--x", "stance_angle=0.1:0.3:1000000000", "--y", "stance_rate=-0.5:0:1000000000"]
    result, peak = allocation_peak(lambda: invoke("basin", SIMPLEST, *args, "--out", str(tmp_path / "b")))
    assert peak < MEMORY_BOUND
    assert result.exit_code == 2, result.output
    assert "cells (x times y values), more than the limit of 1,000,000" in one_line_error(result.stderr)
    assert not (tmp_path / "b").exists()


def test_a_basin_tolerance_of_zero_is_refused_not_replaced(tmp_path: Path) -> None:
    args = ["--x", "stance_angle=0.1:0.3:3", "--y", "stance_rate=-0.5:0:3", "--tolerance", "0"]
    result = invoke("basin", SIMPLEST, *args, "--out", str(tmp_path / "b"))
    assert result.exit_code == 2
    assert one_line_error(result.stderr) == "error: --tolerance: must be a positive number"


def test_the_basin_api_names_its_arguments_not_the_options() -> None:
    config = config_from_dict({}, ["dynamics=rigid", "walker.kind=simplest"])
    with pytest.raises(ArgumentError, match=r"^tolerance: must be a positive number$"):
        BasinSpec(config, parse_axis("x", "stance_angle=0.1:0.3:3"), parse_axis("y", "stance_rate=-1:0:3"), 5, 0.0)
    with pytest.raises(ArgumentError, match=r"^x: "):
        parse_axis("x", "stance_angle=0.3:0.1:3")


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["bifurcation", SIMPLEST, "--n", "1000000000"], "--n: 1,000,000,000 slopes, more than the limit"),
        (["robustness", SIMPLEST, "--seeds", "1000000000"], "--seeds: 4,000,000,000 rough-ground runs"),
    ],
)
def test_studies_of_too_many_runs_are_refused_at_once(args: list[str], expected: str, tmp_path: Path) -> None:
    out = ["--out", str(tmp_path / "b")] if args[0] == "bifurcation" else []
    result = invoke(*args, *out)
    assert result.exit_code == 2 and expected in one_line_error(result.stderr)


# physics edge cases the validation refused


def test_frictionless_contact_on_level_ground_is_allowed_and_still_refused_on_a_slope() -> None:
    level = ["ground.slope=0", "friction.mu_kinetic=0", "friction.mu_static=0", "friction.model=coulomb"]
    assert config_from_dict({}, level).friction.mu_kinetic == 0.0
    with pytest.raises(ConfigError, match=r"^ground\.slope: steeper than the friction cone"):
        config_from_dict({}, [*level, "ground.slope=0.01"])


# usage errors and help


@pytest.mark.parametrize(
    "args",
    [
        ["robustness", SIMPLEST, "--seeds", "0"],
        ["bifurcation", SIMPLEST, "--n", "1"],
        ["bifurcation", SIMPLEST, "--n", "many"],
        ["run"],
        ["run", str(DEFAULT_CONFIG), "--bogus"],
        ["runn"],
    ],
)
def test_every_usage_error_is_one_line_exit_2(args: list[str], tmp_path: Path) -> None:
    result = invoke(*args, *(["--out", str(tmp_path / "b")] if args[0] == "bifurcation" else []))
    assert result.exit_code == 2, result.output
    one_line_error(result.stderr)
    assert result.stdout == ""


def test_the_real_entry_point_prints_typers_usage_errors_on_one_line(tmp_path: Path) -> None:
    result = subprocess.run([*CLI, "robustness", SIMPLEST, "--seeds", "0"], capture_output=True, text=True,
                            env=child_env(), cwd=tmp_path, timeout=120)  # fmt: skip
    assert result.returncode == 2
    assert "--seeds" in one_line_error(result.stderr)


@pytest.mark.parametrize(
    ("command", "text"),
    [
        ("limit-cycle", "'[stance_angle, stance_rate, swing_angle, swing_rate]'"),
        ("animate", "First simulated time shown [s]."),
        ("bifurcation", "First slope [rad]."),
        ("converge", "LuGre mu_k [default 1.0]."),
    ],
)
def test_help_shows_bracketed_text(command: str, text: str) -> None:
    result = invoke(command, "--help")
    assert result.exit_code == 0
    assert text in " ".join(line.strip("│ ") for line in result.stdout.splitlines())


def test_help_lists_the_commands_in_the_order_a_user_meets_them() -> None:
    listed = [
        line.strip("│ ").split()[0]
        for line in invoke("--help").stdout.split("Commands")[1].splitlines()
        if line.startswith("│ ") and not line.startswith("│  ")
    ]
    assert listed == list(COMMAND_ORDER)


# a sweep's failures: the exit code, a full disk


def test_a_sweep_with_a_diverged_run_exits_1_and_says_so(tmp_path: Path) -> None:
    path = write_sweep(tmp_path, "div", set_={"simulation.t_end": 0.3, "integrator.method": "rk4"},
                       grid={"integrator.dt": [1e-4, 3e-3]})  # fmt: skip
    result = invoke("sweep", str(path), "--jobs", "1", "--out", str(tmp_path / "out"))
    assert result.exit_code == 1, result.output
    assert one_line_error(result.stderr).startswith("error: 1 failed run(s) (1 diverged); see ")
    assert "ran 2: 1 diverged, 1 walking" in result.stdout


@contextmanager
def full_disk_after(
    runs: int, monkeypatch: pytest.MonkeyPatch, stopping: threading.Event | None = None
) -> Iterator[list[Path]]:
    """Writing run directories fails with 'no space left' after ``runs`` of them; yields the directories tried.

    With ``stopping``, a write after the first failed one waits for it to be set first.
    """
    tried: list[Path] = []
    write = run_files.write_run_directory

    def writer(out_dir: Path, *args: object, **kwargs: object) -> None:
        tried.append(out_dir)
        if stopping is not None and len(tried) > runs + 1:
            assert stopping.wait(timeout=120), "the sweep did not stop its executor"
        if len(tried) > runs:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(out_dir / "trajectory.h5"))
        write(out_dir, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(result_module, "write_run_directory", writer)
    yield tried


class StoppedExecutor(ThreadPoolExecutor):
    """One thread whose tasks past the first failed write wait until the sweep stops the executor (its queue
    cancelled by then): the thread cannot outrun the sweep's reaction, however busy the machine."""

    def __init__(self) -> None:
        super().__init__(max_workers=1)
        self.stopping = threading.Event()

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        self.stopping.set()
        super().shutdown(wait, cancel_futures=cancel_futures)


def test_a_sweep_stops_at_the_first_full_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    slopes = [0.01, 0.011, 0.012, 0.013, 0.014, 0.015]
    path = write_sweep(tmp_path, "full", set_={"simulation.t_end": 0.3}, grid={"ground.slope": slopes})
    executor = StoppedExecutor()
    with (
        full_disk_after(1, monkeypatch, executor.stopping) as tried,
        executor,
        pytest.raises(OSError, match="No space left"),
    ):
        run_sweep(load_sweep(path), tmp_path / "out", executor)
    assert len(tried) <= 3  # the queue is cancelled: at most the run the worker took meanwhile went on
    table = pd.read_csv(tmp_path / "out" / "sweep.csv")
    assert list(table["status"]) == ["walking"] + ["pending"] * 5  # resumable: no run failed is taken as finished


def test_the_sweep_command_on_a_full_disk_is_one_line_naming_the_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = write_sweep(tmp_path, "full", set_={"simulation.t_end": 0.3}, grid={"ground.slope": [0.01, 0.012, 0.014]})

    executor = StoppedExecutor()

    @contextmanager
    def in_process(kind: str, jobs: int, scheduler: str | None = None) -> Iterator[ThreadPoolExecutor]:
        with executor:  # the monkeypatched writer works in this process only
            yield executor

    monkeypatch.setattr("biped_sim.sweep.make_executor", in_process)
    with full_disk_after(0, monkeypatch, executor.stopping) as tried:
        result = invoke("sweep", str(path), "--out", str(tmp_path / "out"))
    assert result.exit_code == 1 and len(tried) <= 2
    assert one_line_error(result.stderr) == f"error: {tried[0] / 'trajectory.h5'}: No space left on device"
