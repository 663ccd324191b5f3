"""The independent validator: a planned valid plan, mutations it must reject, and the CLI.

The valid plan is made with the planning streams (tests may use them; the validator does not):
the left arm picks o1 at its start, places it at its goal and returns home; o2 never moves.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanEvent, PlanFile
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, parse_instance
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKRequest, solve_ik_candidates
from streams.motion.exact_check import HeldObject
from streams.motion.ladder import plan_dual_motion
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, MotionResult

INSTANCE = """name: T2
workspace: {x: [-0.25, 0.25], y: [-0.3, 0.3]}
objects:
  - {name: o1, size: [0.08, 0.04, 0.05], start: [-0.15, 0.15, 0.3], goal: [-0.1, -0.15, 1.2]}
  - {name: o2, size: [0.08, 0.04, 0.05], start: [0.12, 0.0, 0.5], goal: [0.12, 0.0, 0.5]}
"""


@dataclass(frozen=True)
class Planned:
    ctx: WorldContext
    instance: Instance
    plan: PlanFile
    q_grasp: FloatArray  # (12,) left arm at the grasp of o1, right arm home
    T_tcp_obj: FloatArray


def _box(o: ObjectSpec, p: Pose2D) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(p.x, p.y, o.size[2] / 2, p.yaw), o.size)


def _segment(result: MotionResult, kind: str) -> MotionSegment:
    assert result.success and result.trajectory is not None, result.reason
    traj = result.trajectory
    return MotionSegment(traj.t, traj.q, result.level or "", ("o1",), kind)


@pytest.fixture(scope="module")
def planned(ctx: WorldContext, planner: MotionPlanner) -> Planned:
    instance = parse_instance(INSTANCE, "t2.yaml")
    o1 = instance.objects[0]
    start = {o.name: _box(o, o.start) for o in instance.objects}
    goal = {"o1": _box(o1, o1.goal), "o2": start["o2"]}
    home = {a: ctx.home(a) for a in ctx.arm_names}
    world = ctx.new_world()
    grasps = sample_grasps(o1.size, ctx.scene.grasp_limits)
    at_start = solve_ik_candidates(
        ctx, world, start, [IKRequest("left", "o1", start["o1"], grasps)], home
    )
    at_goal = solve_ik_candidates(
        ctx, world, goal, [IKRequest("left", "o1", goal["o1"], grasps)], home
    )
    pick, place = next((a, b) for a in at_start for b in at_goal if a.grasp is b.grasp)
    h12 = np.concatenate([home["left"], home["right"]])
    q_pick = np.concatenate([pick.q, home["right"]])
    q_place = np.concatenate([place.q, home["right"]])
    T_tcp_obj = inverse(pick.grasp.T_object_tcp)
    held = HeldObject("o1", o1.size, ctx.kinematics["left"].T_tool0_tcp @ T_tcp_obj)
    requests = [
        MotionRequest(h12, q_pick, start, approach=(True, False)),
        MotionRequest(
            q_pick, q_place, {"o2": start["o2"]}, {"left": held}, (True, False), (True, False)
        ),
        MotionRequest(q_place, h12, goal, retreat=(True, False)),
    ]
    a, b, c = (plan_dual_motion(planner, r) for r in requests)
    items: list[MotionSegment | GripperEvent] = [
        _segment(a, "pick"),
        GripperEvent("left", "grasp", "o1", T_tcp_obj),
        _segment(b, "place"),
        GripperEvent("left", "release", "o1", T_tcp_obj),
        _segment(c, "retreat"),
    ]
    plan = build_plan_file(
        ctx.scene,
        instance.name,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        items,
        {"planning_time": 0.0},
    )
    return Planned(ctx, instance, plan, q_pick, T_tcp_obj)


def _kind(instance: Instance, plan: PlanFile) -> str | None:
    report = validate_plan(instance, plan)
    return report.violation.kind if report.violation is not None else None


def _with_q(plan: PlanFile, edit: FloatArray) -> PlanFile:
    return dataclasses.replace(plan, q=edit)


def _events(plan: PlanFile, kind: str, T: FloatArray) -> tuple[PlanEvent, ...]:
    return tuple(
        dataclasses.replace(e, T_tcp_object=T) if e.type == kind else e for e in plan.events
    )


# -- the valid plan ------------------------------------------------------------------------------
def test_the_planned_plan_is_valid(planned: Planned) -> None:
    report = validate_plan(planned.instance, planned.plan, planned.ctx.scene)
    assert report.ok and report.violation is None
    assert report.checks > len(planned.plan.t) // 2
    assert planned.plan.metrics.actions == 1


def test_a_finer_tcp_step_makes_more_checks(planned: Planned) -> None:
    fine = validate_plan(planned.instance, planned.plan, max_tcp_step=0.002)
    coarse = validate_plan(planned.instance, planned.plan, max_tcp_step=0.02)
    assert fine.ok and coarse.ok and fine.checks > 2 * coarse.checks


# -- mutations -------------------------------------------------------------------------------------
def test_a_joint_jump_breaks_the_velocity_limit(planned: Planned) -> None:
    q = np.array(planned.plan.q)
    q[60, 2] += 0.5
    report = validate_plan(planned.instance, _with_q(planned.plan, q))
    assert report.violation is not None and report.violation.kind == "velocity"
    assert report.violation.t == pytest.approx(planned.plan.t[59])
    assert "left elbow" in report.violation.message


def test_a_lowered_arm_collides(planned: Planned) -> None:
    q = np.array(planned.plan.q)
    q[:, 1] += 0.3  # the whole left shoulder lift: same velocities, arm 0.3 rad lower
    report = validate_plan(planned.instance, _with_q(planned.plan, q))
    assert report.violation is not None and report.violation.kind == "collision"
    assert "left_" in report.violation.message


def test_joint_limit(planned: Planned) -> None:
    q = np.array(planned.plan.q)
    q[:, 5] += 3.5  # wrist 3 past pi from the start
    report = validate_plan(planned.instance, _with_q(planned.plan, q))
    assert report.violation is not None and report.violation.kind == "joint limit"
    assert report.violation.t == 0.0


def test_a_faster_replay_breaks_the_dynamic_limits(planned: Planned) -> None:
    events = tuple(dataclasses.replace(e, t=0.5 * e.t) for e in planned.plan.events)
    plan = dataclasses.replace(planned.plan, t=planned.plan.t * 0.5, events=events)
    assert _kind(planned.instance, plan) in ("velocity", "acceleration")


def test_a_grasp_away_from_the_object(planned: Planned) -> None:
    T = np.array(planned.T_tcp_obj)
    T[0, 3] += 0.02
    plan = dataclasses.replace(planned.plan, events=_events(planned.plan, "grasp", T))
    report = validate_plan(planned.instance, plan)
    assert report.violation is not None and report.violation.kind == "grasp"
    assert "20.0 mm" in report.violation.message


def test_a_release_pose_moved_by_two_centimetres(planned: Planned) -> None:
    T = np.array(planned.T_tcp_obj)
    T[1, 3] += 0.02
    plan = dataclasses.replace(planned.plan, events=_events(planned.plan, "release", T))
    assert _kind(planned.instance, plan) == "release"


def test_changed_final_poses(planned: Planned) -> None:
    final = dict(planned.plan.final_poses)
    x, y, yaw = final["o1"]
    final["o1"] = (x + 0.02, y, yaw)
    assert _kind(planned.instance, dataclasses.replace(planned.plan, final_poses=final)) == (
        "final poses"
    )
    final["o1"] = (x, y, yaw + np.pi)  # the cuboid's symmetry: still the same placement
    assert _kind(planned.instance, dataclasses.replace(planned.plan, final_poses=final)) is None


def test_a_goal_two_centimetres_away(planned: Planned) -> None:
    o1, o2 = planned.instance.objects
    moved = dataclasses.replace(o1, goal=dataclasses.replace(o1.goal, x=o1.goal.x + 0.02))
    instance = dataclasses.replace(planned.instance, objects=(moved, o2))
    assert _kind(instance, planned.plan) == "goal"


def test_a_skipped_release(planned: Planned) -> None:
    events = tuple(e for e in planned.plan.events if e.type != "release")
    report = validate_plan(planned.instance, dataclasses.replace(planned.plan, events=events))
    assert report.violation is not None and report.violation.kind == "held"
    assert report.violation.t == planned.plan.duration


def test_a_second_grasp_by_a_full_gripper(planned: Planned) -> None:
    grasp = planned.plan.events[0]
    events = (grasp, dataclasses.replace(grasp, object="o2"), *planned.plan.events[1:])
    report = validate_plan(planned.instance, dataclasses.replace(planned.plan, events=events))
    assert report.violation is not None and report.violation.kind == "dwell"
    assert "grasp of o2 comes 0.000 s after its grasp" in report.violation.message
    # the second grasp after the dwell, the arm still standing: the gripper is full
    plan = _standing(planned, planned.instance, [], second="o2")
    report = validate_plan(planned.instance, plan)
    assert report.violation is not None and report.violation.kind == "grasp"
    assert "left grasps o2 while holding o1" in report.violation.message
    assert report.violation.t == pytest.approx(0.5)


def test_wrong_instance_object_set_and_name(planned: Planned) -> None:
    o1, o2 = planned.instance.objects
    o3 = dataclasses.replace(o2, name="o3")
    for objects in ((o1,), (o1, o3), (o1, o2, o3)):
        instance = dataclasses.replace(planned.instance, objects=objects)
        report = validate_plan(instance, planned.plan)
        assert report.violation is not None and report.violation.kind == "instance"
        assert report.violation.t == 0.0 and report.checks == 0
    renamed = dataclasses.replace(planned.instance, name="other")
    assert _kind(renamed, planned.plan) == "instance"


def test_arms_must_match_the_scene(planned: Planned) -> None:
    left, right = planned.plan.arms
    base = np.array(left.T_world_base)
    base[0, 3] += 0.01
    moved = dataclasses.replace(left, T_world_base=base)
    assert _kind(planned.instance, dataclasses.replace(planned.plan, arms=(moved, right))) == (
        "scene"
    )
    assert _kind(planned.instance, dataclasses.replace(planned.plan, arms=(right, left))) == (
        "scene"
    )


# -- release rules, on plans that stand still at the grasp -------------------------------------
def _standing(
    planned: Planned, instance: Instance, motion: list[MotionSegment], second: str = "o1"
) -> PlanFile:
    """Grasp o1 where it stands, optionally move (else stand still through the dwell), then
    release it (``second``: another object, grasped instead)."""
    still = MotionSegment(np.zeros(1), planned.q_grasp[None])  # the dwell, nothing more
    items: list[MotionSegment | GripperEvent] = [
        GripperEvent("left", "grasp", "o1", planned.T_tcp_obj),
        *(motion or [still]),
        GripperEvent("left", "release" if second == "o1" else "grasp", second, planned.T_tcp_obj),
    ]
    return build_plan_file(
        planned.ctx.scene,
        instance.name,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        items,
        {},
        q_start=planned.q_grasp,
    )


def _only_o1(planned: Planned, workspace: Workspace | None = None) -> Instance:
    o1 = planned.instance.objects[0]
    o1 = dataclasses.replace(o1, goal=o1.start)
    return Instance("T1", workspace or planned.instance.workspace, (o1,))


def test_grasp_and_release_in_place_is_valid(planned: Planned) -> None:
    instance = _only_o1(planned)
    assert validate_plan(instance, _standing(planned, instance, [])).ok


def test_release_onto_another_object(planned: Planned) -> None:
    o1 = _only_o1(planned).objects[0]
    s = o1.start
    # 1.5 mm over: the footprints overlap (the released one is shrunk by 1 mm per side), the
    # boxes do not collide (both shrunk by 1 mm per side)
    d = 0.0785
    near = Pose2D(s.x + d * np.cos(s.yaw), s.y + d * np.sin(s.yaw), s.yaw)
    o2 = ObjectSpec("o2", o1.size, near, near)
    instance = Instance("T1", planned.instance.workspace, (o1, o2))
    report = validate_plan(instance, _standing(planned, instance, []))
    assert report.violation is not None and report.violation.kind == "release"
    assert "onto o2" in report.violation.message


def test_release_outside_the_workspace(planned: Planned) -> None:
    instance = _only_o1(planned, Workspace((-0.25, -0.16), (-0.3, 0.3)))
    report = validate_plan(instance, _standing(planned, instance, []))
    assert report.violation is not None and "leaves the workspace" in report.violation.message


def test_release_of_a_tilted_object(planned: Planned) -> None:
    instance = _only_o1(planned)
    t = np.linspace(0.0, 1.5, 76)
    q = np.repeat(planned.q_grasp[None], len(t), axis=0)
    q[:, 3] -= np.linspace(0.0, 0.15, len(t))  # turn the left wrist 1: the object tilts up
    report = validate_plan(instance, _standing(planned, instance, [MotionSegment(t, q)]))
    assert report.violation is not None and report.violation.kind == "release"
    assert "flat" in report.violation.message


# -- the command line ----------------------------------------------------------------------
def test_sdar_validate_exit_codes(
    planned: Planned, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    instance = tmp_path / "t2.yaml"
    instance.write_text(INSTANCE)
    good = save_plan(planned.plan, tmp_path / "plan.json")
    assert main(["validate", str(instance), str(good)]) == 0
    assert capsys.readouterr().out.startswith("valid: ")
    final = dict(planned.plan.final_poses)
    final["o1"] = (0.0, 0.0, 0.0)
    bad = save_plan(dataclasses.replace(planned.plan, final_poses=final), tmp_path / "bad.json")
    assert main(["validate", str(instance), str(bad)]) == 1
    out = capsys.readouterr().out
    assert out.startswith("invalid at t=") and "s: final poses: o1 ends at" in out
    assert main(["validate", str(instance), str(bad), "--json"]) == 1
    record = json.loads(capsys.readouterr().out)
    assert record["valid"] is False and record["violation"]["kind"] == "final poses"
    assert main(["validate", str(instance), str(good), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["valid"] is True and record["violation"] is None and record["checks"] > 0
    assert main(["validate", str(instance), str(tmp_path / "none.json")]) == 2
    assert "none.json: cannot read file" in capsys.readouterr().err
    broken = tmp_path / "broken.json"
    broken.write_text("{")
    assert main(["validate", str(instance), str(broken)]) == 2
    assert "invalid JSON" in capsys.readouterr().err
    assert main(["validate", str(tmp_path / "none.yaml"), str(good)]) == 2
