"""The asynchronous scheduler on plans of three and four arms: every arm's pieces, groups of
blocks of several arms tried with each arm leading in turn, and schedules that replay."""

from __future__ import annotations

import pytest

from sdar_tamp.app.execution import execution_options, schedule_plan
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.replay import validate_plan
from sdar_tamp.schedule import ScheduleOptions, schedule_async
from sdar_tamp.schedule.pieces import arm_blocks
from sdar_tamp.schedule.scheduler import Placement, groups
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.schedule.timelines import schedule_timelines
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene


def _placement(plan: PlanFile, scene: Scene, instance: Instance) -> Placement:
    options = ScheduleOptions()
    blocks = [arm_blocks(plan, scene, i, options.tick) for i in range(len(scene.arms))]
    sweep = WorldSweep(instance, scene, options.max_tcp_step)
    return Placement(plan, blocks, sweep, options, "objects")


def test_every_arm_has_its_blocks_and_groups_hold_every_arm(
    plans: dict[int, PlanFile], cells: dict[int, Scene], instances: dict[int, Instance]
) -> None:
    placement = _placement(plans[4], cells[4], instances[4])
    assert len(placement.blocks) == 4
    for i, blocks in enumerate(placement.blocks):
        assert [b.arm for b in blocks] == [i] * len(blocks)
        assert sum(b.event is not None for b in blocks) == 2  # its grasp and its release
    first = groups(placement.blocks)[0]
    assert sorted({b.arm for b in first}) == [0, 1, 2, 3]  # the arms moved together


def test_a_group_of_k_arms_is_tried_with_each_arm_leading(
    plans: dict[int, PlanFile], cells: dict[int, Scene], instances: dict[int, Instance]
) -> None:
    placement = _placement(plans[3], cells[3], instances[3])
    group = groups(placement.blocks)[0]
    orders = placement.reorderings(group)
    leading = [[b.arm for b in order] for order in orders]
    arms = list(dict.fromkeys(b.arm for b in group))
    assert len(orders) == 3
    assert [order[0] for order in leading] == [arms[0], arms[1], arms[2]]
    for order in orders:  # the same blocks, each arm's in order
        assert sorted(map(id, order)) == sorted(map(id, group))
        for arm in arms:
            assert [b for b in order if b.arm == arm] == [b for b in group if b.arm == arm]
    # a group of one arm's blocks: tried as it is, twice (as the two-arm scheduler does)
    alone = placement.blocks[0][:2]
    assert len(alone) == 2
    assert placement.reorderings(alone) == [alone, alone]
    assert placement.reorderings(group[:1]) == [group[:1]]


@pytest.mark.parametrize("k", (1, 3))
def test_k_arm_schedules_replay(
    k: int, plans: dict[int, PlanFile], cells: dict[int, Scene], instances: dict[int, Instance]
) -> None:
    result = schedule_async(plans[k], instances[k], cells[k])
    assert result.plan.duration <= plans[k].duration
    assert result.plan.arm_names == plans[k].arm_names
    report = validate_plan(instances[k], result.plan, cells[k])
    assert report.ok, report.violation


@pytest.mark.parametrize("k", (1, 3, 4))
def test_k_arm_timelines_replay(
    k: int, plans: dict[int, PlanFile], cells: dict[int, Scene], instances: dict[int, Instance]
) -> None:
    """One timeline per arm for one, three and four arms: never longer than the synchronous
    plan, every arm's motions committed, and the result replays."""
    plan, scene = plans[k], cells[k]
    result = schedule_timelines(plan, instances[k], scene, execution_options(scene))
    assert result.plan.duration <= plan.duration
    assert result.plan.arm_names == plan.arm_names
    figures = dict(result.figures)
    blocks = sum(len(arm_blocks(plan, scene, i, 0.02)) for i in range(k))
    assert figures["motions"] + figures["together"] <= blocks
    assert result.asynchronous, result.reason
    # the arms carry their objects at once: alone, each goes at its own limits, straighter
    retimed = schedule_async(plan, instances[k], scene, execution_options(scene))
    assert result.plan.duration < retimed.plan.duration
    report = validate_plan(instances[k], result.plan, scene)
    assert report.ok, report.violation
    kept = schedule_plan(plan, instances[k], scene, scheduler="timelines")
    assert kept.plan.duration <= min(result.plan.duration, plan.duration) + 1e-9
    assert validate_plan(instances[k], kept.plan, scene).ok
