"""SDAR-M end to end on small rearrangements: plans of the domain, statuses, diagnoses."""

from __future__ import annotations

import math
from collections.abc import Generator, Iterator
from typing import Any

import numpy as np
import pytest

from sdar_tamp.app import (
    Rearrangement,
    plan_file_from_solution,
    rearrangement_problem,
    solve_rearrangement,
)
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from solvers.sdar.report import PlannedStep
from solvers.solution import Certificate, Solution, Status
from solvers.solve import solve
from streams.context import WorldContext
from streams.motion.planner import MotionPlanner
from streams.stream_map import make_stream_map

#: A solve's time budget: generous, so that a busy machine slows a test down but never turns
#: a solvable case into a timeout (the budget is not what these tests check).
BUDGET = 600.0

SIZE = (0.08, 0.04, 0.05)
WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))


def _swap() -> Instance:
    """Two objects whose goals are each other's starts (a 2-cycle: one dual-arm swap)."""
    a, b = Pose2D(-0.1, 0.1, 0.0), Pose2D(0.1, -0.1, 0.5)
    return Instance("swap", WORKSPACE, (ObjectSpec("a", SIZE, a, b), ObjectSpec("b", SIZE, b, a)))


@pytest.fixture(scope="module")
def solved_three(ctx: WorldContext, planner: MotionPlanner) -> tuple[Rearrangement, Solution]:
    """``_three`` (seed 0) solved once by ``solve_rearrangement`` for the tests that only read
    the solution. With the default motion planner its options are ``SdarOptions(max_time)``
    (the default quick attempts), so it is also the quick run of the motion-stream test."""
    r = rearrangement_problem(_three(), ctx, planner=planner)
    return r, solve_rearrangement(r, "sdar", BUDGET)


@pytest.fixture(scope="module")
def solved_swap(ctx: WorldContext, planner: MotionPlanner) -> tuple[Rearrangement, Solution]:
    """``_swap`` (seed 0) solved once, through the generic entry point
    ``solve(algorithm="sdar")``; with the default motion planner ``solve_rearrangement`` runs
    the same solver configuration (``test_both_entry_points_configure_sdar_alike``)."""
    r = rearrangement_problem(_swap(), ctx, planner=planner)
    return r, solve(r.problem, algorithm="sdar", max_time=BUDGET, verbose=False)


def _three() -> Instance:
    """A chain c -> b (c's goal is b's start) and an independent object a."""
    return Instance(
        "three",
        WORKSPACE,
        (
            ObjectSpec("a", SIZE, Pose2D(-0.15, 0.2, 0.0), Pose2D(-0.15, -0.2, 0.0)),
            ObjectSpec("b", SIZE, Pose2D(0.1, 0.0, 0.0), Pose2D(0.1, 0.2, 1.0)),
            ObjectSpec("c", SIZE, Pose2D(0.1, -0.2, 0.3), Pose2D(0.1, 0.0, 0.0)),
        ),
    )


def test_swap_is_one_synchronous_dual_arm_step(
    ctx: WorldContext, solved_swap: tuple[Rearrangement, Solution]
) -> None:
    r, solution = solved_swap
    assert solution.status is Status.SOLVED
    names = [a.name for a in solution.plan or []]
    assert names == ["move", "pick-both", "move", "place-both"]
    assert [t.kind for t in solution.trace] == ["swap"]
    plan = plan_file_from_solution(r, solution)
    assert plan.metrics.actions == 2 and plan.metrics.dual_arm_steps == 2
    report = validate_plan(r.instance, plan, ctx.scene)
    assert report.ok, report.violation


def test_plan_is_a_plan_of_the_domain(
    ctx: WorldContext, solved_three: tuple[Rearrangement, Solution]
) -> None:
    r, solution = solved_three
    assert solution.status is Status.SOLVED and solution.plan is not None
    # Checked by code that shares nothing with SDAR: the timed plan is replayed by the
    # geometric validator (every object at its goal, no collision, limits), and the plan's
    # cost is the sum of the domain's action costs (motion durations and gripper times).
    plan = plan_file_from_solution(r, solution)
    report = validate_plan(r.instance, plan, ctx.scene)
    assert report.ok, report.violation
    gripper = {"pick": 0.5, "place": 0.5, "pick-both": 0.5, "place-both": 0.5}
    expected = sum(
        float(a.args[1].trajectory.duration)  # move ?d1 ?t ?d2
        if a.name == "move"
        else gripper[a.name]
        for a in solution.plan
    )
    assert expected == pytest.approx(solution.cost)
    # c waits for b (chain): b is placed no later than c
    placed = [a.args for a in solution.plan if a.name.startswith("place")]
    order = [x for args in placed for x in args if x in ("a", "b", "c")]
    assert order.index("b") <= order.index("c")


def test_baseline_task_planner_solves_too(ctx: WorldContext, planner: MotionPlanner) -> None:
    r = rearrangement_problem(_swap(), ctx, planner=planner)
    solution = solve_rearrangement(r, "baseline", BUDGET)
    assert solution.status is Status.SOLVED
    # the baseline has no dual-arm swap: one object goes through a buffer
    assert sum(sum(t.to_buffer) for t in solution.trace) == 1


def test_solve_entry_point_runs_sdar(solved_swap: tuple[Rearrangement, Solution]) -> None:
    plan, cost, _ = solved_swap[1]  # from solve(r.problem, algorithm="sdar")
    assert plan is not None and cost > 0


def test_both_entry_points_configure_sdar_alike(
    ctx: WorldContext, planner: MotionPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With the default motion planner, ``solve_rearrangement``, ``solve(algorithm="sdar")``
    and ``rearrangement_steps`` build the same solver (problem, task planner, options), so what
    the tests check of one holds for the others."""
    from sdar_tamp.app.solving import rearrangement_steps
    from solvers.sdar.solver import SdarSolver, run_to_end

    built: list[tuple[Any, ...]] = []

    def record(self: SdarSolver) -> Generator[PlannedStep, None, Solution]:
        built.append((self.cache.problem, type(self.planner), self.options))
        return Solution(None, math.inf, Certificate((), ()))
        yield  # a generator, as the decision loop is

    monkeypatch.setattr(SdarSolver, "steps", record)  # solve() runs steps() to its end
    r = rearrangement_problem(_swap(), ctx, planner=planner)
    solve(r.problem, algorithm="sdar", max_time=BUDGET, verbose=False)
    solve_rearrangement(r, "sdar", BUDGET)
    run_to_end(rearrangement_steps(r, "sdar", BUDGET))  # a stream's steps: the same solver
    assert len(built) == 3 and built[0] == built[1] == built[2]


def test_steps_yield_each_decision_and_return_the_solution(
    ctx: WorldContext, planner: MotionPlanner, solved_three: tuple[Rearrangement, Solution]
) -> None:
    """``steps()`` yields each executed decision as it is executed: its actions, in order,
    are the plan ``solve()`` returns (the same loop), and the generator returns that
    solution."""
    from sdar_tamp.app.solving import rearrangement_steps

    r = rearrangement_problem(_three(), ctx, planner=planner)
    steps = rearrangement_steps(r, "sdar", BUDGET)
    yielded: list[PlannedStep] = []
    while True:
        try:
            yielded.append(next(steps))
        except StopIteration as end:
            solution = end.value
            break
    assert [s.index for s in yielded] == list(range(len(yielded))) and len(yielded) >= 2
    assert solution.plan is not None
    assert [a for s in yielded for a in s.actions] == list(solution.plan)
    assert tuple(s.task for s in yielded) == solution.trace
    batch = solved_three[1].plan
    assert batch is not None and [a.name for a in solution.plan] == [a.name for a in batch]


def test_no_ik_gives_infeasible_with_a_diagnosis(ctx: WorldContext, planner: MotionPlanner) -> None:
    def no_ik(*_args: Any, **_kwargs: Any) -> Iterator[Any]:
        return iter(())

    r = rearrangement_problem(
        _swap(), ctx, planner=planner, overrides={"inverse-kinematics": no_ik}
    )
    solution = solve_rearrangement(r, "sdar", BUDGET)
    assert solution.status is Status.INFEASIBLE and solution.plan is None
    assert "no candidate step could be grounded" in solution.diagnosis[0]
    assert any("no grasp with IK" in d for d in solution.diagnosis)


def test_time_limit_gives_timeout(ctx: WorldContext, planner: MotionPlanner) -> None:
    r = rearrangement_problem(_three(), ctx, planner=planner)
    solution = solve_rearrangement(r, "sdar", 1e-6)
    assert solution.status is Status.TIMEOUT
    assert "max_time" in solution.diagnosis[0]


def test_crowded_goal_is_unblocked_by_an_eviction(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """a cannot be picked while b rests at its start, and a cannot be placed while b rests at
    its goal: b must go to its goal first, then make room for a (an eviction), then return."""
    inst = Instance(
        "crowded",
        WORKSPACE,
        (
            ObjectSpec("a", SIZE, Pose2D(-0.15, 0.2, 0.0), Pose2D(-0.15, -0.2, 0.0)),
            ObjectSpec("b", SIZE, Pose2D(0.15, 0.2, 0.0), Pose2D(0.15, -0.2, 0.0)),
        ),
    )
    real = make_stream_map(ctx, {o.name: o.size for o in inst.objects})["inverse-kinematics"]
    b_start, b_goal = inst.objects[1].start, inst.objects[1].goal
    a_goal = inst.objects[0].goal

    def crowded_ik(arm: str, o: str, p: Pose2D, g: Any, fluents: Any = ()) -> Iterator[Any]:
        resting = {(f[1], f[2]) for f in fluents if f[0] == "atpose"}
        if o == "a" and p != a_goal and ("b", b_start) in resting:
            return iter(())
        if o == "a" and p == a_goal and ("b", b_goal) in resting:
            return iter(())
        return real(arm, o, p, g, fluents)

    r = rearrangement_problem(
        inst, ctx, planner=planner, overrides={"inverse-kinematics": crowded_ik}
    )
    solution = solve_rearrangement(r, "sdar", BUDGET)
    assert solution.status is Status.SOLVED, solution.diagnosis
    kinds = [t.kind for t in solution.trace]
    assert "evict" in kinds


def test_sdar_refuses_a_domain_without_the_rearrangement_roles() -> None:
    from domains.kitchen.samplers import make_problem

    with pytest.raises(ParameterError, match="needs a rearrangement domain; missing: stream"):
        solve(make_problem(), algorithm="sdar")


def test_sdar_needs_a_goal_of_object_poses(ctx: WorldContext) -> None:
    r = rearrangement_problem(_swap(), ctx)
    p = r.problem
    other = PDDLProblem(
        domain_file("dual_arm_rearrangement").read_text(encoding="utf-8"),
        {},
        p.stream_pddl,
        p.stream_map,
        p.init,
        ("empty", "left"),
    )
    with pytest.raises(ParameterError, match="conjunction of"):
        solve(other, algorithm="sdar")


def test_unknown_task_planner_and_override_are_refused(ctx: WorldContext) -> None:
    r = rearrangement_problem(_swap(), ctx)
    with pytest.raises(ParameterError, match="task_planner must be one of sdar, baseline"):
        solve(r.problem, algorithm="sdar", task_planner="greedy")
    with pytest.raises(ParameterError, match="overrides: unknown streams"):
        rearrangement_problem(_swap(), ctx, overrides={"sample-pose": print})
    with pytest.raises(ParameterError, match="motion must be one of sdar, plain, sequential"):
        rearrangement_problem(_swap(), ctx, motion="fast")


def test_same_seed_gives_the_same_plan(
    ctx: WorldContext, planner: MotionPlanner, solved_three: tuple[Rearrangement, Solution]
) -> None:
    # a second, independent solve of the shared instance with the same seed (0)
    r = rearrangement_problem(_three(), ctx, planner=planner, seed=0)
    a = plan_file_from_solution(*solved_three)
    b = plan_file_from_solution(r, solve_rearrangement(r, "sdar", BUDGET))
    assert np.array_equal(a.q, b.q) and np.array_equal(a.t, b.t)
    assert [(e.t, e.arm, e.type, e.object) for e in a.events] == [
        (e.t, e.arm, e.type, e.object) for e in b.events
    ]


@pytest.mark.parametrize(("task_planner", "instance"), [("baseline", _three), ("sdar", _swap)])
def test_baseline_motion_planner_works_one_arm_at_a_time(
    ctx: WorldContext, planner: MotionPlanner, task_planner: str, instance: Any
) -> None:
    """The baseline motion planner: one arm moves at a time, and at every gripper action the
    other arm waits at its retract (home) pose; a swap has one arm hold its object at home."""
    r = rearrangement_problem(instance(), ctx, planner=planner, motion="sequential")
    solution = solve_rearrangement(r, task_planner, BUDGET)
    assert solution.status is Status.SOLVED and solution.plan is not None
    names = [a.name for a in solution.plan]
    assert "pick-both" not in names and "place-both" not in names
    plan = plan_file_from_solution(r, solution)
    assert validate_plan(r.instance, plan, ctx.scene).ok
    moving = np.abs(np.diff(plan.q, axis=0)) > 1e-9
    assert not np.any(moving[:, :6].any(axis=1) & moving[:, 6:].any(axis=1))
    assert plan.metrics.dual_arm_steps == 0
    home = [arm.home for arm in plan.arms]
    for event in plan.events:
        k = int(np.searchsorted(plan.t, event.t))
        other = 1 if event.arm == plan.arms[0].name else 0
        np.testing.assert_allclose(plan.q[k, 6 * other : 6 * other + 6], home[other], atol=1e-9)
    if task_planner == "sdar":  # the swap: a picks, b picks, b is placed, then a
        kinds = [(e.type, e.object) for e in plan.events]
        first = kinds[0][1]
        second = "b" if first == "a" else "a"
        assert kinds == [("grasp", first), ("grasp", second), ("release", second),
                         ("release", first)]  # fmt: skip


def test_colliding_first_grasps_widen_the_options(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """D5 is two 2-cycles and a free object. With the first two grasp options per arm, the
    arms collide at every swap and SDAR-M breaks the cycles with buffers; with the widened
    options both swaps are dual-arm steps."""
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.suites import shipped_suite_dir
    from solvers.sdar.planners import make_task_planner
    from solvers.sdar.solver import SdarOptions, SdarSolver

    instance = load_instance(shipped_suite_dir("paper") / "D5.yaml")
    kinds: dict[int, list[str]] = {}
    buffered: dict[int, int] = {}
    for more in (2, 6):
        r = rearrangement_problem(instance, ctx, planner=planner)
        options = SdarOptions(max_time=BUDGET, more_options=more, pair_grasps=0)
        solution = SdarSolver(r.problem, make_task_planner("sdar"), options).solve()
        assert solution.status is Status.SOLVED
        kinds[more] = [t.kind for t in solution.trace]
        buffered[more] = sum(sum(t.to_buffer) for t in solution.trace)
    assert "swap" not in kinds[2] and buffered[2] > 0  # the 2-cycles broken with buffers
    assert kinds[6].count("swap") == 2 and buffered[6] == 0


def test_motions_come_from_the_quick_stream_first(
    ctx: WorldContext, planner: MotionPlanner, solved_three: tuple[Rearrangement, Solution]
) -> None:
    """Where optimisation alone finds the motions, the full motion planner (with its
    fallbacks) is never called; without quick attempts only the full planner is."""
    from solvers.sdar.planners import make_task_planner
    from solvers.sdar.solver import SdarOptions, SdarSolver

    quick = SdarOptions.quick_attempts
    r = rearrangement_problem(_three(), ctx, planner=planner)
    options = SdarOptions(max_time=BUDGET, quick_attempts=0)
    runs = {
        quick: solved_three,
        0: (r, SdarSolver(r.problem, make_task_planner("sdar"), options).solve()),
    }
    calls: dict[int, dict[str, int]] = {}
    for attempts, (r, solution) in runs.items():
        assert solution.status is Status.SOLVED
        assert validate_plan(r.instance, plan_file_from_solution(r, solution), ctx.scene).ok
        calls[attempts] = {k: s.calls for k, s in solution.streams.items() if "motion" in k}
    motions = calls[0]["plan-dual-motion"]
    assert motions >= 3 and calls[0]["plan-dual-motion-quick"] == 0
    # with quick attempts the full planner is never needed here; a quick attempt that fails
    # moves on to the next grounding's quick attempt, so there may be more quick calls
    assert calls[quick]["plan-dual-motion"] == 0
    assert calls[quick]["plan-dual-motion-quick"] >= motions
