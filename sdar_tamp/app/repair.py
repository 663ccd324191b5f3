"""Repairing a running plan for an observed change: keep what still holds, re-ground the rest
of the task that the change touches (:func:`repair`, called by
:func:`sdar_tamp.app.replanning.replan` before a fresh solve).

The old plan's rest after the cut is split into tasks at the instants where every arm has
finished a release and its dwell (each task: move to the grasps, grasp, carry, release). The
rest is replayed from the cut in the observed world; at its first violation (a nudged object
no longer where the grasp expects it, a removed object, an added object in the way), the task
it falls in is planned again by SDAR for its own objects only, from the arms' configuration at
the task's start to the placements the old plan gave them (a removed object's part is
dropped, an added object that blocks those placements is moved away); one motion then joins
the arms to the old plan's next grasp, and the old plan goes on from there. An object left off
its goal at the end (one at its goal, nudged: no task of the old plan touches it) joins the
last task, planned again with it (the arms may share the work), or, when that fails within
half the budget or no task is left, one more task after the old plan's end brings it back.
The result is
kept when it replays without violation from the cut; after a few tasks repaired in turn (or a
failed step) the caller solves afresh.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping

import numpy as np

from sdar_tamp.app.cache import PlanningWorld
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.plan_export import decoder_of, timeline
from sdar_tamp.app.problem import rearrangement_problem
from sdar_tamp.app.records import task_records
from sdar_tamp.app.replan_world import continuation_instance, start_configuration
from sdar_tamp.app.solving import solve_rearrangement
from sdar_tamp.app.splicing import check_from, cut_at, head_at, splice, tail, walk_from
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import GRIPPER_DWELL, PlanFile
from sdar_tamp.plan_state import PlanState
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.motion.ladder import plan_dual_motion
from streams.motion.records import MotionRequest
from streams.stream_types import ArmConf, CellConf

Pose3 = tuple[float, float, float]
MAX_TASKS = 3  #: tasks repaired in turn before the caller solves afresh
BUDGET = 3.0  #: [s] of planning the repair may take at least before the caller solves afresh
#: Share of the re-plan's time limit the repair may take, when more than :data:`BUDGET`: on a
#: loaded machine (wall time several times the CPU time) a repair that needs 1 s of CPU
#: still fits, rather than falling back on a fresh solve that needs several times more.
BUDGET_SHARE = 0.25


def repair_budget(max_time: float) -> float:
    """The repair's planning budget [s] (wall time) within a re-plan's ``max_time`` [s]."""
    return min(max_time, max(BUDGET, BUDGET_SHARE * max_time))


@dataclasses.dataclass(frozen=True)
class Task:
    """One task of the old plan: from ``start`` [s] (every arm empty and still) to ``end``
    [s] (its releases and their dwell over); ``objects`` grasped in it."""

    start: float
    end: float
    objects: tuple[str, ...]


def tasks_of(plan: PlanFile, t_from: float) -> list[Task]:
    """The tasks of ``plan`` after ``t_from`` [s] (see the module docstring)."""
    out: list[Task] = []
    start = t_from
    held: set[str] = set()
    grasped: list[str] = []
    for e in plan.events:
        if e.t < t_from - 1e-9:
            continue
        if e.type == "grasp":
            held.add(e.object)
            grasped.append(e.object)
        else:
            held.discard(e.object)
            if not held:
                end = min(e.t + GRIPPER_DWELL, float(plan.t[-1]))
                out.append(Task(start, end, tuple(dict.fromkeys(grasped))))
                start, grasped = end, []
    return out


def repair(
    world: PlanningWorld,
    config: PlannerConfig,
    instance: Instance,
    plan: PlanFile,
    state: PlanState,
    kins: Mapping[str, ArmKinematics],
    collision: CollisionWorld,
    sizes: Mapping[str, tuple[float, float, float]],
) -> tuple[PlanFile, tuple[str, ...], bool] | None:
    """``plan`` (the prefix to ``state.t`` followed by the old plan's rest) repaired from
    ``state`` (every arm empty and still), the added objects it moves away and whether it
    changed (a task planned again or one more), or None when the repair fails."""
    scene = world.ctx.scene
    moved: tuple[str, ...] = ()
    clock = config.sdar.clock
    deadline = clock() + repair_budget(config.max_time)
    plan, emptied = without_gone(plan, state)
    for tasks in range(MAX_TASKS + 1):
        plan, bad, why = check_from(instance, plan, scene, kins, collision, state)
        if bad is None:
            return plan, moved, emptied or tasks > 0
        left = deadline - clock()
        if left <= 0.0:
            return None
        budget = config.replace(max_time=left)
        fixed = _repair_task(world, budget, instance, plan, state, kins, collision, sizes, bad,
                             why)  # fmt: skip
        if fixed is None:
            return None
        plan, more, state = fixed  # the next replay begins where the repaired task does
        moved = tuple(dict.fromkeys((*moved, *more)))
    return None


def without_gone(plan: PlanFile, state: PlanState) -> tuple[PlanFile, bool]:
    """``plan`` without the grasps and releases after ``state.t`` of the objects gone from
    the table (grasped later, not resting in ``state``: removed) in the tasks that move other
    objects too, and whether any was dropped. The arm that was to carry a gone object makes
    the same motions with an empty gripper, beside the task's other arms, so no motion is
    planned again (an empty gripper where an object was carries less: the plan's motions
    stay clear). A task of gone objects only is left as it is: the repair replaces it by one
    motion to the next task (:func:`_replan_task`)."""
    after = [e for e in plan.events if e.t >= state.t - 1e-9]
    gone = {e.object for e in after} - set(state.resting) - set(state.held.values())
    spans = [
        (k.start, k.end) for k in tasks_of(plan, state.t)
        if set(k.objects) & gone and set(k.objects) - gone
    ]  # fmt: skip
    if not spans:
        return plan, False

    def emptied(t: float) -> bool:
        return any(start <= t < end for start, end in spans)

    events = tuple(e for e in plan.events if not (e.object in gone and emptied(e.t)))
    steps = tuple(
        dataclasses.replace(s, objects=tuple(n for n in s.objects if n not in gone))
        if emptied(s.t_start) else s
        for s in plan.steps
    )  # fmt: skip
    metrics = plan.metrics.updated({"actions": sum(e.type == "release" for e in events)})
    return dataclasses.replace(plan, events=events, steps=steps, metrics=metrics), True


def _repair_task(
    world: PlanningWorld, config: PlannerConfig, instance: Instance, plan: PlanFile,
    state: PlanState, kins: Mapping[str, ArmKinematics], collision: CollisionWorld,
    sizes: Mapping[str, tuple[float, float, float]], bad: float, why: str,
) -> tuple[PlanFile, tuple[str, ...], PlanState] | None:  # fmt: skip
    """The task of ``plan`` in which time ``bad`` [s] falls planned again (see the module
    docstring), the added objects moved away, and the state where the new task begins.
    ``why``: the replay's violation there; an object it names outside the task (a nudged or
    added object in the task's way) is moved too: to its goal, or away (added objects)."""
    tasks = tasks_of(plan, state.t)
    task = next((k for k in tasks if k.start <= bad < k.end), None)
    if task is not None:
        return _replan_task(world, config, instance, plan, state, kins, collision, sizes, task,
                            why)  # fmt: skip
    if bad < float(plan.t[-1]) - 1e-9:
        return None
    # an object off its goal at the end: it joins the last task (half the budget), else one
    # more task after the plan's end brings it back
    started = config.sdar.clock()
    if tasks:
        half = config.replace(max_time=0.5 * config.max_time)
        joined = _replan_task(world, half, instance, plan, state, kins, collision, sizes,
                              tasks[-1], why)  # fmt: skip
        if joined is not None:
            return joined
    left = config.max_time - (config.sdar.clock() - started)
    if left <= 0.0:
        return None
    return _append_task(world, config.replace(max_time=left), instance, plan, sizes)


def _replan_task(
    world: PlanningWorld, config: PlannerConfig, instance: Instance, plan: PlanFile,
    state: PlanState, kins: Mapping[str, ArmKinematics], collision: CollisionWorld,
    sizes: Mapping[str, tuple[float, float, float]], task: Task, why: str,
) -> tuple[PlanFile, tuple[str, ...], PlanState] | None:  # fmt: skip
    """``task`` of ``plan`` planned again (see :func:`_repair_task`)."""
    scene = world.ctx.scene
    begin = cut_at(plan, task.start)
    walk = walk_from(instance, plan, scene, kins, collision, state)
    if walk.walk(begin.t, state.t) is not None:
        return None
    here = dict(walk.rest)
    targets = _placements(plan, task, kins, scene.layout)
    goals = {n: Pose2D(*targets[n]) for n in task.objects if n in here and n in targets}
    known = {o.name: o.goal for o in instance.objects}
    culprits = {n for n in re.findall(r"[A-Za-z0-9_.\-]+", why) if n in here} - set(goals)
    goals.update({n: known[n] for n in culprits if n in known})
    goals.update({n: Pose2D(*p) for n, p in here.items() if n not in goals and n in known})
    fake = dataclasses.replace(
        instance,
        objects=tuple(ObjectSpec(n, sizes[n], Pose2D(*here[n]), g) for n, g in goals.items()),
    )
    mini, moved = continuation_instance(fake, here, sizes, config.seed, frozenset(culprits))
    head = head_at(plan, begin)
    q0 = head.q[-1]
    restart = PlanState(float(head.t[-1]), q0, {}, here)
    start = start_configuration(
        _home(world), q0, {a: scene.layout.slice(a) for a in scene.arm_names}
    )
    r = rearrangement_problem(mini, world.ctx, config=config, planner=world.planner, start=start)
    items: list[MotionSegment | GripperEvent] = []
    if any(o.start != o.goal for o in mini.objects):
        solution = solve_rearrangement(r, prove=False)
        if solution.plan is None:
            return None
        items = timeline(solution.plan, task_records(solution), decoder_of(r))
    sizes_here = {n: sizes[n] for n in here}
    middle = build_plan_file(scene, instance.name, here, sizes_here, items, {},
                             gripper_time=config.gripper_time, q_start=q0)  # fmt: skip
    nxt = next((e.t for e in plan.events if e.t >= task.end - 1e-9 and e.type == "grasp"), None)
    if nxt is None:
        return splice(head, middle), moved, restart
    join = cut_at(plan, nxt)
    grasping = {e.arm for e in plan.events if abs(e.t - join.t) < 1e-9}
    acted = _last_actors(items)
    request = MotionRequest(
        middle.q[-1], plan.q[join.index],
        {n: _box(p, sizes[n]) for n, p in middle.final_poses.items()}, {},
        tuple(a in acted for a in scene.arm_names),
        tuple(a in grasping for a in scene.arm_names),
    )  # fmt: skip
    result = plan_dual_motion(world.planner, request)
    if not result.success or result.trajectory is None:
        return None
    traj = result.trajectory
    items.append(MotionSegment(traj.t, traj.q, result.level or "", (), "rejoin"))
    middle = build_plan_file(scene, instance.name, here, sizes_here, items, {},
                             gripper_time=config.gripper_time, q_start=q0)  # fmt: skip
    return splice(splice(head, middle), tail(plan, join)), moved, restart


def _append_task(
    world: PlanningWorld, config: PlannerConfig, instance: Instance, plan: PlanFile,
    sizes: Mapping[str, tuple[float, float, float]],
) -> tuple[PlanFile, tuple[str, ...], PlanState] | None:  # fmt: skip
    """``plan`` followed by one more task that brings the objects it leaves off their goals
    there (an object at its goal nudged off it, which no task of the old plan touches), and
    the state where that task begins; the added objects in the way are moved away."""
    scene = world.ctx.scene
    here = dict(plan.final_poses)
    mini, moved = continuation_instance(instance, here, sizes, config.seed)
    if all(o.start == o.goal for o in mini.objects):
        return None  # nothing off its goal: the violation is another one
    q0 = plan.q[-1]
    start = start_configuration(
        _home(world), q0, {a: scene.layout.slice(a) for a in scene.arm_names}
    )
    r = rearrangement_problem(mini, world.ctx, config=config, planner=world.planner, start=start)
    solution = solve_rearrangement(r, prove=False)
    if solution.plan is None:
        return None
    items = timeline(solution.plan, task_records(solution), decoder_of(r))
    more = build_plan_file(scene, instance.name, here, {n: sizes[n] for n in here}, items, {},
                           gripper_time=config.gripper_time, q_start=q0)  # fmt: skip
    end = PlanState(float(plan.t[-1]), q0, {}, here)
    return splice(plan, more), moved, end


def _last_actors(items: list[MotionSegment | GripperEvent]) -> set[str]:
    """The arms whose gripper acted after the last motion of ``items``."""
    out: set[str] = set()
    for item in items:
        if isinstance(item, MotionSegment):
            out.clear()
        else:
            out.add(item.arm)
    return out


def _placements(
    plan: PlanFile, task: Task, kins: Mapping[str, ArmKinematics], layout: ArmLayout
) -> dict[str, Pose3]:
    """Where ``task`` places its objects in ``plan`` (forward kinematics at the releases)."""
    out: dict[str, Pose3] = {}
    for e in plan.events:
        if e.type != "release" or not task.start <= e.t < task.end:
            continue
        q = np.array([np.interp(e.t, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])])
        T = kins[e.arm].fk_tcp(layout.part(q, e.arm)) @ e.T_tcp_object
        out[e.object] = (float(T[0, 3]), float(T[1, 3]), float(np.arctan2(T[1, 0], T[0, 0])))
    return out


def _home(world: PlanningWorld) -> CellConf:
    ctx = world.ctx
    return CellConf(*(ArmConf(a, tuple(float(x) for x in ctx.home(a))) for a in ctx.arm_names))


def _box(p: tuple[float, ...], size: tuple[float, float, float]) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(p[0], p[1], size[2] / 2.0, p[2]), size)
