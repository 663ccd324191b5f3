"""What SDAR-M still spends time on: the decision's blocked families and step sizes, the soft
limit of the budget and the anytime finish (its spread steps: test_spread.py)."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import pytest

from sdar_tamp.app.plan_export import plan_file_from_solution
from sdar_tamp.app.problem import rearrangement_problem, table_plane
from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import load_instance
from solvers.sdar.attempts import MotionMode
from solvers.sdar.budget import Deadline, Pace
from solvers.sdar.options import SdarOptions
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.sdar.spending import (
    DecisionSpend,
    finish_pace,
    finishing_options,
    finishing_view,
)
from solvers.sdar.tasks import Layout, Move, Step, TaskView
from solvers.solution import Solution
from streams.context import WorldContext

DATA = Path(__file__).parent / "data"
PAPER = domain_file("dual_arm_rearrangement", "domain.pddl").parent / "suites" / "paper"
#: The bases of the four-arm test table (south, north, west, east).
BASES = ((0.0, -0.5), (0.0, 0.5), (-0.6, 0.0), (0.6, 0.0))


def _step(*objs: str) -> Step:
    return Step(tuple(Move(o) for o in objs), "pair")


# -- the decision's spending ---------------------------------------------------------------------


def test_a_failed_family_is_blocked_for_the_decision_in_its_mode() -> None:
    spend = DecisionSpend(4, (2, 6))
    step, arms = _step("a", "b", "c"), ("n", "s", "w")
    assert not spend.blocked(step, arms, MotionMode.QUICK)
    spend.failed(step, arms, MotionMode.QUICK)
    assert spend.blocked(step, arms, MotionMode.QUICK)
    assert not spend.blocked(step, arms, MotionMode.FULL)  # the full stream may still find it
    assert not spend.blocked(step, ("s", "n", "w"), MotionMode.QUICK)  # other arms: another family
    spend.failed(step, arms, MotionMode.FULL)
    assert spend.blocked(step, arms, MotionMode.FULL)
    assert spend.blocked(step, arms, MotionMode.QUICK)


def test_steps_of_fewer_moves_after_failures() -> None:
    spend = DecisionSpend(4, (2, 5))
    four, two, one = _step("a", "b", "c", "d"), _step("e", "f"), _step("g")
    candidates = [four, two, one]
    assert spend.allowed(candidates) == candidates and spend.most_moves == 4
    spend.failed(four, ("1", "2", "3", "4"), MotionMode.QUICK)
    assert spend.most_moves == 4
    spend.failed(four, ("2", "1", "3", "4"), MotionMode.FULL)
    assert spend.most_moves == 2 and spend.allowed(candidates) == [two, one]
    for arms in (("1", "2"), ("2", "1"), ("3", "4")):
        spend.failed(two, arms, MotionMode.FULL)
    assert spend.most_moves == 1 and spend.allowed(candidates) == [one]


def test_with_two_arms_nothing_is_blocked_or_cut() -> None:
    spend = DecisionSpend(2, (1, 1))
    step = _step("a", "b")
    for _ in range(3):
        spend.failed(step, ("l", "r"), MotionMode.FULL)
    assert not spend.blocked(step, ("l", "r"), MotionMode.FULL)
    assert spend.most_moves == 2 and spend.allowed([step]) == [step]


# -- the budget and the finish -------------------------------------------------------------------


class FakeClock:
    """A clock [s] that moves only when told (and by 1 ms per reading, so that time passes
    between two readings)."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        self.now += 1e-3
        return self.now


def test_the_soft_limit_comes_before_max_time_and_can_be_lifted() -> None:
    clock = FakeClock()
    deadline = Deadline(1000.0, clock)
    assert not deadline.passed() and deadline.left() == math.inf  # not started
    deadline.start()
    assert deadline.left() == pytest.approx(1000.0, abs=0.01)
    deadline.reserve(400.0)  # the soft limit at 600 s
    clock.now += 599.0
    assert not deadline.passed()
    clock.now += 1.0
    assert deadline.soft_passed() and deadline.passed() and not deadline.expired()
    deadline.reserve(math.inf)  # lifted: only max_time counts
    assert not deadline.soft_passed() and not deadline.passed()
    deadline.reserve(-1.0)  # a negative reserve is none
    assert not deadline.passed()
    clock.now += 400.0
    assert deadline.expired() and deadline.passed() and not deadline.soft_passed()
    assert Deadline(1.0).clock is time.perf_counter  # the real clock by default


def test_the_reserve_follows_the_pace_measured_in_the_run() -> None:
    pace = Pace(max_time=60.0, prior=4.0, safety=1.3, share=0.9)
    assert pace.reserve(10) == pytest.approx(40.0)  # nothing measured: the prior per object
    pace.decided(6.0, 0, finishing=False)  # a decision that only buffered: still the prior
    assert pace.reserve(10) == pytest.approx(40.0)
    pace.attempted(5.0, True, finishing=False)
    pace.attempted(9.0, False, finishing=False)  # the longest attempt: kept on top
    pace.decided(8.0, 4, finishing=False)  # 14 s for 4 objects, the executed attempt 5 s
    assert pace.per_object() == pytest.approx(1.3 * 5.0)
    assert pace.reserve(2) == pytest.approx(8.0)  # at most the prior per object
    assert pace.reserve(10) == pytest.approx(40.0)
    slow = Pace(max_time=60.0, prior=100.0, safety=1.3, share=0.9)
    slow.attempted(9.0, False, finishing=False)
    slow.decided(8.0, 2, finishing=False)
    assert slow.reserve(1) == pytest.approx(1.3 * 4.0 + 9.0)  # the measured need
    assert slow.reserve(10) == pytest.approx(54.0)  # at most 0.9 of max_time
    pace.decided(3.0, 2, finishing=True)  # the finish's own pace, once measured
    assert pace.per_object() == pytest.approx(1.3 * 1.5)
    assert pace.reserve(10) == pytest.approx(1.3 * 1.5 * 10 + 9.0)
    # a normal decision took 7 s on average: it fits only with 7 s to spare above the reserve
    assert pace.room_for_normal(50.0, 10) and not pace.room_for_normal(25.0, 10)


def test_the_pace_follows_the_last_decisions_when_they_slow_down() -> None:
    pace = Pace(max_time=600.0, prior=100.0, safety=1.5, share=0.9)
    for _ in range(6):
        pace.decided(2.0, 2, finishing=False)  # 1 s per object
    assert pace.per_object() == pytest.approx(1.5 * 1.0)
    for _ in range(3):  # the load rises: 3 s per object; 30 s for 18 objects over the run
        pace.decided(6.0, 2, finishing=False)
    assert pace.per_object() == pytest.approx(1.5 * 3.0)  # the last three, not 1.67
    pace.decided(0.5, 1, finishing=False)  # faster again: the last three 12.5 s for 5
    assert pace.per_object() == pytest.approx(1.5 * 2.5)
    for _ in range(3):  # the run's mean (33.5 s for 22 objects) is the slower one now
        pace.decided(1.0, 1, finishing=False)
    assert pace.per_object() == pytest.approx(1.5 * 33.5 / 22)
    pace.decided(4.0, 0, finishing=False)  # a buffer move counts no object
    assert pace.per_object() == pytest.approx(1.5 * 6.0 / 2)


def test_the_pace_exists_for_finite_budgets_long_enough() -> None:
    pace = finish_pace(SdarOptions(max_time=60.0, finish_reserve=2.0, finish_share=0.5))
    assert pace is not None and pace.reserve(24) == pytest.approx(30.0)  # capped at 30 s
    assert finish_pace(SdarOptions(max_time=60.0, finish_reserve=0.0)) is None
    assert finish_pace(SdarOptions(finish_reserve=2.0)) is None  # no max_time
    assert finish_pace(SdarOptions(max_time=10.0, finish_min_time=20.0)) is None  # latency


def test_the_finishing_view_and_options() -> None:
    graph = DependencyGraph(("a", "b"), ())
    layout = Layout({"a": ((0, 0), (0, 0.1)), "b": ((0.2, 0), (0.2, 0.1))}, BASES)
    view = TaskView(graph, frozenset(), frozenset(), arms=4, layout=layout)
    two = finishing_view(view, 2)
    assert two.arms == 2 and two.layout is None and two.graph is graph
    assert finishing_view(TaskView(graph, frozenset(), frozenset(), arms=1), 2).arms == 1
    options = finishing_options(SdarOptions())
    assert options.choose_among == 1 and options.peer_steps == 0


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("fewer_moves_after", (3, 2), "fewer_moves_after"),
        ("fewer_moves_after", (0, 2), "fewer_moves_after"),
        ("fewer_moves_after", (1,), "fewer_moves_after"),
        ("finish_reserve", -1.0, "finish_reserve"),
        ("finish_reserve", math.nan, "finish_reserve"),
        ("finish_safety", 0.5, "finish_safety"),
        ("finish_gap", -0.1, "finish_gap"),
        ("finish_moves", 0, "finish_moves"),
        ("finish_share", 1.5, "finish_share"),
        ("finish_min_time", -1.0, "finish_min_time"),
    ],
)
def test_bad_spending_options_are_refused(field: str, value: object, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        SdarOptions(**{field: value})  # type: ignore[arg-type]


def _solve_on_fake_clock(
    path: Path, motion_cost: float, **options: object
) -> tuple[SdarSolver, Solution, list[tuple[str, int, float]], FakeClock]:
    """Solve ``path`` on a fake clock on which every motion planned costs ``motion_cost``
    [s]; also the switches into and out of the finish: (which, tasks executed before, time)."""
    instance = load_instance(path)
    ctx = WorldContext.load(instance.scene_path(path))
    r = rearrangement_problem(instance, ctx)
    clock = FakeClock()
    solver = SdarSolver(
        r.problem,
        SdarTaskPlanner(),
        SdarOptions(clock=clock, plane=table_plane(ctx), **options),  # type: ignore[arg-type]
    )
    motion = solver.executor._motion
    switches: list[tuple[str, int, float]] = []
    finish, resume = solver._finish, solver._resume

    def dear(*args: Any) -> str | None:
        clock.now += motion_cost
        return motion(*args)

    def on_finish() -> None:
        switches.append(("finish", len(solver.records), clock.now))
        finish()

    def on_resume() -> None:
        switches.append(("resume", len(solver.records), clock.now))
        resume()

    solver.executor._motion = dear  # type: ignore[method-assign]
    solver._finish = on_finish  # type: ignore[method-assign]
    solver._resume = on_resume  # type: ignore[method-assign]
    return solver, solver.solve(), switches, clock


def test_cheap_motions_never_finish_early() -> None:
    """Motions of 0.5 s: four objects take a few seconds of a 20 s budget, so the run never
    finishes early and plans as a run without the finish (a fixed 2.5 s per object would have
    reserved half the budget)."""
    path = PAPER / "R4.yaml"
    solver, solution, switches, _ = _solve_on_fake_clock(path, 0.5, max_time=20.0)
    assert solution.status.value == "solved" and switches == []
    plain, _, _, _ = _solve_on_fake_clock(path, 0.5, max_time=20.0, finish_reserve=0.0)
    assert [(r.objects, r.arms) for r in solver.records] == [
        (r.objects, r.arms) for r in plain.records
    ]
    assert [len(r.objects) for r in solver.records] == [2, 2]


def test_dear_motions_finish_once_the_pace_measured_needs_the_time_left() -> None:
    """Motions of 8 s (and a ceiling of 100 s per object): the first two-object step takes
    16 s; at that pace the two objects left need more than the 44 s left (1.5 x 16 s each,
    plus the longest attempt), so the run
    finishes with one-move steps from there and ends before max_time."""
    solver, solution, switches, clock = _solve_on_fake_clock(
        PAPER / "R4.yaml", 8.0, max_time=60.0, finish_reserve=100.0
    )
    assert solution.status.value == "solved"
    assert switches == [("finish", 1, pytest.approx(16.0, abs=0.1))]
    assert [len(r.objects) for r in solver.records] == [2, 1, 1]
    assert clock.now < 60.0


def test_a_run_past_its_soft_limit_finishes_with_one_move_steps() -> None:
    """Without spread steps (``finish_gap=0``), a prior reserve larger than the budget: the
    run finishes from its first decision; at 50 s a motion its own pace keeps it finishing
    until the last object, and the goal is reached (the anytime finish, not a timeout)."""
    solver, solution, switches, _ = _solve_on_fake_clock(
        DATA / "four_arm_cycle.yaml", 50.0, max_time=600.0, finish_reserve=1000.0,
        finish_share=1.0, finish_moves=1, finish_gap=0.0,
    )  # fmt: skip
    assert solution.status.value == "solved", solution.diagnosis
    assert switches[0] == ("finish", 0, pytest.approx(0.0, abs=0.1))
    assert all(len(record.objects) == 1 for record in solver.records)
    # the 4-cycle without a rotation: one object through a buffer
    assert sum(sum(record.to_buffer) for record in solver.records) == 1


def test_a_finish_moves_four_objects_apart_in_one_step_and_the_replay_accepts_it() -> None:
    """Finishing from the first decision, four objects each in front of its own arm go in one
    spread step (two motions) instead of four one-move steps (eight)."""
    path = DATA / "four_arm_apart.yaml"
    options = {"max_time": 600.0, "finish_reserve": 1000.0, "finish_share": 1.0}
    solver, solution, switches, clock = _solve_on_fake_clock(path, 50.0, **options)
    assert solution.status.value == "solved", solution.diagnosis
    assert switches == [("finish", 0, pytest.approx(0.0, abs=0.1))]
    (record,) = solver.records
    value = solver.cache.table.value
    assert record.kind == "spread" and sorted(map(value, record.objects)) == [
        "o0",
        "o1",
        "o2",
        "o3",
    ]
    assert sorted(map(value, record.arms)) == ["east", "north", "south", "west"]
    assert clock.now == pytest.approx(100.0, abs=0.5)  # two motions
    instance = load_instance(path)
    r = rearrangement_problem(instance, WorldContext.load(instance.scene_path(path)))
    replayed = SdarSolver(
        r.problem, SdarTaskPlanner(), SdarOptions(plane=table_plane(r.ctx), **options)
    )  # the real clock: the same plan
    plan = plan_file_from_solution(r, replayed.solve())
    assert [t.kind for t in replayed.records] == ["spread"]
    report = validate_plan(instance, plan, r.ctx.scene)
    assert report.ok, report.violation
    _, one_by_one, _, slow = _solve_on_fake_clock(path, 50.0, finish_gap=0.0, **options)
    assert one_by_one.status.value == "solved" and slow.now > clock.now


def test_a_finish_whose_own_pace_leaves_room_goes_back_to_the_normal_search() -> None:
    """The same prior, motions of 20 s: after two finishing steps (a buffer, then one object
    in 80 s) the three objects left need 3 x 1.5 x 80 s = 360 s of the 520 s left, so the run
    goes back to the normal search, which rotates the 3-cycle left in one step."""
    solver, solution, switches, _ = _solve_on_fake_clock(
        DATA / "four_arm_cycle.yaml", 20.0, max_time=600.0, finish_reserve=1000.0,
        finish_share=1.0, finish_moves=1, finish_gap=0.0,
    )  # fmt: skip
    assert solution.status.value == "solved", solution.diagnosis
    assert [s[:2] for s in switches] == [("finish", 0), ("resume", 2)]
    assert [len(r.objects) for r in solver.records] == [1, 1, 3]
