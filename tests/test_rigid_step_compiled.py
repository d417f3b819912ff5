"""The compiled rigid step with pushes, ground profiles, samples and stop strikes: its energy books, its footing on
a profile, its trips, and its slow reference, the same code run as plain Python, bit for bit.

Walkers: Chen's kneed walker (a knee stop strikes mid-swing) and the compass (Goswami's near-point feet and the
round-foot walker), each started near its gait (section points of their rigid limit cycles).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from numba import njit
from numba.core.registry import CPUDispatcher

from biped_sim import load_config, simulate
from biped_sim.config import Config, derive
from biped_sim.integrate.stepper import Scratch, make_scratch
from biped_sim.integrate.tableaus import Tableau, tableau
from biped_sim.rigid import compiled
from biped_sim.rigid.build import rigid_walker
from biped_sim.rigid.ground import Footing, ProfileStrike, rigid_ground
from biped_sim.rigid.integration import ROOT_TOL, event_root
from biped_sim.rigid.tree import RigidWalker

from .conftest import CONFIGS, run_as_plain_python

# config, a section point near its gait (stance angle, both rates)
WALKERS = {
    "kneed": (CONFIGS / "kneed_walker.yaml", [0.23858546, -1.10958733, -0.05714811]),
    "compass": (CONFIGS / "compass_goswami.yaml", [0.27130009, -1.09317942, -0.37759863]),
    "round_foot": (CONFIGS / "round_foot_walker.yaml", [0.27136095, -1.61448028, -0.84377804]),
}


def _config(name: str) -> Config:
    return load_config(WALKERS[name][0], ["dynamics=rigid"])


@pytest.fixture(scope="module", params=list(WALKERS))
def case(request: pytest.FixtureRequest) -> tuple[Config, RigidWalker, np.ndarray]:
    config = _config(request.param)
    walker = rigid_walker(config)
    return config, walker, walker.from_section(np.array(WALKERS[request.param][1]))


def _pushes(walker: RigidWalker) -> list[tuple[float, np.ndarray]]:
    """Two pushes on the hip, forward then back, of a few percent of the walker's momentum scale."""
    scale = walker.reference_mass * np.sqrt(walker.gravity * walker.leg_length)
    return [(0.15, scale * np.array([0.02, 0.005])), (0.3, scale * np.array([-0.01, 0.0]))]


def _profile(config: Config, walker: RigidWalker, x0: np.ndarray, at: float, height: float) -> ProfileStrike:
    """One step of ``height`` leg lengths at ``at`` of the plane's step length ahead of the stance contact (x = 0)."""
    step = {"at": at * compiled.rigid_step(walker, x0).length, "height": height * walker.leg_length}
    ground = rigid_ground(derive(config, {"ground.profile": {"kind": "steps", "steps": [step]}}))
    assert ground is not None
    return ProfileStrike(walker, ground, Footing(-walker.contact_point(x0[: walker.n_q])[0], 0.0))


def test_a_plain_step_conserves_energy_but_for_its_stop_strikes(case) -> None:  # type: ignore[no-untyped-def]
    _, walker, x0 = case
    mine = compiled.rigid_step(walker, x0)
    assert mine.status == "strike"
    scale = walker.reference_mass * walker.gravity * walker.leg_length
    change = sum(walker.energy(mine.x_minus)) - sum(walker.energy(x0))
    assert change == pytest.approx(-sum(loss for _, loss in mine.stop_strikes), abs=1e-10 * scale)
    knees = walker.n_q > 2
    assert len(mine.stop_strikes) == (1 if knees else 0)  # the kneed walker's knee strike, booked with its loss
    if knees:
        assert 0.0 < mine.stop_strikes[0][0] < mine.period and mine.stop_strikes[0][1] > 0.0


def test_pushes_work_closes_the_energy_balance(case) -> None:  # type: ignore[no-untyped-def]
    _, walker, x0 = case
    mine = compiled.rigid_step(walker, x0, pushes=_pushes(walker))
    assert mine.status == "strike" and [t for t, *_ in mine.pushes] == [0.15, 0.3]
    # between strikes the energy changes only by the pushes' work and the stop strikes' losses
    work = sum(w for _, w, _ in mine.pushes) - sum(loss for _, loss in mine.stop_strikes)
    change = sum(walker.energy(mine.x_minus)) - sum(walker.energy(x0))
    assert abs(work) > 1e-3 * walker.reference_mass * walker.gravity * walker.leg_length  # pushes that do work
    assert change == pytest.approx(work, abs=1e-10 * walker.reference_mass * walker.gravity * walker.leg_length)


def test_a_push_at_the_start_is_the_tree_walkers_hip_push(case) -> None:  # type: ignore[no-untyped-def]
    _, walker, x0 = case
    impulse = _pushes(walker)[1][1]  # backward: a forward one would snap the kneed walker's swing knee straight at once
    step = compiled.rigid_step(walker, x0, sample_rate=100.0, pushes=[(0.0, impulse)])
    walker.begin_step()  # the locks of a step's start (the walker's parameters keep those of its last use)
    after, normal = walker.hip_push(x0, impulse)
    assert step.samples_t[0] == 0.0 and np.array_equal(step.samples_x[0], after)  # the sample after the push
    work = walker.energy(after)[0] - walker.energy(x0)[0]
    assert step.pushes == [(0.0, pytest.approx(work, abs=1e-15), pytest.approx(normal, abs=1e-15))]


def test_pushes_at_one_time_are_one_push_of_their_sum(case) -> None:  # type: ignore[no-untyped-def]
    _, walker, x0 = case
    (at, a), (_, b) = _pushes(walker)
    # the jump is linear in the impulse at fixed angles; the second push, at or within 1e-15 s of the first, follows it
    together = compiled.rigid_step(walker, x0, pushes=[(at, a + b)])
    for second in (at, at + 1e-15):
        apart = compiled.rigid_step(walker, x0, pushes=[(at, a), (second, b)])
        assert [t for t, *_ in apart.pushes] == [at, at]  # the second at the state's time: within MIN_STEP of its own
        assert apart.status == together.status == "strike"
        assert np.max(np.abs(apart.x_minus - together.x_minus)) < 1e-11
        assert sum(w for _, w, _ in apart.pushes) == pytest.approx(together.pushes[0][1], rel=1e-12)


def test_a_step_down_lands_on_the_lower_tread(case) -> None:  # type: ignore[no-untyped-def]
    config, walker, x0 = case
    profile = _profile(config, walker, x0, 0.6, -0.01)
    mine = compiled.rigid_step(walker, x0, 200.0, _pushes(walker), profile)
    assert mine.status == "strike" and len(mine.samples_t) > 50 and mine.x_plus is not None
    footing = profile.after(mine.x_minus, mine.x_plus).footing
    assert footing.level == pytest.approx(-0.01 * walker.leg_length, abs=1e-12)  # landed on the lower tread
    assert abs(profile.clearance(mine.x_minus)) < 1e-12  # the swing foot's lowest point on the profile
    assert abs(mine.period - compiled.rigid_step(walker, x0, pushes=_pushes(walker)).period) > 1e-4  # a later strike


@pytest.mark.parametrize("at", [0.3, 0.9])  # the swing foot below the profile when the strike is sought; a riser hit
def test_a_riser_trips_both_at_the_same_point(case, at: float) -> None:  # type: ignore[no-untyped-def]
    config, walker, x0 = case
    profile = _profile(config, walker, x0, at, 0.2)
    mine = compiled.rigid_step(walker, x0, 200.0, (), profile)
    assert mine.status == "tripped" and mine.x_plus is None and len(mine.samples_t) > 20  # sampled up to the trip
    assert profile.tripped(mine.x_minus) or profile.clearance(mine.x_minus) < 0.0  # at the riser, or under the tread


@contextmanager
def plain_python(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The rigid step map as plain Python: every compiled function of the rigid, integration and contact modules is
    its plain-Python function (conftest.plain_function)."""
    with monkeypatch.context() as patch:
        run_as_plain_python(patch, ("biped_sim.rigid", "biped_sim.integrate", "biped_sim.contact"))
        yield


def test_the_compiled_step_is_its_plain_python_run_bit_for_bit(monkeypatch: pytest.MonkeyPatch) -> None:
    config = _config("round_foot")
    walker = rigid_walker(config)
    x0 = walker.from_section(np.array(WALKERS["round_foot"][1]))
    profile = _profile(config, walker, x0, 0.6, -0.01)
    args = (walker, x0, 100.0, _pushes(walker), profile)
    fast = compiled.rigid_step(*args)
    with plain_python(monkeypatch):
        assert not isinstance(compiled.step_kernel, CPUDispatcher)
        plain = compiled.rigid_step(*args)
    assert fast.status == plain.status == "strike" and len(fast.pushes) == 2
    assert fast.period == plain.period and (fast.rhs_evals, fast.accepted_steps) == (
        plain.rhs_evals,
        plain.accepted_steps,
    )
    for field in ("x_minus", "x_plus", "samples_t", "samples_x"):
        assert getattr(fast, field).tobytes() == getattr(plain, field).tobytes(), field
    assert fast.pushes == plain.pushes and fast.stop_strikes == plain.stop_strikes


def test_a_plain_step_through_its_entry_is_the_dispatched_step_bit_for_bit(case) -> None:  # type: ignore[no-untyped-def]
    """A plain step with the caller's buffers runs step_kernel's entry found once for them (no typing per call)."""
    _, walker, x0 = case
    cw = compiled.compile_walker(walker)
    first, again = compiled.rigid_step(walker, x0, cw=cw), compiled.rigid_step(walker, list(x0), cw=cw)
    assert id(cw) in compiled._ENTRIES
    x_minus, x_plus, counters = np.zeros_like(x0), np.zeros_like(x0), np.zeros(2, dtype=np.int64)
    code, period = compiled.step_kernel(cw, x0.copy(), x_minus, x_plus, counters)  # the dispatcher's call
    assert compiled.STATUS_NAMES[code] == first.status == again.status == "strike"
    assert period == first.period == again.period and x_plus.tobytes() == first.x_plus.tobytes()
    assert again.x_plus.tobytes() == first.x_plus.tobytes() and counters.tolist() == [
        first.rhs_evals,
        first.accepted_steps,
    ]


def test_a_run_with_a_push_and_steps_closes_its_energy_balance() -> None:
    overrides = [
        "simulation.t_end=2.5",
        "simulation.pushes=[{time: 0.9, impulse: [0.03, 0.0]}]",
        "ground.profile={kind: steps, steps: [{at: 0.7, height: -0.004}, {at: 1.6, height: 0.003}]}",
    ]
    run = simulate(load_config(CONFIGS / "kneed_walker.yaml", overrides))
    assert run.status == "walking" and len(run.strike_time) >= 4 and len(run.pushes) == 1  # type: ignore[attr-defined]
    assert np.max(np.abs(run.energy.residual)) < 1e-9 * run.walker.reference_mass * run.walker.gravity  # type: ignore[attr-defined]


@njit(cache=True, inline="always")
def _line_inlined(on: tuple[float, float], j: int, x: np.ndarray) -> float:
    return on[0] * x[0] + on[1]


@njit(cache=True)
def _line_called(on: tuple[float, float], j: int, x: np.ndarray) -> float:
    return on[0] * x[0] + on[1]


@njit(cache=True)
def _event_roots(tab: Tableau, sc: Scratch, y: np.ndarray, on: tuple[float, float]) -> tuple[float, float]:
    """The one event search with an event function that numba inlines and with one that it calls."""
    return (
        event_root(_line_inlined, on, tab, sc, 0, 0.0, 1.0, y),
        event_root(_line_called, on, tab, sc, 0, 0.0, 1.0, y),
    )


def test_the_event_search_finds_the_root_of_the_dense_output_with_its_event_function_inlined_or_called() -> None:
    """DOP853's dense output set to y(theta) = 1 - 2 theta + theta (1 - theta) / 2 over a step of length 1 at t = 0,
    the event 2 y - 0.5: its zero theta = (-3 + sqrt(15)) / 2 to a few ROOT_TOL, the same bits either way; a step
    that ends on the zero returns 1."""
    tab, sc = tableau("dop853"), make_scratch(1, 0, 1)
    y = np.array([1.0])
    sc.dense[0, 0], sc.dense[1, 0] = -2.0, 0.5  # y + theta (d0 + (1 - theta) d1)
    on = (2.0, -0.5)
    sc.g_old[0], sc.g_new[0] = 1.5, -2.5
    inlined, called = _event_roots(tab, sc, y, on)
    assert abs(inlined - (-3.0 + np.sqrt(15.0)) / 2.0) <= 4 * ROOT_TOL
    assert np.float64(inlined).tobytes() == np.float64(called).tobytes()
    sc.g_new[0] = 0.0
    assert _event_roots(tab, sc, y, on) == (1.0, 1.0)
