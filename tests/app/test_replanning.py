"""Re-planning from an observed state (``sdar_tamp.app.replanning``) on D5 of the paper
suite and its stored plan: a nudged object is re-grasped at its new pose, a removed object's
remaining tasks disappear, an added object that blocks a goal is moved away, impossible
observed states are refused with their location, and where the running plan meets the
observed world before its arms can stop the answer is ``infeasible`` naming the object. Every
new plan is the spliced whole and validates by the independent replay."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.replanning import ReplanOutcome, replan
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_state import state_at
from sdar_tamp.replay import validate_plan
from sdar_tamp.resources import domains_root
from sdar_tamp.world.errors import ObservedStateError
from sdar_tamp.world.instance import Instance, load_instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.observed import parse_observed
from sdar_tamp.world.scene import load_scene

SOLVED = Path(__file__).parents[1] / "plan" / "solved"
AT = 4.5  # D5's plan: o3/o0 swapped, o4/o1 on their way; o2 rests until the last task
CONFIG = PlannerConfig(max_time=60.0, seed=0)


@pytest.fixture(scope="module")
def cache() -> PlannerCache:
    return PlannerCache()


@pytest.fixture(scope="module")
def d5() -> tuple[Instance, PlanFile]:
    instance = load_instance(domains_root() / "dual_arm_rearrangement/suites/paper/D5.yaml")
    return instance, load_plan(SOLVED / "D5.plan.json")


def _obj(instance: Instance, name: str):  # type: ignore[no-untyped-def]
    return next(o for o in instance.objects if o.name == name)


def _replan(d5: tuple[Instance, PlanFile], cache: PlannerCache, text: str, at: float = AT,
            **kw: object) -> ReplanOutcome:  # fmt: skip
    instance, plan = d5
    return replan(instance, plan, at, parse_observed(text, "obs.yaml"), config=CONFIG,
                  cache=cache, **kw)  # type: ignore[arg-type]  # fmt: skip


def _grasp_poses(plan: PlanFile, name: str, after: float) -> list[tuple[float, float, float]]:
    """Where ``plan``'s grasps of ``name`` after ``after`` [s] take the object from."""
    scene = load_scene()
    out = []
    for e in plan.events:
        if e.object == name and e.type == "grasp" and e.t > after:
            q = np.array([np.interp(e.t, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])])
            T = ArmKinematics.from_scene(scene, e.arm).fk_tcp(scene.layout.part(q, e.arm))
            T = T @ e.T_tcp_object
            out.append((float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0])))
    return out


def _assert_valid_whole(d5: tuple[Instance, PlanFile], out: ReplanOutcome) -> PlanFile:
    instance, old = d5
    assert out.plan is not None and out.valid is True, out
    report = validate_plan(instance, out.plan, load_scene())  # the independent replay again
    assert report.ok, report.violation
    prefix = out.plan.t <= out.cut
    assert np.array_equal(out.plan.q[prefix], old.q[old.t <= out.cut])  # the executed prefix
    assert [o.t for o in out.plan.observations] == [AT]
    return out.plan


@pytest.mark.parametrize("repair", [True, False])
def test_a_nudged_object_is_regrasped_at_its_new_pose(
    d5: tuple[Instance, PlanFile], cache: PlannerCache, repair: bool
) -> None:
    o2 = _obj(d5[0], "o2")
    new = (o2.start.x + 0.015, o2.start.y - 0.01, o2.start.yaw + 0.15)
    out = _replan(d5, cache, f"poses: [{{name: o2, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
                  repair=repair)  # fmt: skip
    assert out.status == ("repaired" if repair else "replanned")
    plan = _assert_valid_whole(d5, out)
    grasps = _grasp_poses(plan, "o2", out.cut)
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
    out = _replan(d5, cache, text, at=at)
    kept = _replan(d5, cache, text, at=at, compare=False)
    fresh = _replan(d5, cache, text, at=at, repair=False)
    assert kept.status == "repaired" and kept.plan is not None and kept.valid is True
    assert fresh.status == "replanned" and fresh.plan is not None and fresh.valid is True
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(instance, out.plan, load_scene()).ok
    assert out.cut == kept.cut == fresh.cut
    assert out.alternative == pytest.approx(kept.plan.duration)  # the repair, not kept
    assert out.plan.duration < 0.99 * kept.plan.duration
    assert np.array_equal(out.plan.t, fresh.plan.t) and np.array_equal(out.plan.q, fresh.plan.q)
    assert len(_grasp_poses(out.plan, "o4", out.cut)) == 1


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
    out = _replan(d5, cache, text, at=5.116)
    assert out.status == "repaired" and out.valid is True and out.alternative is None


def test_a_repair_as_short_as_a_fresh_continuation_is_kept(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 12.3 s (every task done) o3 nudged off its goal: the repair's one more task and a
    fresh continuation take as long; the repair is kept and the fresh one's duration is
    reported."""
    goal = _obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    out = _replan(d5, cache, f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
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
    goal = _obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    out = _replan(d5, cache, f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
                  repair=repair)  # fmt: skip
    assert out.status == ("repaired" if repair else "replanned")
    plan = _assert_valid_whole(d5, out)
    grasps = _grasp_poses(plan, "o3", out.cut)
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
    goal = _obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    text = f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]"
    out = _replan(d5, cache, text, compare=False)
    assert out.status == "repaired" and out.plan is not None
    # compared, a fresh continuation (o3 put back within it) is shorter and kept
    shorter = _replan(d5, cache, text)
    assert shorter.status == "replanned" and shorter.plan is not None
    assert shorter.alternative == pytest.approx(out.plan.duration)
    assert shorter.plan.duration < 0.99 * out.plan.duration
    plan = _assert_valid_whole(d5, out)
    kept = [(e.type, e.object) for e in d5[1].events if e.t > AT]
    after = [(e.type, e.object) for e in plan.events if e.t > AT]
    assert after == [*kept, ("grasp", "o3"), ("release", "o3")]


def test_a_nudged_object_at_its_goal_after_the_last_task_gets_one_more(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 12.3 s every task is done (the last release, at 12.03 s, in its dwell): one more
    task after the old plan's end puts o3 back."""
    goal = _obj(d5[0], "o3").goal
    new = (goal.x + 0.012, goal.y + 0.006, goal.yaw - 0.2)
    out = _replan(d5, cache, f"poses: [{{name: o3, pose: [{new[0]}, {new[1]}, {new[2]}]}}]",
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
    out = _replan(d5, cache, "removed: [o2]")
    plan = _assert_valid_whole(d5, out)
    assert not [e for e in plan.events if e.object == "o2"]
    assert "o2" not in plan.final_poses and out.plan is not None
    assert out.plan.duration < d5[1].duration  # its task is gone, the rest is kept


def test_an_added_object_on_a_goal_is_moved_away(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    goal = _obj(d5[0], "o2").goal
    out = _replan(
        d5, cache,
        f"added: [{{name: b1, size: [0.05, 0.05, 0.05], pose: [{goal.x}, {goal.y}, 0.3]}}]",
    )  # fmt: skip
    plan = _assert_valid_whole(d5, out)
    assert out.moved_away == ("b1",)
    assert {e.type for e in plan.events if e.object == "b1"} == {"grasp", "release"}
    x, y, _ = plan.final_poses["b1"]
    assert math.hypot(x - goal.x, y - goal.y) > 0.05
    assert np.allclose(plan.final_poses["o2"][:2], (goal.x, goal.y), atol=1e-3)


def test_an_added_object_out_of_the_way_stays(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    out = _replan(d5, cache, "added: [{name: b1, size: [0.04, 0.04, 0.04], pose: [0.2, -0.25, 0]}]")
    plan = _assert_valid_whole(d5, out)
    assert out.status == "repaired" and out.moved_away == ()
    assert not [e for e in plan.events if e.object == "b1"]
    assert plan.final_poses["b1"] == pytest.approx((0.2, -0.25, 0.0))


def test_nothing_changed_keeps_the_old_plan(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    out = _replan(d5, cache, "")
    plan = _assert_valid_whole(d5, out)
    assert out.status == "repaired"
    assert len(plan.events) == len(d5[1].events)


def _o1_nudged(instance: Instance) -> str:
    o1 = _obj(instance, "o1")  # the right arm is on its way to grasp it at 5.71 s
    return (f"poses: [{{name: o1, pose: [{o1.start.x + 0.015}, {o1.start.y - 0.01}, "
            f"{o1.start.yaw + 0.15}]}}]")  # fmt: skip


def test_the_arms_brake_short_of_a_change_on_their_way(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """The right arm would touch the nudged o1 at 5.414 s, before the plan's next cut (its
    grasp at 5.71 s): the arms brake on their way from 4.5 s, on the old plan's path, and a
    fresh continuation re-grasps o1 at its new pose."""
    out = _replan(d5, cache, _o1_nudged(d5[0]))
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
    assert len(_grasp_poses(out.plan, "o1", out.cut)) == 1


def test_the_running_plan_meeting_the_change_is_infeasible_with_the_object(
    d5: tuple[Instance, PlanFile], cache: PlannerCache
) -> None:
    """At 5.4 s the right arm is 14 ms from touching o1: too late to brake."""
    out = _replan(d5, cache, _o1_nudged(d5[0]), at=5.4)
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
    out = _replan(d5, cache, _b1(0.07, -0.05, 0.1), at=10.8)
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    assert _released_after(out.plan, 10.8) == [("left", "release", "o2")]
    goal = _obj(d5[0], "o2").goal
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
    goal = _obj(d5[0], "o2").goal
    out = _replan(d5, cache, _b1(goal.x, goal.y, 0.05), at=10.8)
    assert out.status == "replanned" and out.plan is not None and out.valid is True
    assert validate_plan(d5[0], out.plan, load_scene()).ok
    events = _released_after(out.plan, 10.8)
    assert events[0] == ("left", "release", "o2")
    assert out.moved_away == ("b1",) and ("right", "grasp", "b1") in events
    start = _obj(d5[0], "o2").start
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
    goal, start = _obj(d5[0], "o2").goal, _obj(d5[0], "o2").start
    box = "size: [0.04, 0.04, 0.05], pose"
    text = (f"added: [{{name: b1, {box}: [{goal.x}, {goal.y}, 0]}}, "
            f"{{name: b2, {box}: [{start.x}, {start.y}, 0]}}]")  # fmt: skip
    out = _replan(d5, cache, text, at=11.1)
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
    out = _replan(d5, cache, _b1(-0.1929, -0.0573, 0.1), at=2.4)
    assert out.status == "infeasible" and out.plan is None
    assert "nor braking on their way" in out.reasons[0] and out.blocking == ("o3", "b1")


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
        _replan(d5, cache, text, at=2.5)  # at 2.5 s the left arm carries o3
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
            _replan(d5, cache, text, at=at)
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
        _replan(d5, cache, "", at=d5[1].duration + 1.0)
