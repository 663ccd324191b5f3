"""Grasp-aware dependencies: edges of SDAR's dependency graph from the grasp-blocking test
stream on hand-built scenes, and how SDAR-T orders moves with them."""

from __future__ import annotations

from sdar_tamp.app import rearrangement_problem
from sdar_tamp.graph import DependencyGraph
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from solvers.sdar.planners import make_task_planner
from solvers.sdar.sdar_t import WAIT, SdarTaskPlanner
from solvers.sdar.solver import SdarOptions, SdarSolver
from solvers.sdar.tasks import Move, TaskView
from streams.context import WorldContext
from streams.motion.planner import MotionPlanner

BAR = (0.08, 0.04, 0.05)  # graspable across its 4 cm side only (y)
CUBE = (0.04, 0.04, 0.05)  # graspable across both sides
WORKSPACE = Workspace((-0.25, 0.25), (-0.30, 0.30))


def _view(ctx: WorldContext, planner: MotionPlanner, *objects: ObjectSpec) -> TaskView:
    """The solver's first view, objects by their instance names."""
    r = rearrangement_problem(Instance("hand", WORKSPACE, objects), ctx, planner=planner)
    solver = SdarSolver(r.problem, make_task_planner("sdar"), SdarOptions(max_time=10.0))
    view, show = solver.view(), solver.cache.show
    return TaskView(
        DependencyGraph(tuple(map(show, view.graph.names)), view.graph.edges),
        frozenset(map(show, view.done)),
        frozenset(map(show, view.in_buffer)),
        frozenset((show(i), show(j)) for i, j in view.waits),
    )


def _edges(view: TaskView) -> set[tuple[str, str]]:
    names = view.graph.names
    return {(names[i], names[j]) for i, j in view.graph.edges}


def test_a_goal_beside_a_start_on_its_closing_axis_is_an_edge(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """a's goal lies 5 mm beside b's start across b's graspable side: no footprint overlap,
    but once a is there b cannot be picked, so a waits for b (edge a -> b)."""
    b_start = Pose2D(0.1, 0.0, 0.0)
    a = ObjectSpec("a", BAR, Pose2D(-0.15, 0.2, 0.0), Pose2D(0.1, 0.045, 0.0))
    b = ObjectSpec("b", BAR, b_start, Pose2D(-0.15, -0.2, 0.0))
    assert _edges(_view(ctx, planner, a, b)) == {("a", "b")}


def test_far_apart_or_beside_the_long_side_there_is_no_edge(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    b = ObjectSpec("b", BAR, Pose2D(0.1, 0.0, 0.0), Pose2D(-0.15, -0.2, 0.0))
    far = ObjectSpec("a", BAR, Pose2D(-0.15, 0.2, 0.0), Pose2D(0.1, 0.15, 0.0))
    assert _edges(_view(ctx, planner, far, b)) == set()
    end_to_end = ObjectSpec("a", BAR, Pose2D(-0.15, 0.2, 0.0), Pose2D(0.19, 0.0, 0.0))
    assert _edges(_view(ctx, planner, end_to_end, b)) == set()


def test_a_resting_object_that_leaves_a_goal_no_grasp_is_an_edge(
    ctx: WorldContext, planner: MotionPlanner
) -> None:
    """b rests 5 mm beside a's goal across a's graspable side: a cannot be placed there
    while b stays (edge a -> b)."""
    a = ObjectSpec("a", BAR, Pose2D(-0.15, 0.2, 0.0), Pose2D(0.1, -0.045, 0.0))
    b = ObjectSpec("b", BAR, Pose2D(0.1, 0.0, 0.0), Pose2D(-0.15, -0.2, 0.0))
    assert _edges(_view(ctx, planner, a, b)) == {("a", "b")}


def test_a_goal_that_blocks_another_goal_waits(ctx: WorldContext, planner: MotionPlanner) -> None:
    """The cube's goal lies across the bar's goal: once the cube is there the bar cannot be
    placed, so the cube goes to its goal after the bar (the bar beside the cube leaves the
    cube its grasps across the other side)."""
    cube = ObjectSpec("c", CUBE, Pose2D(-0.15, 0.2, 0.0), Pose2D(0.1, 0.045, 0.0))
    bar = ObjectSpec("b", BAR, Pose2D(-0.15, -0.2, 0.0), Pose2D(0.1, 0.0, 0.0))
    view = _view(ctx, planner, cube, bar)
    assert _edges(view) == set()
    assert view.waits == frozenset({("c", "b")})
    assert view.must_wait("c") and not view.must_wait("b")
    steps = SdarTaskPlanner().candidates(view)
    first_with_cube = next(s for s in steps if Move("c") in s.moves)
    assert Move("c") not in steps[0].moves and Move("b") in steps[0].moves
    assert first_with_cube.rank == WAIT


def test_waiting_steps_come_last_in_sdar_t() -> None:
    graph = DependencyGraph(("x", "y"), ())
    view = TaskView(graph, frozenset(), frozenset(), frozenset({("x", "y")}))
    steps = SdarTaskPlanner().candidates(view)
    placing_x = [s for s in steps if Move("x") in s.moves]
    assert placing_x and all(s.rank == WAIT for s in placing_x)
    assert all(s.rank < WAIT for s in steps[: len(steps) - len(placing_x)])
    assert steps[0].moves == (Move("y"),)
    # once y is at its goal, x no longer waits
    done = TaskView(DependencyGraph(("x",), ()), frozenset({"y"}), frozenset(), view.waits)
    assert not done.must_wait("x")
