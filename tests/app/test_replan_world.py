"""The instance a re-planned continuation solves (``sdar_tamp.app.replan_world``): objects at
their goals stay, the others keep their goals, added objects stay unless they block one."""

from __future__ import annotations

import math

import pytest

from sdar_tamp.app.replan_world import AT_GOAL, at_goal, continuation_instance
from sdar_tamp.resources import domains_root
from sdar_tamp.world.instance import Instance, load_instance


@pytest.fixture(scope="module")
def d5() -> Instance:
    return load_instance(domains_root() / "dual_arm_rearrangement/suites/paper/D5.yaml")


@pytest.mark.parametrize(
    ("offset", "expected"),
    [
        ((1e-15, -1e-15, 2e-16), True),  # rounding
        ((0.0, 0.0, math.pi), True),  # half a turn: the same cuboid
        ((0.0, 0.0, -math.pi + 1e-9), True),
        ((AT_GOAL[0] * 0.9, 0.0, 0.0), True),
        ((AT_GOAL[0] * 1.1, 0.0, 0.0), False),
        ((0.0, 0.0, AT_GOAL[1] * 1.1), False),
        ((0.0, 0.0, math.pi / 2), False),
    ],
)
def test_at_goal(d5: Instance, offset: tuple[float, float, float], expected: bool) -> None:
    goal = d5.objects[0].goal
    pose = (goal.x + offset[0], goal.y + offset[1], goal.yaw + offset[2])
    assert at_goal(pose, goal) is expected


def test_objects_at_their_goals_are_not_moved_again(d5: Instance) -> None:
    """At goal to rounding or half a turn: the goal becomes the pose (no task); off it by
    2 mm: the instance's goal stays; a removed object is gone."""
    o0, o1, o2, o3 = (next(o for o in d5.objects if o.name == n) for n in ("o0", "o1", "o2", "o3"))
    resting = {
        "o0": (o0.goal.x + 1e-16, o0.goal.y, o0.goal.yaw + math.pi),
        "o1": (o1.goal.x + 0.002, o1.goal.y, o1.goal.yaw),
        "o2": o2.start.as_tuple(),
        "o3": (o3.goal.x, o3.goal.y - 1e-15, o3.goal.yaw),
    }
    sizes = {o.name: o.size for o in d5.objects}
    inst, moved = continuation_instance(d5, resting, sizes)
    assert moved == ()
    objs = {o.name: o for o in inst.objects}
    assert sorted(objs) == ["o0", "o1", "o2", "o3"]  # o4 is gone
    assert objs["o0"].goal.as_tuple() == resting["o0"] == objs["o0"].start.as_tuple()
    assert objs["o3"].goal.as_tuple() == resting["o3"]
    assert objs["o1"].goal == o1.goal and objs["o2"].goal == o2.goal
