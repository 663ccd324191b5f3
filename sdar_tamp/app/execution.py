"""How a synchronous plan is executed asynchronously: the scheduler's options, with each arm's
motions re-timed by the same time-optimal path timing the motion planner uses
(:func:`streams.motion.timing.time_parameterize`) and the same slow tool travel at gripper
events."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.replay import ReplayReport, validate_plan
from sdar_tamp.schedule import Schedule, ScheduleOptions, schedule_async
from sdar_tamp.schedule.retiming import PathTimer
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray
from streams.motion.shape import ShapeOptions
from streams.motion.timing import time_parameterize

_log = logging.getLogger(__name__)


def path_timer(safety: float) -> PathTimer:
    """The motion planner's time-optimal path timing at ``safety`` (the scene's
    ``velocity_safety``, in (0, 1]), as the scheduler's :data:`PathTimer`."""

    def timer(
        path: FloatArray,
        v_max: FloatArray,
        a_max: FloatArray,
        path_speed: FloatArray | None,
        dt: float,
    ) -> tuple[FloatArray, FloatArray]:
        traj = time_parameterize(path, v_max, a_max, dt=dt, safety=safety, path_speed=path_speed)
        return traj.t, traj.q

    return timer


def execution_options(scene: Scene, shape: ShapeOptions | None = None) -> ScheduleOptions:
    """The scheduler's options for plans of ``scene`` whose motions have ``shape`` (default:
    the motion planner's default shape)."""
    shape = shape or ShapeOptions()
    return ScheduleOptions(
        timer=path_timer(scene.velocity_safety),
        straight=shape.straight,
        grasp_speed=shape.grasp_speed,
    )


def schedule_plan(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    shape: ShapeOptions | None = None,
    options: ScheduleOptions | None = None,
) -> Schedule:
    """``plan`` re-scheduled for asynchronous execution (``options``: default
    :func:`execution_options`), and the result replayed by the independent validator: a
    schedule it rejects is dropped for the synchronous plan (and logged), so the plan returned
    is never longer than ``plan`` and valid whenever ``plan`` is."""
    return _checked_schedule(plan, instance, scene, shape, options, None)[0]


def schedule_and_validate(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    shape: ShapeOptions | None = None,
    options: ScheduleOptions | None = None,
    stage: Callable[[str], None] | None = None,
) -> tuple[Schedule, ReplayReport]:
    """:func:`schedule_plan`, and the independent replay's report on the plan it returns: the
    schedule's own replay when the schedule is kept, else a replay of ``plan`` (each plan is
    replayed once). ``stage("validating")`` is called when the first replay starts."""
    result, report = _checked_schedule(plan, instance, scene, shape, options, stage)
    return result, report or validate_plan(instance, result.plan, scene)


def _checked_schedule(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    shape: ShapeOptions | None,
    options: ScheduleOptions | None,
    stage: Callable[[str], None] | None,
) -> tuple[Schedule, ReplayReport | None]:
    """The schedule with the replay's report when the schedule is kept; the synchronous plan
    and None (not replayed) when there is none or the replay rejects it."""
    options = options or execution_options(scene, shape)
    result = schedule_async(plan, instance, scene, options)
    if stage is not None:
        stage("validating")
    if not result.asynchronous:
        return result, None
    report = validate_plan(instance, result.plan, scene)
    if report.ok:
        return result, report
    why = "the replay rejects the schedule" + (
        f" at t={report.violation.t:.3f} s: {report.violation.kind}: {report.violation.message}"
        if report.violation is not None
        else ""
    )
    _log.warning("%s: %s; the synchronous plan is kept", instance.name, why)
    return dataclasses.replace(result, plan=plan, asynchronous=False, reason=why), None
