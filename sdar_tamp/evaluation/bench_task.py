"""One benchmark run as a worker solves it: the task sent to the worker and its answer.

:func:`run_task` is the function the backends run (in a worker process or a Ray task). Every
worker keeps one :class:`~sdar_tamp.app.cache.PlannerCache`, so it builds the motion planner
once, and the task planner's geometry-free counts once per instance and planner.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from sdar_tamp.evaluation.payload import InstanceFiles, unpack
from sdar_tamp.evaluation.records import BenchRow, RunAnswer
from sdar_tamp.evaluation.results import Combination
from sdar_tamp.evaluation.suite import SuiteEntry

if TYPE_CHECKING:
    from sdar_tamp.app.abstract import AbstractFigures
    from sdar_tamp.app.cache import PlannerCache

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class BenchTask:
    """One (instance, combination) to solve with ``time_limit`` [s] and ``seed``."""

    entry: SuiteEntry
    combo: Combination
    time_limit: float
    seed: int
    files: InstanceFiles | None = None  # the instance as text, for a machine without the suite
    scene: Path | None = None  # a scene file (cell) replacing the instance's own


@functools.cache
def _worker_cache() -> PlannerCache:
    """Per worker process: the world and motion planner kept between runs."""
    from sdar_tamp.app.cache import PlannerCache

    return PlannerCache()


@functools.cache
def _abstract_figures(path: Path, task_planner: str, scene: Path | None) -> AbstractFigures:
    """The task planner's geometry-free counts, once per worker, instance, planner and cell:
    for the arms of ``scene`` where the run replaces the instance's own cell."""
    from sdar_tamp.app.abstract import abstract_figures
    from sdar_tamp.world.scene import load_scene

    arms = None if scene is None else len(load_scene(scene).arms)
    return abstract_figures(path, task_planner, arms)


def task_row(task: BenchTask, status: str, diagnosis: str) -> BenchRow:
    """The row of a run that did not succeed: the columns known before the run, ``status``
    and ``diagnosis``."""
    e, c = task.entry, task.combo
    return BenchRow(
        instance=e.name, family=e.family, objects=e.objects, combination=c.id,
        task_planner=c.task_planner, motion_planner=c.motion_planner, seed=task.seed,
        time_limit_s=task.time_limit, success=False, status=status, valid=False,
        diagnosis=diagnosis,
    )  # fmt: skip


def run_task(task: BenchTask) -> RunAnswer:
    """One solve in a worker: the CSV row, the per-step planning times and the plan."""
    from sdar_tamp.app.pipeline import solve_instance

    e, c = task.entry, task.combo
    path = e.path if task.files is None else unpack(task.files)
    abstract = _abstract_figures(path, c.task_planner, task.scene)
    start = time.perf_counter()
    try:
        outcome = solve_instance(
            path, time_limit=task.time_limit, seed=task.seed, task_planner=c.task_planner,
            motion_planner=c.motion_planner, execution=c.execution, cache=_worker_cache(),
            scene=task.scene,
        )  # fmt: skip
    except Exception as error:  # one broken run is recorded as such, not the end of the bench
        log.exception("%s with %s raised", e.name, c.id)
        row = dataclasses.replace(
            task_row(task, "error", repr(error)),
            wall_time_s=time.perf_counter() - start,
            abstract_actions=abstract.actions,
            abstract_buffer_moves=abstract.buffer_moves,
            abstract_steps=abstract.steps,
        )
        return RunAnswer(row)
    f = outcome.figures
    row = dataclasses.replace(
        task_row(task, outcome.status, outcome.diagnosis[0] if outcome.diagnosis else ""),
        success=outcome.success, valid=outcome.valid, violation=outcome.violation,
        planning_time_s=f.planning_time, selection_time_s=f.selection_time,
        motion_time_s=f.motion_time, setup_time_s=f.setup_time,
        wall_time_s=time.perf_counter() - start, abstract_actions=abstract.actions,
        abstract_buffer_moves=abstract.buffer_moves, abstract_steps=abstract.steps,
        bound_s=None if outcome.bound is None else outcome.bound.seconds,
    )  # fmt: skip
    if outcome.plan is None:
        return RunAnswer(row)
    m = outcome.plan.metrics
    row = dataclasses.replace(
        row, actions=m.actions, steps=m.steps, dual_arm_steps=m.dual_arm_steps,
        execution_time_s=m.execution_time, buffer_moves=f.buffer_moves,
        step_time_median_s=f.step_time_median, execution_over_bound=outcome.execution_over_bound,
    )  # fmt: skip
    return RunAnswer(row, tuple(f.step_times), outcome.plan)
