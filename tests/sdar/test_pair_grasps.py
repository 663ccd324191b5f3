"""Swaps of close neighbours: SDAR-M searches the grasp set for a compatible pair of grasps
(tilted ones included) before a buffer, and drops pairs whose grippers would meet the other
object at its target."""

from __future__ import annotations

import itertools
import math

from sdar_tamp.app import (
    PlannerConfig,
    plan_file_from_solution,
    rearrangement_problem,
    solve_rearrangement,
)
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from solvers.sdar.attempts import MotionMode
from solvers.sdar.grounding import grounding_stages
from solvers.sdar.planners import make_task_planner
from solvers.sdar.solver import SdarOptions, SdarSolver
from solvers.sdar.tasks import Move, Step
from solvers.solution import Status
from streams.context import WorldContext
from streams.grasps import GraspOptions
from streams.motion.planner import MotionPlanner

#: A solve's time budget: generous, so that a busy machine slows a test down but never turns
#: a solvable case into a timeout (the budget is not what these tests check).
BUDGET = 600.0

WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))
CUBE = (0.04, 0.04, 0.05)
BAR = (0.08, 0.04, 0.05)


def _swap(size: tuple[float, float, float], gap: float, yaw: float, turn: float) -> Instance:
    """Two objects side by side along y (``gap`` [m] between them) trading places, their
    goals turned by ``turn`` [rad]."""
    d = (size[0] if abs(math.sin(yaw)) > 0.5 else size[1]) + gap
    a, b = Pose2D(0.0, 0.05 + d / 2, yaw), Pose2D(0.0, 0.05 - d / 2, yaw)
    return Instance(
        "close-swap",
        WORKSPACE,
        (
            ObjectSpec("a", size, a, Pose2D(b.x, b.y, yaw + turn)),
            ObjectSpec("b", size, b, Pose2D(a.x, a.y, yaw - turn)),
        ),
    )


def _solver(
    inst: Instance,
    ctx: WorldContext,
    planner: MotionPlanner,
    grasps: GraspOptions | None = None,
    **kw: int,
) -> SdarSolver:
    config = PlannerConfig(grasps=grasps or GraspOptions())
    r = rearrangement_problem(inst, ctx, planner=planner, config=config)
    return SdarSolver(r.problem, make_task_planner("sdar"), SdarOptions(max_time=BUDGET, **kw))


DENSE_CUBE = (0.045, 0.045, 0.05)
CLEARANCE = 0.026  # [m] the paper suite's clearance between objects


def _row(axis: int) -> Instance:
    """Four cubes in a row along ``axis`` (0: x, 1: y), 2.6 cm apart: the middle two trade
    places (goals turned half a turn), the outer two stay."""
    d = DENSE_CUBE[0] + CLEARANCE

    def at(k: float, yaw: float = 0.0) -> Pose2D:
        return Pose2D(0.0, k * d, yaw) if axis == 1 else Pose2D(k * d, 0.0, yaw)

    return Instance(
        "row",
        WORKSPACE,
        (
            ObjectSpec("a", DENSE_CUBE, at(0.5), at(-0.5, math.pi)),
            ObjectSpec("b", DENSE_CUBE, at(-0.5), at(0.5, math.pi)),
            ObjectSpec("n1", DENSE_CUBE, at(1.5), at(1.5)),
            ObjectSpec("n2", DENSE_CUBE, at(-1.5), at(-1.5)),
        ),
    )


def test_the_pair_search_reaches_grasps_beyond_the_first_ones(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """Two cubes 6 cm apart trading places, turned: no pair among the first six grasps of each
    works (the arms collide); the grasp set holds pairs that do, all tilted."""
    inst = _swap(CUBE, 0.06, 0.0, 0.3)
    found = {}
    for pair_grasps in (0, 12):
        solver = _solver(inst, ctx, planner, pair_grasps=pair_grasps)
        (swap,) = [s for s in solver.planner.candidates(solver.view()) if s.kind == "swap"]
        found[pair_grasps] = solver.grounder.select([swap], MotionMode.FULL)
    grasps = [[solver.cache.table.value(o.grasp) for o in g.options] for g in found[12]]
    assert found[0] == []
    assert found[12] and all(any(g.index >= 6 for g in pair) for pair in grasps)
    assert all(not g.is_top_down for pair in grasps for g in pair)


def test_pairs_whose_gripper_meets_the_other_object_are_dropped(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    inst = _swap(CUBE, 0.06, 0.0, 0.3)
    solver = _solver(inst, ctx, planner)
    (swap,) = [s for s in solver.planner.candidates(solver.view()) if s.kind == "swap"]
    cache, voc = solver.cache, solver.voc
    groundings = solver.grounder.select([swap], MotionMode.FULL)
    a, b = swap.objects
    for g in groundings:
        oa, ob = g.options
        assert cache.test(voc.grasp_cfree, (a, oa.target, oa.grasp, b, ob.target))
        assert cache.test(voc.grasp_cfree, (b, ob.target, ob.grasp, a, oa.target))
    # and the test does reject gripper positions: a top-down grasp across y of a at its goal
    # meets b at its goal 2 mm away
    near = _swap(CUBE, 0.002, 0.0, 0.0)
    solver = _solver(near, ctx, planner)
    cache = solver.cache
    a, b = sorted(solver.goals)
    (g0,) = [
        gr
        for (gr,) in cache.outputs(voc.grasp, (a,), 12)
        if cache.table.value(gr).closing_axis == 1 and cache.table.value(gr).is_top_down
    ][:1]
    assert not cache.test(voc.grasp_cfree, (a, solver.goals[a], g0, b, solver.goals[b]))


def test_close_neighbours_trade_places_in_one_dual_arm_swap(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """Two bars end to end, 2.6 cm apart (the paper suite's clearance), goals turned: one
    synchronous swap, no buffer, and the plan validates."""
    inst = _swap(BAR, 0.026, math.pi / 2, 0.3)
    r = rearrangement_problem(inst, ctx, planner=planner)
    solution = solve_rearrangement(r, "sdar", BUDGET)
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert [t.kind for t in solution.trace] == ["swap"]
    assert not any(any(t.to_buffer) for t in solution.trace)
    plan = plan_file_from_solution(r, solution)
    assert plan.metrics.actions == 2
    report = validate_plan(r.instance, plan, ctx.scene)
    assert report.ok, report.violation


def test_boxed_in_neighbours_need_the_moderate_pair_tilts(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """The middle two of a row of cubes (along y) trade places: top-down, the two wrists
    collide; at 45 degrees a gripper reaches over an outer cube (so the first six grasps give
    fewer than six options, and the pair search must still run). Only the pair tilts of 20
    and 30 degrees make a compatible pair."""
    inst = _row(axis=1)
    groundings = {}
    for options in (GraspOptions(pair_tilts=()), GraspOptions()):
        solver = _solver(inst, ctx, planner, grasps=options)
        (swap,) = [s for s in solver.planner.candidates(solver.view()) if s.kind == "swap"]
        groundings[options.pair_tilts] = solver.grounder.select([swap], MotionMode.FULL)
        value = solver.cache.table.value
        if not options.pair_tilts:
            assert solver.failures.reasons
            assert all("the arms collide at the objects" in r for r in solver.failures.reasons)
    assert groundings[()] == []
    found = groundings[GraspOptions().pair_tilts]
    assert found
    moderate = {20, 30}
    for g in found:
        tilts = {round(abs(math.degrees(value(o.grasp).tilt))) for o in g.options}
        assert tilts & moderate
        # every grounding's grasps belong to pairs that work with no other object around
        free = solver.grounder.free_pairs(swap, g.arms, solver.options.pair_grasps)
        assert free is not None
        assert all(o.grasp in grasps for o, grasps in zip(g.options, free, strict=True))


def test_a_swap_no_grasp_pair_allows_is_dropped_before_any_ik_among_the_others(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """Two bars side by side, 2.6 cm apart, held across their 4 cm side: both grippers'
    fingers would close in the same gap. No pair works even on an empty table, and the
    pair search says so instead of asking IK in the arrangement."""
    d = 0.04 + CLEARANCE
    a, b = Pose2D(0.0, d / 2, 0.0), Pose2D(0.0, -d / 2, 0.0)
    size = (0.06, 0.04, 0.05)
    inst = Instance(
        "bars",
        WORKSPACE,
        (
            ObjectSpec("a", size, a, Pose2D(b.x, b.y, math.pi)),
            ObjectSpec("b", size, b, Pose2D(a.x, a.y, math.pi)),
        ),
    )
    solver = _solver(inst, ctx, planner)
    (swap,) = [s for s in solver.planner.candidates(solver.view()) if s.kind == "swap"]
    assert solver.grounder.select([swap], MotionMode.FULL) == []
    reasons = solver.failures.reasons
    assert len(reasons) == 2  # both arm assignments
    assert all("no pair of grasps keeps the arms apart" in r for r in reasons)
    for arms in itertools.permutations(sorted(solver.home)):
        free = solver.grounder.free_pairs(swap, arms, solver.options.pair_grasps)
        assert free == (frozenset(), frozenset())


def test_neighbours_in_a_row_trade_places_in_one_swap(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    inst = _row(axis=1)
    r = rearrangement_problem(inst, ctx, planner=planner)
    solution = solve_rearrangement(r, "sdar", BUDGET)
    assert solution.status is Status.SOLVED, solution.diagnosis
    assert [t.kind for t in solution.trace] == ["swap"]
    plan = plan_file_from_solution(r, solution)
    assert plan.metrics.actions == 2
    report = validate_plan(r.instance, plan, ctx.scene)
    assert report.ok, report.violation


def test_a_step_checked_in_pairs_gets_as_many_options_per_move_as_a_two_move_step() -> None:
    """Four moves: two options per move when every combination is checked (36 at most), six
    (a two-move step's expanded stage) when the options are checked in pairs of arms."""
    opt = SdarOptions()
    four = Step(tuple(Move(o) for o in "abcd"), "chain")
    assert grounding_stages(four, opt, pairwise=False) == [(2, opt.grasps)]
    assert grounding_stages(four, opt, pairwise=True) == [(2, opt.grasps), (6, opt.grasps)]
    two = Step((Move("a"), Move("b")), "chain")
    assert grounding_stages(two, opt, pairwise=True) == grounding_stages(two, opt, False)
    assert grounding_stages(Step((Move("a"),), "single"), opt, pairwise=False) == [(2, opt.grasps)]
