"""Scheduling a plan of a 6-joint and a 7-joint arm: each arm's blocks hold its own joints, its
motions are re-timed within its own limits (uniformly and time-optimally, with the tool slow at
a gripper event, from the 7-joint arm's forward kinematics), and the asynchronous placement
assembles a plan of both arms that keeps every limit."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pytest
from mixed_cell import PANDA_URDF, PANDA_VELOCITY

from sdar_tamp.app.execution import path_timer
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import LIMIT_RTOL, check_timeline
from sdar_tamp.schedule.pieces import Block, arm_blocks, arm_columns
from sdar_tamp.schedule.retiming import ArmRetimer, PathTimer
from sdar_tamp.schedule.scheduler import Placement, ScheduleOptions
from sdar_tamp.schedule.sweep import Conflict, TimedEvent
from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray, translation

TICK = 0.02


@dataclass(frozen=True)
class PinTool:
    """The 7-joint arm's flange poses in the world, by pinocchio's forward kinematics."""

    robot: PinRobot
    T_world_base: FloatArray
    tcp_offset: float

    def fk_batch(self, q: FloatArray) -> FloatArray:
        flange = self.robot.frame_id("tool0")
        poses = [self.robot.frame_pose(np.ascontiguousarray(row), flange) for row in q]
        return self.T_world_base @ np.stack(poses)

    @property
    def T_tool0_tcp(self) -> FloatArray:
        return translation(0.0, 0.0, self.tcp_offset)


def _retimer(cell: Scene, arm: int, timer: PathTimer | None) -> ArmRetimer:
    spec = cell.arms[arm]
    kin = (
        ArmKinematics.from_scene(cell, spec.name)
        if arm == 0
        else PinTool(PinRobot.load(PANDA_URDF), spec.T_world_base, cell.gripper.tcp_offset)
    )
    return ArmRetimer(
        kin, np.array(spec.velocity_limit), np.array(spec.acceleration_limit), TICK, timer
    )


def _within_limits(q: FloatArray, v_max: Sequence[float], a_max: Sequence[float]) -> bool:
    """The plan rules' measures on samples ``TICK`` apart, at rest before and after."""
    rest = np.zeros((1, q.shape[1]))
    v = np.concatenate([rest, np.diff(q, axis=0) / TICK, rest])
    a = np.diff(v, axis=0) / TICK
    tol = 1.0 + LIMIT_RTOL
    return bool(np.all(np.abs(v) <= np.array(v_max) * tol)) and bool(
        np.all(np.abs(a) <= np.array(a_max) * tol)
    )


def test_arm_columns_follow_the_plans_layout(plan: PlanFile) -> None:
    assert arm_columns(plan, 0) == slice(0, 6)
    assert arm_columns(plan, 1) == slice(6, 13)
    with pytest.raises(ParameterError, match=r"arm: expected an index in \[0, 2\), got 2"):
        arm_columns(plan, 2)


def test_blocks_hold_each_arms_joints(plan: PlanFile, cell: Scene) -> None:
    blocks = [arm_blocks(plan, cell, i, TICK, retimed=False) for i in range(2)]
    assert [b.q.shape[1] for b in blocks[0]] == [6] * len(blocks[0])
    assert [b.q.shape[1] for b in blocks[1]] == [7] * len(blocks[1])
    first_left, first_right = blocks[0][0], blocks[1][0]
    assert first_left.event is not None and first_left.event.object == "o1"
    assert first_right.event is not None and first_right.event.object == "o2"
    np.testing.assert_array_equal(first_right.q[-1], plan.q[-1, 6:])
    assert first_right.sync_end == pytest.approx(1.4)


def test_a_scene_arm_of_another_joint_count_is_refused(plan: PlanFile, cell: Scene) -> None:
    ur_like = dataclasses.replace(cell, arms=(cell.arms[0], cell.arms[0]))
    with pytest.raises(ParameterError, match="the plan holds 7 joints, the scene's arm 6"):
        arm_blocks(plan, ur_like, 1, TICK, retimed=False)


@pytest.mark.parametrize("timed", [False, True], ids=["uniform", "time-optimal"])
def test_the_7_joint_arm_is_retimed_within_its_own_limits(
    plan: PlanFile, cell: Scene, timed: bool
) -> None:
    timer = path_timer(cell.velocity_safety) if timed else None
    spec = cell.arms[1]
    blocks = arm_blocks(plan, cell, 1, TICK, True, _retimer(cell, 1, timer))
    moving = [b for b in blocks if len(b.q) > 1]
    assert moving and all(b.q.shape[1] == 7 for b in moving)
    assert len(moving[0].q) < len(moving[0].q_sync)  # alone, the arm goes faster
    for b in moving:
        assert _within_limits(b.q, spec.velocity_limit, spec.acceleration_limit)
        np.testing.assert_allclose(b.q[0], b.q_sync[0])
        np.testing.assert_allclose(b.q[-1], b.q_sync[-1])
    # the joints 1-4 (2.175 rad/s) are the slower ones: no joint beyond its own limit
    speeds = np.abs(np.diff(moving[0].q, axis=0)).max(axis=0) / TICK
    assert np.all(speeds <= np.array(PANDA_VELOCITY) * (1 + LIMIT_RTOL))


def test_the_tool_is_slow_near_the_7_joint_arms_grasp(cell: Scene, plan: PlanFile) -> None:
    retimer = _retimer(cell, 1, path_timer(cell.velocity_safety))
    path = plan.q[:71:5, 6:]
    caps = retimer.tool_caps(path, slow_start=False, slow_end=True)
    assert caps is not None and caps.shape == (len(path),)
    assert np.isfinite(caps[-1]) and np.isinf(caps[0])


class FreeSweep:
    """A world in which nothing collides (the placement's replay is not what is tested)."""

    checks = 0

    def reset(self, before: Sequence[TimedEvent]) -> None:
        pass

    def run(self, k0: int, q: FloatArray, events: Sequence[TimedEvent]) -> Conflict | None:
        assert q.shape[1] == 13
        return None


def test_the_asynchronous_placement_assembles_both_arms(plan: PlanFile, cell: Scene) -> None:
    options = ScheduleOptions()
    blocks: list[list[Block]] = [
        arm_blocks(plan, cell, i, TICK, True, _retimer(cell, i, None)) for i in range(2)
    ]
    result = Placement(plan, blocks, FreeSweep(), options, "objects").run()  # type: ignore[arg-type]
    assert result.q.shape == (len(result.t), 13)
    assert result.layout.dofs == (6, 7)
    assert check_timeline(result, cell) is None
    # each arm on its own: the 7-joint arm, faster alone, may grasp first
    assert sorted((e.arm, e.object) for e in result.events) == [("left", "o1"), ("right", "o2")]
    assert result.duration < plan.duration
    np.testing.assert_allclose(result.q[-1], plan.q[-1])
    for e in result.events:  # each event where its arm arrived
        k = round(e.t / TICK)
        cols = arm_columns(result, result.arm_names.index(e.arm))
        sync = plan.q[round(next(x.t for x in plan.events if x.object == e.object) / TICK)]
        np.testing.assert_allclose(result.q[k, cols], sync[cols], atol=1e-9)
