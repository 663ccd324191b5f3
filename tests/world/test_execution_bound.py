"""The lower bound on execution time: the formula, a hand-computed case, k arms, and every
reference plan the tests hold above it."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app.bound import instance_bound
from sdar_tamp.errors import ParameterError
from sdar_tamp.world.cells import cell_path
from sdar_tamp.world.execution_bound import (
    ExecutionBound,
    ObjectBound,
    at_goal,
    execution_bound,
    joint_displacement,
    rest_to_rest_time,
)
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, load_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import shipped_suite_dir
from streams.grasps import sample_grasps

SOLVED = Path(__file__).resolve().parents[1] / "plan" / "solved"
SIZE = (0.08, 0.04, 0.05)


def test_rest_to_rest_time_is_the_triangle_or_the_trapezoid_of_the_slowest_joint() -> None:
    v, a = np.array([np.pi, 2.0]), np.array([5.0, 1.0])
    # joint 0: 0.5 rad <= pi^2 / 5, a triangle: 2 sqrt(0.5 / 5)
    assert rest_to_rest_time(np.array([0.5, 0.0]), v, a) == pytest.approx(2 * math.sqrt(0.1))
    # joint 1: 6 rad > 2^2 / 1, a trapezoid: 6 / 2 + 2 / 1 = 5 s
    assert rest_to_rest_time(np.array([0.5, -6.0]), v, a) == pytest.approx(5.0)
    # the two profiles meet where the top speed is just reached
    edge = np.array([np.pi**2 / 5.0, 0.0])
    assert 2 * math.sqrt(edge[0] / 5.0) == pytest.approx(edge[0] / np.pi + np.pi / 5.0)
    assert rest_to_rest_time(edge, v, a) == pytest.approx(2 * np.pi / 5.0)
    assert rest_to_rest_time(np.zeros((3, 2)), v, a).shape == (3,)
    with pytest.raises(ParameterError, match="must be > 0"):
        rest_to_rest_time(np.zeros(2), np.array([1.0, 0.0]), a)


def test_joint_displacement_takes_other_turns_within_the_limits() -> None:
    wide = (np.array([-2 * np.pi]), np.array([2 * np.pi]))
    narrow = (np.array([-np.pi]), np.array([np.pi]))
    # 3 rad to -3 rad: 2 pi - 6 the short way when -3 + 2 pi is within the limits
    assert joint_displacement(np.array([3.0]), np.array([-3.0]), *wide)[0] == pytest.approx(
        2 * np.pi - 6.0
    )
    assert joint_displacement(np.array([3.0]), np.array([-3.0]), *narrow)[0] == pytest.approx(6.0)


def test_a_hand_computed_case_equals_the_formula() -> None:
    """One object turned by 0.5 rad about the one arm's base: every IK branch of the goal is
    the start's with the pan joint 0.5 rad on, so the shortest motion is the pan's triangle,
    2 sqrt(0.5 / 5) s, and the bound is two dwells more."""
    scene = load_scene(cell_path("ur5e_table_1arm"))
    base = np.array(scene.arm("south").base_xyz[:2])
    theta = 0.5
    start = np.array([0.0, 0.0])
    c, s = math.cos(theta), math.sin(theta)
    goal = base + np.array([[c, -s], [s, c]]) @ (start - base)
    obj = ObjectSpec("o0", SIZE, Pose2D(0.0, 0.0, 0.3), Pose2D(*map(float, goal), 0.3 + theta))
    inst = Instance("hand", scene.workspace, (obj,))
    top_down = sample_grasps(SIZE, scene.grasp_limits, (), symmetric=False)
    assert len(top_down) == 1
    bound = execution_bound(scene, inst, {"o0": [top_down[0].T_object_tcp]}, dwell=0.5)
    motion = 2.0 * math.sqrt(theta / 5.0)  # v = pi rad/s is not reached; a = 5 rad/s^2
    assert bound.objects[0].motion == pytest.approx(motion, abs=1e-9)
    assert bound.objects[0].arm == "south" and not bound.objects[0].relay
    assert bound.seconds == pytest.approx(2 * 0.5 + motion, abs=1e-9)
    assert bound.arms == 1 and bound.proven
    # the planner's whole grasp set can only lower it, never raise it
    assert instance_bound(scene, inst).seconds <= bound.seconds + 1e-12
    # the scene's velocity_safety scales both limits, as the planner's timing does
    slow = dataclasses.replace(scene, velocity_safety=0.5)
    half = execution_bound(slow, inst, {"o0": [top_down[0].T_object_tcp]}, dwell=0.5)
    assert half.objects[0].motion == pytest.approx(2.0 * math.sqrt(theta / 2.5), abs=1e-9)


def test_the_bound_scales_with_the_arms() -> None:
    costs = tuple(ObjectBound(f"o{i}", 1.5, 0.5, "a", False) for i in range(4))
    for k, expected in ((1, 6.0), (2, 3.0), (3, 2.0), (4, 1.5), (8, 1.5)):
        b = ExecutionBound(k, 0.5, costs)
        assert b.seconds == pytest.approx(expected)
    assert ExecutionBound(2, 0.5, costs).ratio(9.0) == pytest.approx(3.0)
    assert (
        ExecutionBound(2, 0.5, ()).seconds == 0.0 and ExecutionBound(2, 0.5, ()).ratio(1.0) is None
    )
    with pytest.raises(ParameterError, match="at least one arm"):
        ExecutionBound(0, 0.5, costs)


def test_more_arms_of_the_table_lower_the_bound() -> None:
    """The table's cells nest (each adds an arm), so every c_i can only shrink with k, and the
    sum is shared by k arms."""
    inst = load_instance(shipped_suite_dir("table_1arm") / "R12-1.yaml")
    bounds = [
        instance_bound(load_scene(cell_path(f"ur5e_table_{k}arm")), inst) for k in (1, 2, 3, 4)
    ]
    one = bounds[0]
    assert one.seconds == pytest.approx(one.total)  # one arm: the sum of the c_i
    for k, b in enumerate(bounds, start=1):
        assert b.arms == k and len(b.objects) == 12
        assert b.seconds == pytest.approx(max(b.total / k, b.longest))
        assert b.total <= one.total + 1e-9
        for mine, alone in zip(b.objects, one.objects, strict=True):
            assert mine.cost <= alone.cost + 1e-9
    assert [b.seconds for b in bounds] == sorted((b.seconds for b in bounds), reverse=True)


@pytest.mark.parametrize("plan", sorted(p.name for p in SOLVED.glob("*.plan.json")))
def test_the_bound_is_below_every_reference_plan(plan: str) -> None:
    data = json.loads((SOLVED / plan).read_text(encoding="utf-8"))
    name = data["instance"]
    inst = load_instance(shipped_suite_dir("paper") / f"{name}.yaml")
    bound = instance_bound(load_scene(), inst)
    execution = float(data["metrics"]["execution_time"])
    assert 0.0 < bound.seconds < execution
    assert len(bound.objects) == len(inst.objects) and bound.proven


def test_objects_at_their_goal_cost_nothing_and_unreachable_ones_a_relay() -> None:
    scene = load_scene(cell_path("ur5e_table_1arm"))
    still = ObjectSpec("o0", SIZE, Pose2D(0.1, 0.0, 0.2), Pose2D(0.1, 0.0005, 0.2 + np.pi))
    moved = ObjectSpec("o1", SIZE, Pose2D(-0.1, 0.0, 0.0), Pose2D(0.2, 0.1, 0.0))
    assert at_goal(still) and not at_goal(moved)
    inst = Instance("two", scene.workspace, (still, moved))
    bound = execution_bound(scene, inst, {"o0": [], "o1": []}, dwell=0.5)
    (only,) = bound.objects
    assert only.name == "o1" and only.relay and only.arm is None and math.isinf(only.motion)
    assert bound.seconds == pytest.approx(4 * 0.5)


def test_bad_input_is_refused() -> None:
    scene = load_scene(cell_path("ur5e_table_1arm"))
    obj = ObjectSpec("o1", SIZE, Pose2D(-0.1, 0.0, 0.0), Pose2D(0.2, 0.1, 0.0))
    inst = Instance("one", scene.workspace, (obj,))
    with pytest.raises(ParameterError, match=r"dwell: expected >= 0 \[s\], got -1"):
        execution_bound(scene, inst, {"o1": []}, dwell=-1.0)
    with pytest.raises(ParameterError, match=r"grasps: no grasp set for the objects \['o1'\]"):
        execution_bound(scene, inst, {}, dwell=0.5)


def test_the_pipeline_bounds_only_cells_with_the_closed_form_ik() -> None:
    from sdar_tamp.app.bound import run_bound
    from sdar_tamp.app.config import PlannerConfig
    from streams.context import WorldContext

    inst = load_instance(shipped_suite_dir("paper") / "R4.yaml")
    ur = WorldContext.load()
    bound = run_bound(ur, inst, PlannerConfig())
    assert bound is not None and bound.proven
    assert bound.seconds == pytest.approx(instance_bound(ur.scene, inst).seconds)
    panda = WorldContext.load(cell_path("panda_facing"))
    assert run_bound(panda, inst, PlannerConfig()) is None
