"""Dead-end recovery: recursive evictions of any resting object, graspability of the evicted
object, and evicted objects that wait for the object they made room for."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from sdar_tamp.app import Rearrangement, rearrangement_problem, solve_rearrangement
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from solvers.sdar.options import SdarOptions
from solvers.sdar.recovery import Boxed, Deferral, Recovery
from solvers.sdar.sdar_t import SdarTaskPlanner
from solvers.sdar.solver import SdarSolver
from solvers.solution import Status
from streams.context import WorldContext
from streams.motion.planner import MotionPlanner
from streams.stream_map import make_stream_map

BUDGET = 600.0  # [s] generous: the budget is not what these tests check
SIZE = (0.08, 0.04, 0.05)
WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))
A_START, A_GOAL = Pose2D(-0.15, 0.2, 0.0), Pose2D(-0.15, -0.2, 0.0)
B_AT = Pose2D(0.12, 0.2, 0.0)  # b and c start at their goals
C_AT = Pose2D(0.12, -0.2, 0.0)


def _nested() -> Instance:
    """a must move; b and c rest at their goals. a has no grasp where it rests while b is at
    its goal, and b none while c is at its goal (see :func:`_nested_problem`): c, then b must
    make room, and come back in the reverse order."""
    return Instance(
        "nested",
        WORKSPACE,
        (
            ObjectSpec("a", SIZE, A_START, A_GOAL),
            ObjectSpec("b", SIZE, B_AT, B_AT),
            ObjectSpec("c", SIZE, C_AT, C_AT),
        ),
    )


def _nested_problem(ctx: WorldContext, planner: MotionPlanner) -> Rearrangement:
    inst = _nested()
    real = make_stream_map(ctx, {o.name: o.size for o in inst.objects})["inverse-kinematics"]

    def boxed_ik(arm: str, o: str, p: Pose2D, g: Any, fluents: Any = ()) -> Iterator[Any]:
        resting = {(f[1], f[2]) for f in fluents if f[0] == "atpose"}
        if o == "a" and p == A_START and ("b", B_AT) in resting:
            return iter(())
        if o == "b" and p == B_AT and ("c", C_AT) in resting:
            return iter(())
        return real(arm, o, p, g, fluents)

    return rearrangement_problem(
        inst, ctx, planner=planner, overrides={"inverse-kinematics": boxed_ik}
    )


def _recovery(r: Rearrangement, max_depth: int) -> tuple[SdarSolver, Recovery]:
    solver = SdarSolver(r.problem, SdarTaskPlanner())
    names = {str(solver.cache.show(n)): n for n in solver.cache.current_poses()}
    assert set(names) == {"a", "b", "c"}
    recovery = Recovery(
        solver.cache, solver.options, solver.goals, tuple(solver.home), solver.deadline, max_depth
    )
    return solver, recovery


def test_a_blocker_that_cannot_be_grasped_is_unblocked_first(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    r = _nested_problem(ctx, planner)
    solver, recovery = _recovery(r, max_depth=3)
    show = solver.cache.show
    view = solver.view()
    current = solver.cache.current_poses()
    a = next(o for o in current if show(o) == "a")
    b = next(o for o in current if show(o) == "b")
    assert recovery.boxed(a, view, current) == Boxed(a, current[a])
    assert recovery.blockers(Boxed(a, current[a]), current, view.done) == frozenset({b})
    steps = recovery.candidates(view)
    # b (at its goal) cannot be grasped: only c, which boxes b in, is evicted, one level down
    assert [tuple((show(m.obj), m.to_buffer) for m in s.moves) for s in steps] == [(("c", True),)]
    assert steps[0].kind == "evict" and steps[0].rank == 4  # depth 1, a single eviction


def test_without_depth_an_ungraspable_blocker_is_not_evicted(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    r = _nested_problem(ctx, planner)
    solver, recovery = _recovery(r, max_depth=0)
    assert recovery.candidates(solver.view()) == []


def test_nested_box_in_is_solved_by_recursive_evictions(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    solution = solve_rearrangement(_nested_problem(ctx, planner), "sdar", BUDGET)
    assert solution.status is Status.SOLVED, solution.diagnosis
    moves = [(o, b) for t in solution.trace for o, b in zip(t.objects, t.to_buffer, strict=True)]
    # c makes room for b, b for a; then b returns before c (c at its goal would box b in)
    assert moves.index(("c", True)) < moves.index(("b", True)) < moves.index(("a", False))
    assert moves.index(("b", False)) < moves.index(("c", False))
    assert len(moves) == 5  # a once, b and c out and back
    assert [t.kind for t in solution.trace].count("evict") == 2


def test_a_deferral_ends_when_the_target_has_left_its_pose() -> None:
    waiting = Deferral("a", "pa")
    assert not waiting.update({"a": "pa"}, goal="ga")  # a still boxed in where it rests
    assert waiting.update({"a": "elsewhere"}, goal="ga")  # a has left: the blocker may return


def test_a_deferral_at_a_goal_ends_when_the_target_is_back_at_it() -> None:
    waiting = Deferral("b", "gb")  # b was boxed in at its goal, where it rested
    assert not waiting.update({"b": "gb"}, goal="gb")  # not yet evicted
    assert not waiting.update({"b": "buffer"}, goal="gb")  # evicted, not back
    assert waiting.left
    assert waiting.update({"b": "gb"}, goal="gb")  # back at its goal


def test_recovery_refuses_a_negative_depth(ctx: WorldContext, planner: MotionPlanner) -> None:
    r = _nested_problem(ctx, planner)
    solver = SdarSolver(r.problem, SdarTaskPlanner())
    with pytest.raises(ValueError, match="max_depth must be >= 0, got -1"):
        Recovery(solver.cache, solver.options, solver.goals, tuple(solver.home),
                 solver.deadline, -1)  # fmt: skip


def _few_grasps_problem(ctx: WorldContext, planner: MotionPlanner) -> Rearrangement:
    """a's only grasps with IK are moderate tilts (the pair tilts, after the first
    ``SdarOptions.grasps`` grasps of the grasp set): no step, eviction or buffer works with
    the first grasps."""
    inst = Instance("few", WORKSPACE, (ObjectSpec("a", SIZE, A_START, A_GOAL),))
    real = make_stream_map(ctx, {o.name: o.size for o in inst.objects})["inverse-kinematics"]
    first = SdarOptions().grasps

    def tilted_only(arm: str, o: str, p: Pose2D, g: Any, fluents: Any = ()) -> Iterator[Any]:
        if o == "a" and g.index < first:
            return iter(())
        return real(arm, o, p, g, fluents)

    return rearrangement_problem(
        inst, ctx, planner=planner, overrides={"inverse-kinematics": tilted_only}
    )


def test_a_dead_end_is_tried_again_with_more_grasps(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    r = _few_grasps_problem(ctx, planner)
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(max_time=BUDGET))
    wider = solver.recovery.wider(solver.view())  # a is boxed in with the first grasps
    assert wider is not None and wider.grasps == solver.options.pair_grasps
    solution = solver.solve()
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert solver.grounder.options is solver.options  # widened for that decision only
    # without more grasps to search, the same instance is a dead end
    narrow = SdarOptions(max_time=BUDGET, pair_grasps=SdarOptions().grasps)
    stuck = SdarSolver(_few_grasps_problem(ctx, planner).problem, SdarTaskPlanner(), narrow)
    assert stuck.recovery.wider() is None
    assert stuck.solve().status is Status.INFEASIBLE


def test_more_grasps_only_for_a_boxed_in_object(ctx: WorldContext, planner: MotionPlanner) -> None:
    inst = Instance("free", WORKSPACE, (ObjectSpec("a", SIZE, A_START, A_GOAL),))
    solver = SdarSolver(rearrangement_problem(inst, ctx, planner=planner).problem,
                        SdarTaskPlanner())  # fmt: skip
    assert solver.recovery.wider() is not None  # without a view: the options alone
    assert solver.recovery.wider(solver.view()) is None  # a has grasps: nothing boxed in


def _split_grasps_problem(ctx: WorldContext, planner: MotionPlanner) -> Rearrangement:
    """a has IK where it rests with the even ones of its first grasps and at its goal with the
    odd ones: reachable at both (not boxed in), but no first grasp carries it from one to the
    other; the grasps after the first have IK everywhere."""
    inst = Instance("split", WORKSPACE, (ObjectSpec("a", SIZE, A_START, A_GOAL),))
    real = make_stream_map(ctx, {o.name: o.size for o in inst.objects})["inverse-kinematics"]
    first = SdarOptions().grasps

    def split(arm: str, o: str, p: Pose2D, g: Any, fluents: Any = ()) -> Iterator[Any]:
        if o == "a" and g.index < first:
            here = p == A_START and g.index % 2 == 0
            there = p == A_GOAL and g.index % 2 == 1
            if not (here or there):
                return iter(())
        return real(arm, o, p, g, fluents)

    return rearrangement_problem(
        inst, ctx, planner=planner, overrides={"inverse-kinematics": split}
    )


def test_more_grasps_when_no_first_grasp_serves_both_ends(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    r = _split_grasps_problem(ctx, planner)
    solver = SdarSolver(r.problem, SdarTaskPlanner(), SdarOptions(max_time=BUDGET))
    view = solver.view()
    current = solver.cache.current_poses()
    (a,) = view.remaining
    assert solver.recovery.boxed(a, view, current) is None  # graspable at both ends
    assert not solver.recovery.carried(a, view, current)  # but not with one grasp
    wider = solver.recovery.wider(view)
    assert wider is not None and wider.grasps == solver.options.pair_grasps
    solution = solver.solve()
    assert solution.status is Status.SOLVED, solution.diagnosis


def _regrasp_problem(ctx: WorldContext, planner: MotionPlanner) -> Rearrangement:
    """a has IK where it rests only with the even ones of its first grasps and at its goal only
    with the odd ones, and no other grasp has IK at either: no grasp carries it, more grasps do
    not help, nothing boxes it in; elsewhere (a buffer) every grasp has IK."""
    inst = Instance("regrasp", WORKSPACE, (ObjectSpec("a", SIZE, A_START, A_GOAL),))
    real = make_stream_map(ctx, {o.name: o.size for o in inst.objects})["inverse-kinematics"]
    first = SdarOptions().grasps

    def split(arm: str, o: str, p: Pose2D, g: Any, fluents: Any = ()) -> Iterator[Any]:
        if o == "a" and p in (A_START, A_GOAL):
            here = p == A_START and g.index < first and g.index % 2 == 0
            there = p == A_GOAL and g.index < first and g.index % 2 == 1
            if not (here or there):
                return iter(())
        return real(arm, o, p, g, fluents)

    return rearrangement_problem(
        inst, ctx, planner=planner, overrides={"inverse-kinematics": split}
    )


def test_an_object_no_grasp_carries_is_regrasped_through_a_buffer(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    solver = SdarSolver(_regrasp_problem(ctx, planner).problem, SdarTaskPlanner(),
                        SdarOptions(max_time=BUDGET))  # fmt: skip
    view = solver.view()
    current = solver.cache.current_poses()
    (a,) = view.remaining
    assert solver.recovery.boxed(a, view, current) is None
    assert not solver.recovery.carried(a, view, current)
    (step,) = solver.recovery.candidates(view)
    assert step.kind == "regrasp" and step.moves[0].obj == a and step.moves[0].to_buffer
    # a buffer is kept only when some first grasp carries a from it to its goal
    assert solver.recovery.buffer_clear(step.moves, a, current[a]) is False  # where it rests
    solution = solver.solve()
    assert solution.status is Status.SOLVED, solution.diagnosis
    moves = [(o, b) for t in solution.trace for o, b in zip(t.objects, t.to_buffer, strict=True)]
    assert moves == [("a", True), ("a", False)]
    assert [t.kind for t in solution.trace] == ["regrasp", "last"]


def test_without_regrasps_the_same_object_is_a_dead_end(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """The recovery's budget spent, nothing regrasps a: the instance above is a dead end."""
    solver = SdarSolver(_regrasp_problem(ctx, planner).problem, SdarTaskPlanner(),
                        SdarOptions(max_time=BUDGET))  # fmt: skip
    solver.recovery.evictions = 2 * len(solver.goals)
    assert not solver.recovery.budget_left
    assert solver.solve().status is Status.INFEASIBLE
