"""Re-planning where the running plan meets the observed world before its next cut (D5 of
the paper suite, ``conftest.py``): the arms brake on their way, what they hold is put down
(where the plan would release it, back where it was grasped, or straight below), and where
they cannot stop short of the change the answer is ``infeasible`` naming the objects."""

from __future__ import annotations

import numpy as np
import pytest

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_state import state_at
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import load_scene
from tests.app.conftest import AT, grasp_poses, obj, replan_d5


def _o1_nudged(instance: Instance) -> str:
    o1 = obj(instance, "o1")  # the right arm is on its way to grasp it at 5.71 s
    return (f"poses: [{{name: o1, pose: [{o1.start.x + 0.015}, {o1.start.y - 0.01}, "
            f"{o1.start.yaw + 0.15}]}}]")  # fmt: skip


def test_the_arms_brake_short_of_a_change_on_their_way(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """The right arm would touch the nudged o1 at 5.414 s, before the plan's next cut (its
    grasp at 5.71 s): the arms brake on their way from 4.5 s, on the old plan's path, and a
    fresh continuation re-grasps o1 at its new pose."""
    out = replan_d5(d5, cache, _o1_nudged(d5[0]))
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    assert AT < out.cut < 5.414
    old = d5[1]
    dense = np.linspace(AT - 0.05, out.cut + 0.05, 4000)
    path = np.stack([np.interp(dense, old.t, old.q[:, j]) for j in range(old.q.shape[1])], 1)
    braked = out.plan.q[(out.plan.t >= AT) & (out.plan.t <= out.cut)]
    gap = np.linalg.norm(braked[:, None] - path[None], axis=2).min(axis=1)
    assert gap.max() < 2e-3  # configurations of the old path (to the density of ``dense``)
    assert np.array_equal(out.plan.q[out.plan.t <= AT], old.q[old.t <= AT])
    assert len(grasp_poses(out.plan, "o1", out.cut)) == 1


def test_the_running_plan_meeting_the_change_is_infeasible_with_the_object(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 5.4 s the right arm is 14 ms from touching o1: too late to brake."""
    out = replan_d5(d5, cache, _o1_nudged(d5[0]), at=5.4)
    assert out.status == "infeasible" and out.plan is None and not out.success
    assert out.blocking == ("o1",)
    assert "before the arms can stop" in out.reasons[0]
    assert "nor braking on their way" in out.reasons[0]


def _b1(x: float, y: float, height: float) -> str:
    return f"added: [{{name: b1, size: [0.04, 0.04, {height}], pose: [{x}, {y}, 0]}}]"


def _released_after(plan: PlanFile, t: float) -> list[tuple[str, str, str]]:
    return [(e.arm, e.type, e.object) for e in plan.events if e.t > t]


def test_an_arm_braked_with_an_object_in_hand_puts_it_down_where_the_plan_would(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 10.8 s the left arm carries o2 over the table (9 cm up) to its goal; b1, 10 cm
    tall, stands on the way: the arm brakes with o2 in hand, carries it around b1 to its
    goal and releases it there; nothing is left to do."""
    out = replan_d5(d5, cache, _b1(0.07, -0.05, 0.1), at=10.8)
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    assert _released_after(out.plan, 10.8) == [("left", "release", "o2")]
    goal = obj(d5[0], "o2").goal
    assert np.allclose(out.plan.final_poses["o2"][:2], (goal.x, goal.y), atol=1e-3)
    assert out.plan.final_poses["b1"] == pytest.approx((0.07, -0.05, 0.0))
    old = d5[1]
    assert np.array_equal(out.plan.q[out.plan.t <= 10.8], old.q[old.t <= 10.8])


def test_an_arm_braked_with_an_object_in_hand_puts_it_back_when_its_place_is_taken(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """b1 appears on o2's goal while the left arm carries o2 there: the way to the goal is
    blocked, so the arm brakes, puts o2 back where it took it from, and the continuation
    moves b1 away and o2 to its goal."""
    goal = obj(d5[0], "o2").goal
    out = replan_d5(d5, cache, _b1(goal.x, goal.y, 0.05), at=10.8)
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    events = _released_after(out.plan, 10.8)
    assert events[0] == ("left", "release", "o2")
    assert out.moved_away == ("b1",) and ("right", "grasp", "b1") in events
    start = obj(d5[0], "o2").start
    put_back = next(e for e in out.plan.events if e.t > 10.8 and e.type == "release")
    state = state_at(out.plan, {o.name: o.start.as_tuple() for o in d5[0].objects}, load_scene(),
                     put_back.t + 0.01)  # fmt: skip
    assert np.allclose(state.resting["o2"][:2], (start.x, start.y), atol=1e-3)
    assert np.allclose(out.plan.final_poses["o2"][:2], (goal.x, goal.y), atol=1e-3)


def test_an_arm_braked_with_an_object_in_hand_sets_it_down_below_when_both_places_are_taken(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 11.1 s the left arm carries o2 to its goal; b1 stands on that goal and b2 where o2
    was taken from: the arm brakes and sets o2 down straight below where it stopped (its yaw
    kept); the continuation moves b1 away and o2 to its goal."""
    goal, start = obj(d5[0], "o2").goal, obj(d5[0], "o2").start
    box = "size: [0.04, 0.04, 0.05], pose"
    text = (f"added: [{{name: b1, {box}: [{goal.x}, {goal.y}, 0]}}, "
            f"{{name: b2, {box}: [{start.x}, {start.y}, 0]}}]")  # fmt: skip
    out = replan_d5(d5, cache, text, at=11.1)
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    put = next(e for e in out.plan.events if e.t > 11.1)
    assert (put.arm, put.type, put.object) == ("left", "release", "o2")
    down = next(s for s in out.plan.steps if s.kind == "put-down")
    assert down.t_start > 11.1 and down.t_end <= put.t  # from the stop to the release

    def tcp(t: float) -> np.ndarray:
        q = np.array([np.interp(t, out.plan.t, out.plan.q[:, j]) for j in range(12)])
        return ArmKinematics.from_scene(scene, "left").fk_tcp(scene.layout.part(q, "left"))

    scene = load_scene()
    stop, placed = tcp(down.t_start), tcp(put.t)
    assert np.allclose(placed[:2, 3], stop[:2, 3], atol=1e-6)  # straight below
    assert stop[2, 3] > placed[2, 3] + 0.03
    assert out.moved_away == ("b1",)
    assert np.allclose(out.plan.final_poses["o2"][:2], (goal.x, goal.y), atol=1e-3)


def test_no_place_to_put_down_what_the_arms_hold_is_infeasible(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 2.4 s the arms swap o3 and o0 (each carries one to where the other was); b1 appears
    where o3 comes down, next to where o0 was taken: neither the plan's placements, nor the
    grasps', nor straight below where the arms stop are reachable with b1 there, so the
    running plan cannot stop short of it."""
    out = replan_d5(d5, cache, _b1(-0.1929, -0.0573, 0.1), at=2.4)
    assert out.status == "infeasible" and out.plan is None
    assert "nor braking on their way" in out.reasons[0] and out.blocking == ("o3", "b1")
