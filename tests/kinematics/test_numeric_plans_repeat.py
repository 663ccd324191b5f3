"""Same instance, same seed, same plan on an arm of the numeric IK (the Panda cell), whatever
the world context solved before: the solved-pair table of the IK only memoises."""

from __future__ import annotations

import numpy as np

from sdar_tamp.app import rearrangement_problem, solve_rearrangement
from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Scene, Workspace, load_scene
from solvers.solution import Solution, Status
from streams.context import WorldContext
from streams.motion.planner import MotionPlanner

SIZE = (0.08, 0.04, 0.05)
START = Pose2D(-0.1, 0.15, 0.0)


def _panda() -> Scene:
    return load_scene(cell_path("panda_facing"))


def _one(goal: Pose2D) -> Instance:
    workspace = Workspace((-0.18, 0.18), (-0.40, 0.40))
    return Instance("one", workspace, (ObjectSpec("a", SIZE, START, goal),))


def _solve(ctx: WorldContext, instance: Instance) -> Solution:
    r = rearrangement_problem(instance, ctx, planner=MotionPlanner(ctx))
    solution = solve_rearrangement(r, "sdar", 600.0)
    assert solution.status is Status.SOLVED and solution.plan is not None
    return solution


def _paths(solution: Solution) -> list[np.ndarray]:
    assert solution.plan is not None
    return [np.asarray(a.args[1].trajectory.q) for a in solution.plan if a.name == "move"]


def test_a_numeric_arm_plans_the_same_after_other_instances() -> None:
    scene = _panda()
    target = _one(Pose2D(0.05, 0.25, 1.0))
    fresh = _solve(WorldContext.load(scene), target)
    used = WorldContext.load(scene)
    assert not used.kinematics["left"].closed_form
    _solve(used, _one(Pose2D(0.1, -0.2, 0.5)))  # the grasps of the start met in its batches
    again = _solve(used, target)
    assert fresh.cost == again.cost
    for p, q in zip(_paths(fresh), _paths(again), strict=True):
        np.testing.assert_array_equal(p, q)
