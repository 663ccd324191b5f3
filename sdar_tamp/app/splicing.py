"""Pieces of plans joined in time, and replayed from a time other than zero
(:mod:`sdar_tamp.app.replanning`, :mod:`sdar_tamp.app.repair`).

A piece is a :class:`~sdar_tamp.plan_file.PlanFile` from ``t = 0`` that starts where the
previous one ends; :func:`splice` shifts it after the previous. :func:`walk_from` is the
validator's walk (:class:`~sdar_tamp.replay_walk.ReplayWalk`) begun at a known state, so that a
continuation is checked without replaying what is already checked.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from sdar_tamp.plan_file import GRIPPER_DWELL, PlanFile
from sdar_tamp.plan_rules import STILL_TOL, TIME_TOL, check_timeline
from sdar_tamp.plan_state import Cut, PlanState, prefix_plan, shift_steps
from sdar_tamp.replay_walk import ReplayWalk
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

Pose3 = tuple[float, float, float]


def splice(first: PlanFile, then: PlanFile) -> PlanFile:
    """``then`` (from ``t = 0`` at ``first``'s last configuration) appended after ``first``:
    times, events and steps shifted by ``first``'s duration; ``then``'s ``final_poses``;
    the execution time, steps and actions of the whole; ``first``'s observations."""
    dt = float(first.t[-1])
    t = np.concatenate([first.t, then.t[1:] + dt])
    q = np.concatenate([first.q, then.q[1:]])
    events = first.events + tuple(dataclasses.replace(e, t=e.t + dt) for e in then.events)
    steps = first.steps + shift_steps(then.steps, dt)
    metrics = then.metrics.updated(
        {"execution_time": float(t[-1]), "steps": len(steps),
         "actions": sum(e.type == "release" for e in events)}
    )  # fmt: skip
    return PlanFile(
        first.instance, first.arms, t, q, events, dict(then.final_poses), metrics, steps,
        first.observations,
    )  # fmt: skip


def tail(plan: PlanFile, cut: Cut) -> PlanFile:
    """``plan`` from ``cut`` on, shifted to start at ``t = 0`` (the events of the cut's
    instant included); no observations."""
    return dataclasses.replace(
        plan,
        t=plan.t[cut.index :] - cut.t,
        q=plan.q[cut.index :],
        events=tuple(dataclasses.replace(e, t=e.t - cut.t) for e in plan.events[cut.events :]),
        steps=shift_steps(tuple(s for s in plan.steps if s.t_start >= cut.t - 1e-9), -cut.t),
        observations=(),
    )


def cut_at(plan: PlanFile, t: float) -> Cut:
    """The cut at the sample at or after ``t`` [s] (the events before it counted)."""
    index = min(int(np.searchsorted(plan.t, t - 1e-9)), len(plan.t) - 1)
    at = float(plan.t[index])
    return Cut(index, at, sum(e.t < at - 1e-9 for e in plan.events))


def head_at(plan: PlanFile, begin: Cut) -> PlanFile:
    """``plan`` up to ``begin``, where a continuation starts: cut there when the plan
    already stands still over the sample spacing before it with every gripper dwell over (the
    end of a hold or of a dwell: a new motion may start at once), else with a still hold after
    it (:func:`~sdar_tamp.plan_state.prefix_plan`)."""
    i = begin.index
    events = plan.events[: begin.events]
    dwells_over = all(e.t + GRIPPER_DWELL <= begin.t + TIME_TOL for e in events)
    if i == 0 or not dwells_over or np.abs(plan.q[i] - plan.q[i - 1]).max() > STILL_TOL:
        return prefix_plan(plan, begin)
    head = prefix_plan(plan, begin)  # its events, steps and observations up to the cut
    return dataclasses.replace(head, t=plan.t[: i + 1], q=plan.q[: i + 1])


def walk_from(
    instance: Instance, plan: PlanFile, scene: Scene, kins: Mapping[str, ArmKinematics],
    world: CollisionWorld, state: PlanState,
) -> ReplayWalk:  # fmt: skip
    """The validator's walk of ``plan``, begun at ``state.t`` in ``state`` (walk it with
    ``walk(t_stop, state.t)``)."""
    for arm in scene.arm_names:
        if world.held_by(arm) is not None:
            world.detach(arm)
    walk = ReplayWalk(instance, plan, scene, 0.005, dict(kins), world)
    grips: dict[str, FloatArray] = {}
    for e in plan.events:
        if e.t >= state.t:
            break
        if e.type == "grasp":
            grips[e.arm] = e.T_tcp_object
    walk.start_from(state.resting, state.held, state.q, grips)
    return walk


def final_poses(walk: ReplayWalk, plan: PlanFile, t_from: float) -> dict[str, Pose3]:
    """Where the objects end: the events of ``plan`` from ``t_from`` [s] followed by forward
    kinematics (as the plan builder places releases), from the arrangement ``walk`` begins
    in."""
    resting = dict(walk.rest)
    for e in plan.events:
        if e.t < t_from:
            continue
        if e.type == "grasp":
            resting.pop(e.object, None)
            continue
        q = np.array([np.interp(e.t, plan.t, plan.q[:, j]) for j in range(plan.q.shape[1])])
        T = walk.tcp(e.arm, q) @ e.T_tcp_object
        resting[e.object] = (float(T[0, 3]), float(T[1, 3]), float(np.arctan2(T[1, 0], T[0, 0])))
    return {n: (float(p[0]), float(p[1]), float(p[2])) for n, p in resting.items()}


def check_from(
    instance: Instance, plan: PlanFile, scene: Scene, kins: Mapping[str, ArmKinematics],
    world: CollisionWorld, state: PlanState,
) -> tuple[PlanFile, float | None, str]:  # fmt: skip
    """``plan`` with its ``final_poses`` computed from ``state`` on, and its replay from
    ``state.t`` to the end: the time and text of the first violation (None: valid)."""
    limit = check_timeline(plan, scene)
    if limit is not None:
        return plan, limit.t, f"{limit.kind}: {limit.message}"
    walk = walk_from(instance, plan, scene, kins, world, state)
    plan = dataclasses.replace(plan, final_poses=final_poses(walk, plan, state.t))
    walk.plan = plan
    found = walk.walk(np.inf, state.t)
    if found is None:
        return plan, None, ""
    return plan, found.t, f"{found.kind}: {found.message}"
