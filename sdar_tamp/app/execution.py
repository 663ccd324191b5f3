"""How a synchronous plan is executed asynchronously: the scheduler's options, with each arm's
motions re-timed by the same time-optimal path timing the motion planner uses
(:func:`streams.motion.timing.time_parameterize`) and the same slow tool travel at gripper
events.

Three schedules (:data:`SCHEDULERS`): ``"retime"``, the synchronous plan's steps re-timed
(:func:`sdar_tamp.schedule.schedule_async`); ``"timelines"``, one timeline per arm by
prioritised planning in time (:func:`sdar_tamp.schedule.timelines.schedule_timelines`), which
also computes the re-timing and keeps the shorter of the two; and ``"assigned"``, the plan's
moves assigned anew to whichever arm is free, with motions planned for it by the streams
(:func:`sdar_tamp.schedule.assignment.schedule_assigned`,
:class:`sdar_tamp.app.move_planning.StreamMovePlanner`), which also computes the other two and
keeps the shortest. Either way the result is replayed by the independent validator and the
synchronous plan kept when the replay rejects every schedule."""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.replay import ReplayReport, validate_plan
from sdar_tamp.schedule import Schedule, ScheduleOptions, schedule_async
from sdar_tamp.schedule.assignment import schedule_assigned
from sdar_tamp.schedule.retiming import PathTimer
from sdar_tamp.schedule.timelines import schedule_timelines
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray
from streams.motion.shape import ShapeOptions
from streams.motion.timing import time_parameterize

_log = logging.getLogger(__name__)

#: The asynchronous schedules: the synchronous steps re-timed, one timeline per arm, or the
#: moves assigned anew to whichever arm is free.
SCHEDULERS = ("retime", "timelines", "assigned")


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
    scheduler: str = "retime",
) -> Schedule:
    """``plan`` re-scheduled for asynchronous execution by ``scheduler`` (one of
    :data:`SCHEDULERS`; ``options``: default :func:`execution_options`), and the result
    replayed by the independent validator: a schedule it rejects is dropped for the
    synchronous plan (and logged), so the plan returned is never longer than ``plan`` and valid
    whenever ``plan`` is."""
    return _checked_schedule(plan, instance, scene, shape, options, None, scheduler)[0]


def schedule_and_validate(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    shape: ShapeOptions | None = None,
    options: ScheduleOptions | None = None,
    stage: Callable[[str], None] | None = None,
    scheduler: str = "retime",
) -> tuple[Schedule, ReplayReport]:
    """:func:`schedule_plan`, and the independent replay's report on the plan it returns: the
    schedule's own replay when the schedule is kept, else a replay of ``plan`` (each plan is
    replayed once). ``stage("validating")`` is called when the first replay starts."""
    result, report = _checked_schedule(plan, instance, scene, shape, options, stage, scheduler)
    return result, report or validate_plan(instance, result.plan, scene)


def _checked_schedule(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    shape: ShapeOptions | None,
    options: ScheduleOptions | None,
    stage: Callable[[str], None] | None,
    scheduler: str,
) -> tuple[Schedule, ReplayReport | None]:
    """The schedule with the replay's report when the schedule is kept; the synchronous plan
    and None (not replayed) when there is none or the replay rejects it. With
    ``"timelines"``, the shorter of the two schedules that the replay accepts; with
    ``"assigned"``, the shortest of the three."""
    if scheduler not in SCHEDULERS:
        raise ParameterError(f"scheduler must be one of {', '.join(SCHEDULERS)}; got {scheduler!r}")
    options = options or execution_options(scene, shape)
    candidates = [schedule_async(plan, instance, scene, options)]
    if scheduler in ("timelines", "assigned"):
        candidates.insert(0, schedule_timelines(plan, instance, scene, options))
    if scheduler == "assigned":
        from sdar_tamp.app.move_planning import StreamMovePlanner

        planner = StreamMovePlanner(instance, scene)
        candidates.insert(0, schedule_assigned(plan, instance, scene, options, planner))
    if stage is not None:
        stage("validating")
    kept = [c for c in candidates if c.asynchronous]
    kept.sort(key=lambda c: c.plan.duration)
    result = candidates[-1]
    for result in kept:
        report = validate_plan(instance, result.plan, scene)
        if report.ok:
            return result, report
        _log.warning("%s: %s", instance.name, _rejected(report))
    if not kept:
        return candidates[-1], None
    why = _rejected(report)
    _log.warning("%s: %s; the synchronous plan is kept", instance.name, why)
    return dataclasses.replace(result, plan=plan, asynchronous=False, reason=why), None


def _rejected(report: ReplayReport) -> str:
    return "the replay rejects the schedule" + (
        f" at t={report.violation.t:.3f} s: {report.violation.kind}: {report.violation.message}"
        if report.violation is not None
        else ""
    )
