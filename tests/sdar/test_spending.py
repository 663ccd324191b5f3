"""What SDAR-M still spends time on: the decision's blocked families and step sizes, the soft
limit of the budget and the anytime finish, and the steps SDAR-T no longer proposes because
their arms obviously meet."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import cast

import pytest

from sdar_tamp.app.problem import rearrangement_problem, table_plane
from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph
from sdar_tamp.world.instance import load_instance
from solvers.sdar.assignment import ArmAssigner
from solvers.sdar.attempts import MotionMode
from solvers.sdar.budget import Deadline
from solvers.sdar.cache import StreamCache
from solvers.sdar.k_steps import TaskScene, meets, rotations
from solvers.sdar.move_option import Option
from solvers.sdar.options import SdarOptions
from solvers.sdar.report import Failures
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.sdar.spending import (
    DecisionSpend,
    finish_reserve,
    finishing_options,
    finishing_view,
)
from solvers.sdar.tasks import Layout, Move, Step, TaskView
from streams.context import WorldContext

DATA = Path(__file__).parent / "data"
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


def test_the_soft_limit_comes_before_max_time_and_can_be_lifted() -> None:
    deadline = Deadline(1000.0)
    assert not deadline.passed() and deadline.left() == math.inf  # not started
    deadline.start()
    assert 990.0 < deadline.left() <= 1000.0
    deadline.reserve(999.9999)  # the soft limit 0.1 ms after the start
    time.sleep(0.01)
    assert deadline.soft_passed() and deadline.passed() and not deadline.expired()
    deadline.reserve(math.inf)  # lifted: only max_time counts
    assert not deadline.soft_passed() and not deadline.passed()
    deadline.reserve(-1.0)  # a negative reserve is none
    assert not deadline.passed()
    over = Deadline(0.0)
    over.start()
    time.sleep(0.001)
    assert over.expired() and over.passed() and not over.soft_passed()


def test_the_reserve_grows_with_the_objects_left_up_to_a_share_of_the_budget() -> None:
    options = SdarOptions(max_time=60.0, finish_reserve=2.0, finish_share=0.5)
    assert finish_reserve(options, 3) == pytest.approx(6.0)
    assert finish_reserve(options, 24) == pytest.approx(30.0)  # capped at half of 60 s
    assert finish_reserve(SdarOptions(max_time=60.0, finish_reserve=0.0), 3) == math.inf
    assert finish_reserve(SdarOptions(finish_reserve=2.0), 3) == math.inf  # no max_time
    short = SdarOptions(max_time=10.0, finish_min_time=20.0)  # a latency budget
    assert finish_reserve(short, 3) == math.inf


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
        ("finish_moves", 0, "finish_moves"),
        ("finish_share", 1.5, "finish_share"),
        ("finish_min_time", -1.0, "finish_min_time"),
    ],
)
def test_bad_spending_options_are_refused(field: str, value: object, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        SdarOptions(**{field: value})  # type: ignore[arg-type]


def test_a_run_past_its_soft_limit_finishes_with_one_move_steps() -> None:
    """A reserve larger than the budget: the run finishes from its first decision; every step
    holds one move, and the goal is reached (the anytime finish, not a timeout)."""
    path = DATA / "four_arm_cycle.yaml"
    instance = load_instance(path)
    ctx = WorldContext.load(instance.scene_path(path))
    r = rearrangement_problem(instance, ctx)
    options = SdarOptions(
        max_time=600.0, finish_reserve=1000.0, finish_share=1.0, finish_moves=1,
        plane=table_plane(ctx),
    )  # fmt: skip
    solver = SdarSolver(r.problem, SdarTaskPlanner(), options)
    solution = solver.solve()
    assert solution.status.value == "solved", solution.diagnosis
    assert solver.finishing
    assert all(len(record.objects) == 1 for record in solver.records)
    # the 4-cycle without a rotation: one object through a buffer
    assert sum(sum(record.to_buffer) for record in solver.records) == 1


# -- SDAR-T: steps whose arms obviously meet -----------------------------------------------------


def _layout_view(places: dict[str, tuple[tuple[float, float], tuple[float, float]]],
                 edges: tuple[tuple[int, int], ...] = ()) -> TaskView:  # fmt: skip
    names = tuple(sorted(places))
    graph = DependencyGraph(names, edges)
    return TaskView(graph, frozenset(), frozenset(), arms=4, layout=Layout(places, BASES))


def test_a_step_whose_arms_cross_whatever_the_seating_is_not_proposed() -> None:
    # three objects crossing one point of the table: every seating on arms crosses there
    crossing = {
        "a": ((-0.15, -0.15), (0.15, 0.15)),
        "b": ((0.15, -0.15), (-0.15, 0.15)),
        "c": ((0.0, -0.2), (0.0, 0.2)),
    }
    assert meets(_layout_view(crossing), ("a", "b", "c"))
    apart = {
        "a": ((-0.2, -0.15), (-0.2, -0.05)),
        "b": ((0.2, 0.15), (0.2, 0.05)),
        "c": ((0.0, 0.2), (0.05, 0.2)),
    }
    assert not meets(_layout_view(apart), ("a", "b", "c"))
    assert not meets(_layout_view(crossing), ("a", "b"))  # two moves: left to SDAR-M
    no_layout = TaskView(DependencyGraph(("a", "b", "c"), ()), frozenset(), frozenset(), arms=4)
    assert not meets(no_layout, ("a", "b", "c"))


def test_a_rotation_whose_arms_cross_is_not_proposed_one_apart_is() -> None:
    # a 3-cycle a -> b -> c -> a: a's goal is b's start, and so on
    edges = ((0, 1), (1, 2), (2, 0))
    through = {  # a tight ring at the table's centre: every arm reaches into it
        "a": ((0.0, 0.0), (0.04, 0.0)),
        "b": ((0.04, 0.0), (0.02, 0.035)),
        "c": ((0.02, 0.035), (0.0, 0.0)),
    }
    view = _layout_view(through, edges)
    assert meets(view, ("a", "b", "c"))
    assert rotations(TaskScene(view), 4) == []
    # the test cells' 3-cycle (data/three_arm_cycle.yaml) is rotated by three arms
    ring = {
        "a": ((0.1, -0.15), (-0.1, -0.15)),
        "b": ((-0.1, -0.15), (0.0, 0.15)),
        "c": ((0.0, 0.15), (0.1, -0.15)),
    }
    kept = rotations(TaskScene(_layout_view(ring, edges)), 4)
    assert [step.objects for _, step in kept] == [("a", "b", "c")]


def test_the_finish_takes_a_one_move_steps_arms_by_plane_reach_without_ik() -> None:
    asked: list[str] = []

    def options(arm: str, *args: object) -> list[Option]:
        asked.append(arm)
        return []

    home = {"east": "q", "north": "q", "south": "q", "west": "q"}
    assigner = ArmAssigner(
        cast(StreamCache, None), SdarOptions(), home, cast(Failures, None), options
    )
    bases = ((0.6, 0.0), (0.0, 0.5), (0.0, -0.5), (-0.6, 0.0))  # sorted arms: e, n, s, w
    layout = Layout({"a": ((0.5, -0.1), (0.5, -0.2))}, bases)
    assigner.by_plane = True
    order = assigner.assignments(Step((Move("a"),), "single"), layout)
    assert order == [("east",), ("south",), ("north",), ("west",)]
    assert asked == []  # no IK asked to rank them
