"""Re-planning from an observed state (``sdar_tamp.app.replanning``) on D5 of the paper
suite and its stored plan (``conftest.py``): a nudged object is re-grasped at its new pose, a
removed object's remaining tasks disappear, an added object that blocks a goal is moved away,
a changed repair is compared with a fresh continuation, and impossible observed states are
refused with their location (the arms braking short of a change:
``test_replanning_braking.py``). Every new plan is the spliced whole and validates by the
independent replay."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_state import state_at
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.errors import ObservedStateError
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import load_scene
from tests.app.conftest import AT, assert_valid_whole, grasp_poses, obj, replan_d5


@pytest.mark.parametrize("repair", [True, False])
def test_a_nudged_object_is_regrasped_at_its_new_pose(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repair: bool
) -> None:
    o2 = obj(d5[0], "o2")
    new = (o2.start.x + 0.015, o2.start.y - 0.01, o2.start.yaw + 0.15)
    out = replan_d5(d5, cache, f"poses: [{{name: o2, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
                  repair=repair)  # fmt: skip
    assert out.status == ("repaired" if repair else "replanned")
    plan = assert_valid_whole(d5, out)
    grasps = grasp_poses(plan, "o2", out.cut)
    assert grasps, "o2 is grasped after the cut"
    d = math.hypot(grasps[0][0] - new[0], grasps[0][1] - new[1])
    assert d < 1e-3  # at its new pose, not at the old one 18 mm away
    # the old plan in the observed world fails at its grasp of o2
    stale = dataclasses.replace(d5[1], observations=plan.observations)
    report = validate_plan(d5[0], stale, load_scene())
    assert not report.ok and report.violation is not None and report.violation.t > AT


def test_a_fresh_continuation_shorter_than_the_repair_is_kept(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """o4 nudged at 5.116 s (resting, its task still to come): the repair plans o4's task
    again and rejoins the old plan, 13.70 s in all; a fresh continuation from the same cut
    ends 0.5 s earlier. The re-plan compares the two and keeps the fresh one; without the
    comparison it keeps the repair, and a fresh continuation alone is the same plan as the
    one kept (same seed, same plan)."""
    instance, plan = d5
    at = 5.116
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    x, y, yaw = state_at(plan, starts, load_scene(), at).resting["o4"]
    text = f"poses: [{{name: o4, pose: [{x + 0.0052}, {y + 0.0173}, {yaw - 0.1559}]}}]"
    out = replan_d5(d5, cache, text, at=at)
    kept = replan_d5(d5, cache, text, at=at, compare=False)
    fresh = replan_d5(d5, cache, text, at=at, repair=False)
    assert kept.status == "repaired" and kept.plan is not None and kept.valid is True
    assert fresh.status == "replanned" and fresh.plan is not None and fresh.valid is True
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(instance, out.plan, load_scene()).ok
    assert out.cut == kept.cut == fresh.cut
    assert out.alternative == pytest.approx(kept.plan.duration)  # the repair, not kept
    assert out.plan.duration < 0.99 * kept.plan.duration
    assert np.array_equal(out.plan.t, fresh.plan.t) and np.array_equal(out.plan.q, fresh.plan.q)
    assert len(grasp_poses(out.plan, "o4", out.cut)) == 1


@pytest.mark.parametrize("failure", ["no plan", "rejected"])
def test_the_repair_is_kept_when_the_fresh_continuation_fails(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, monkeypatch: pytest.MonkeyPatch,
    failure: str,
) -> None:  # fmt: skip
    """The case above, with the fresh continuation of the comparison giving no plan in the
    time left, or one the replay from the cut rejects (both made so here): the repair is
    kept, with no alternative."""
    from sdar_tamp.app import replanning

    if failure == "no plan":
        monkeypatch.setattr(replanning, "fresh_continuation",
                            lambda *a, **k: replanning.Fresh(None, (), "timeout"))  # fmt: skip
    else:
        monkeypatch.setattr(replanning, "check_from", lambda *a: (a[1], 1.0, "made to fail"))
    instance, plan = d5
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    x, y, yaw = state_at(plan, starts, load_scene(), 5.116).resting["o4"]
    text = f"poses: [{{name: o4, pose: [{x + 0.0052}, {y + 0.0173}, {yaw - 0.1559}]}}]"
    out = replan_d5(d5, cache, text, at=5.116)
    assert out.status == "repaired" and out.valid is True and out.alternative is None


def test_a_repair_as_short_as_a_fresh_continuation_is_kept(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 12.3 s (every task done) o3 nudged off its goal: the repair's one more task and a
    fresh continuation take as long; the repair is kept and the fresh one's duration is
    reported."""
    goal = obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    out = replan_d5(d5, cache, f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
                  at=12.3)  # fmt: skip
    assert out.status == "repaired" and out.plan is not None and out.valid is True
    assert out.alternative is not None
    assert out.plan.duration - out.cut <= (out.alternative - out.cut) / 0.99


@pytest.mark.parametrize("repair", [True, False])
def test_a_nudged_object_at_its_goal_is_put_back(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repair: bool
) -> None:
    """o3 rests at its goal from 3.59 s on and no task of the old plan touches it again: the
    repair plans the last task (o2's) again with o3 put back; a fresh continuation puts it back
    within its plan.
    Neither moves o0, at its goal to rounding (the continuation takes it as there)."""
    goal = obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    out = replan_d5(d5, cache, f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
                  repair=repair)  # fmt: skip
    assert out.status == ("repaired" if repair else "replanned")
    plan = assert_valid_whole(d5, out)
    grasps = grasp_poses(plan, "o3", out.cut)
    assert len(grasps) == 1 and math.hypot(grasps[0][0] - new[0], grasps[0][1] - new[1]) < 1e-3
    assert np.allclose(plan.final_poses["o3"][:2], (goal.x, goal.y), atol=1e-3)
    assert not [e for e in plan.events if e.object == "o0" and e.t > out.cut]
    if repair:  # the old plan's rest is kept up to its last task (o2's), which o3 joins
        kept = [(e.type, e.object) for e in d5[1].events if AT < e.t < 10.0]
        after = [(e.type, e.object) for e in plan.events if e.t > AT]
        assert after[: len(kept)] == kept
        assert sorted(after[len(kept) :]) == sorted(
            [("grasp", "o2"), ("release", "o2"), ("grasp", "o3"), ("release", "o3")]
        )


def test_a_nudged_object_at_its_goal_gets_one_more_task_when_the_last_cannot_take_it(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, monkeypatch: pytest.MonkeyPatch
) -> None:
    """When the last task cannot be planned again with o3 (made to fail here), the old plan's
    rest is kept whole and one more task after it puts o3 back (without the comparison with a
    fresh continuation, which is shorter here)."""
    from sdar_tamp.app import repair as repair_module

    monkeypatch.setattr(repair_module, "_replan_task", lambda *args: None)
    goal = obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    text = f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]"
    out = replan_d5(d5, cache, text, compare=False)
    assert out.status == "repaired" and out.plan is not None
    # compared, a fresh continuation (o3 put back within it) is shorter and kept
    shorter = replan_d5(d5, cache, text)
    assert shorter.status == "replanned" and shorter.plan is not None
    assert shorter.alternative == pytest.approx(out.plan.duration)
    assert shorter.plan.duration < 0.99 * out.plan.duration
    plan = assert_valid_whole(d5, out)
    kept = [(e.type, e.object) for e in d5[1].events if e.t > AT]
    after = [(e.type, e.object) for e in plan.events if e.t > AT]
    assert after == [*kept, ("grasp", "o3"), ("release", "o3")]


def test_a_nudged_object_at_its_goal_after_the_last_task_gets_one_more(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 12.3 s every task is done (the last release, at 12.03 s, in its dwell): one more
    task after the old plan's end puts o3 back."""
    goal = obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    out = replan_d5(d5, cache, f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
                  at=12.3)  # fmt: skip
    assert out.status == "repaired" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    assert out.cut == pytest.approx(12.3, abs=0.03)  # in the dwell: still and empty
    after = [(e.type, e.object) for e in out.plan.events if e.t > 12.3]
    assert after == [("grasp", "o3"), ("release", "o3")]
    assert np.allclose(out.plan.final_poses["o3"][:2], (goal.x, goal.y), atol=1e-3)


def test_a_removed_object_loses_its_remaining_tasks(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    out = replan_d5(d5, cache, "removed: [o2]")
    plan = assert_valid_whole(d5, out)
    assert not [e for e in plan.events if e.object == "o2"]
    assert "o2" not in plan.final_poses and out.plan is not None
    assert out.plan.duration < d5[1].duration  # its task is gone, the rest is kept


def test_an_added_object_on_a_goal_is_moved_away(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    goal = obj(d5[0], "o2").goal
    out = replan_d5(
        d5, cache,
        f"added: [{{name: b1, size: [0.05, 0.05, 0.05], pose: [{goal.x}, {goal.y}, 0.3]}}]",
    )  # fmt: skip
    plan = assert_valid_whole(d5, out)
    assert out.moved_away == ("b1",)
    assert {e.type for e in plan.events if e.object == "b1"} == {"grasp", "release"}
    x, y, _ = plan.final_poses["b1"]
    assert math.hypot(x - goal.x, y - goal.y) > 0.05
    assert np.allclose(plan.final_poses["o2"][:2], (goal.x, goal.y), atol=1e-3)


def test_an_added_object_out_of_the_way_stays(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    text = "added: [{name: b1, size: [0.04, 0.04, 0.04], pose: [0.2, -0.25, 0]}]"
    out = replan_d5(d5, cache, text)
    plan = assert_valid_whole(d5, out)
    assert out.status == "repaired" and out.moved_away == ()
    assert not [e for e in plan.events if e.object == "b1"]
    assert plan.final_poses["b1"] == pytest.approx((0.2, -0.25, 0.0))


def test_nothing_changed_keeps_the_old_plan(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    out = replan_d5(d5, cache, "")
    plan = assert_valid_whole(d5, out)
    assert out.status == "repaired"
    assert len(plan.events) == len(d5[1].events)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("poses: [{name: o2, pose: [0.2, 0.04, 0]}]", "objects 'o2' and 'o4' overlap"),
        ("removed: [o3]", "'o3' is held by arm 'left'"),
        ("removed: [nope]", "unknown object 'nope'"),
        ("poses: [{name: o2, pose: [0.9, 0.0, 0]}]", "leaves the workspace"),
    ],
)
def test_impossible_observed_states_are_refused_with_their_location(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, text: str, message: str
) -> None:
    with pytest.raises(ObservedStateError) as err:
        replan_d5(d5, cache, text, at=2.5)  # at 2.5 s the left arm carries o3
    assert str(err.value).startswith("obs.yaml:1:") and message in str(err.value)


def test_an_object_inside_an_arm_at_the_time_reached(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    instance, plan = d5
    scene = load_scene()
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    kin = ArmKinematics.from_scene(scene, "right")
    for at in (2.0, 2.5, 3.0, 7.0, 9.0):  # the right arm in the air, away from resting objects
        state = state_at(plan, starts, scene, at)
        tcp = kin.fk_tcp(scene.layout.part(state.q, "right"))
        text = (f"added: [{{name: b1, size: [0.03, 0.03, {tcp[2, 3] + 0.02:.3f}], "
                f"pose: [{tcp[0, 3]:.4f}, {tcp[1, 3]:.4f}, 0]}}]")  # fmt: skip
        try:
            replan_d5(d5, cache, text, at=at)
        except ObservedStateError as err:
            if "overlap" in str(err):
                continue  # on a resting object: another time
            assert re.match(r"obs\.yaml:1:\d+: object 'b1' is inside arm 'right' \(", str(err))
            assert f"at t = {at:.3f} s, the arm at [" in str(err)
            return
        raise AssertionError(f"b1 inside the right arm at {at} s is not refused")
    raise AssertionError("no time with the right arm clear of the resting objects")


def test_a_time_outside_the_plan(d5: tuple[Instance, PlanFile], cache: PlannerCache) -> None:
    with pytest.raises(ParameterError, match="at: expected a time within the plan"):
        replan_d5(d5, cache, "", at=d5[1].duration + 1.0)
