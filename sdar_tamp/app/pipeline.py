"""``sdar solve``: plan a rearrangement instance, time it, validate it, build the plan file.

:func:`solve_instance` is the one pipeline the command line, the demo and the benchmarks
share: instance file -> world -> problem -> SDAR -> plan file (re-scheduled per arm with
``execution="async"``) -> independent replay.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from sdar_tamp.app.bound import run_bound
from sdar_tamp.app.cache import PlannerCache, PlanningWorld
from sdar_tamp.app.config import (
    EXECUTIONS,
    MOTION_PLANNERS,
    TASK_PLANNERS,
    PlannerConfig,
    check_choice,
)
from sdar_tamp.app.execution import schedule_and_validate
from sdar_tamp.app.plan_export import (
    decoder_of,
    motion_levels,
    plan_file_from_solution,
    plan_metrics,
)
from sdar_tamp.app.problem import Rearrangement, rearrangement_problem
from sdar_tamp.app.records import RunFigures, SolveOutcome, task_records
from sdar_tamp.app.solving import solve_rearrangement
from sdar_tamp.arguments import SEED, TIME_LIMIT
from sdar_tamp.plan_building import PlanBuilder
from sdar_tamp.plan_rules import Violation
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import Instance, load_instance
from solvers.solution import Solution


def solve_instance(
    instance_path: Path,
    config: PlannerConfig | None = None,
    *,
    time_limit: float | None = None,
    seed: int | None = None,
    task_planner: str | None = None,
    motion_planner: str | None = None,
    execution: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    stage: Callable[[str], None] | None = None,
    cache: PlannerCache | None = None,
    scene: Path | None = None,
) -> SolveOutcome:
    """Solve the instance in ``instance_path`` and validate the plan.

    ``config``: the planner configuration (default: :class:`PlannerConfig`, 60 s); the
    keywords, when given, replace its fields: ``time_limit`` [s] (finite and > 0), ``seed``
    (an integer >= 0), ``task_planner``, ``motion_planner``, ``execution``. Values are checked
    before the instance is read.

    ``progress(done, total)``: called as objects reach their goals; ``stage(text)``: called
    when the work after planning starts (``"scheduling"`` for asynchronous execution, then
    ``"validating"``).

    ``scene``: a scene file (cell) that replaces the instance's (its objects are then checked
    against that cell's grippers).

    ``cache``: keeps the world and the motion planner between calls with the same scene
    (building the optimiser takes a few tenths of a second; it is reported as ``setup_time``, not as
    planning time).

    Raises:
        ParameterError: a value out of range or an unknown planner name.
    """
    prepared = prepare_solve(
        instance_path,
        config,
        time_limit=time_limit,
        seed=seed,
        task_planner=task_planner,
        motion_planner=motion_planner,
        execution=execution,
        cache=cache,
        scene=scene,
    )
    solution = solve_rearrangement(prepared.rearrangement, progress=progress)
    return finish_solve(prepared, solution, stage)


@dataclass(frozen=True)
class PreparedSolve:
    """An instance ready to plan: the configuration, the loaded instance, the world (with the
    time it took) and the rearrangement problem."""

    config: PlannerConfig
    instance: Instance
    world: PlanningWorld
    rearrangement: Rearrangement


def prepare_solve(
    instance_path: Path,
    config: PlannerConfig | None = None,
    *,
    time_limit: float | None = None,
    seed: int | None = None,
    task_planner: str | None = None,
    motion_planner: str | None = None,
    execution: str | None = None,
    cache: PlannerCache | None = None,
    scene: Path | None = None,
    defer_build: bool = False,
) -> PreparedSolve:
    """The first half of :func:`solve_instance` (same arguments): the values checked, the
    instance read, the world built (or taken from ``cache``; ``defer_build``: see
    :meth:`PlannerCache.world`), the problem made.

    Raises:
        ParameterError: a value out of range or an unknown planner name.
    """
    if time_limit is not None:
        TIME_LIMIT.check("time_limit", time_limit)
    if seed is not None:
        SEED.check("seed", seed)
    if task_planner is not None:
        check_choice("task_planner", task_planner, TASK_PLANNERS)
    if motion_planner is not None:
        check_choice("motion_planner", motion_planner, MOTION_PLANNERS)
    if execution is not None:
        check_choice("execution", execution, EXECUTIONS)
    config = (config or PlannerConfig()).replace(
        max_time=time_limit,
        seed=seed,
        task_planner=task_planner,
        motion_planner=motion_planner,
        execution=execution,
    )
    instance = load_instance(instance_path, grasp=None)
    scene_path = Path(scene) if scene is not None else instance.scene_path(Path(instance_path))
    world = (cache or PlannerCache()).world(scene_path, config.trajopt, defer_build)
    instance = load_instance(instance_path, world.ctx.scene.grasp_limits)
    rearrangement = rearrangement_problem(instance, world.ctx, config=config, planner=world.planner)
    return PreparedSolve(config, instance, world, rearrangement)


def finish_solve(
    prepared: PreparedSolve,
    solution: Solution,
    stage: Callable[[str], None] | None = None,
    builder: PlanBuilder | None = None,
) -> SolveOutcome:
    """The second half of :func:`solve_instance`: the figures, the plan file (built from the
    solution, or finished by ``builder`` when its items were added as they were planned), its
    asynchronous schedule (``config.execution``) and the independent replay."""
    config, instance, world = prepared.config, prepared.instance, prepared.world
    rearrangement = prepared.rearrangement
    stats = solution.statistics
    figures = RunFigures(
        task_planner=config.task_planner,
        motion_planner=config.motion_planner,
        seed=config.seed,
        setup_time=world.setup_time,
        optimiser_build_time=world.planner.build.build_time,  # CPU [s], in the background
        optimiser_wait=world.planner.build.waited,  # [s] planning waited for the build
        planning_time=float(stats.get("planning_time", 0.0)),
        selection_time=float(stats.get("selection_time", 0.0)),
        motion_time=float(stats.get("motion_time", 0.0)),
        task_selection_time=float(stats.get("task_selection_time", 0.0)),
        tasks=int(stats.get("tasks", 0)),
    )
    bound = run_bound(rearrangement.ctx, instance, config)
    if solution.plan is None:
        return SolveOutcome(
            instance, solution.status.value, None, False, "no plan", figures,
            tuple(solution.diagnosis), bound,
        )  # fmt: skip
    tasks = task_records(solution)
    figures = dataclasses.replace(
        figures,
        step_times=tuple(step for task in tasks for step in task.step_times()),
        levels=motion_levels(solution.plan, decoder_of(rearrangement)),
        buffer_moves=sum(task.buffer_moves for task in tasks),
    )
    metrics: dict[str, float | int | str] = {
        "task_planner": figures.task_planner,
        "motion_planner": figures.motion_planner,
        "seed": figures.seed,
        "step_time_median": figures.step_time_median,
        "buffer_moves": figures.buffer_moves,
    }
    if builder is None:
        plan = plan_file_from_solution(rearrangement, solution, metrics)
    else:
        plan = builder.finish(instance.name, plan_metrics(solution, metrics))
    if config.execution in ("async", "timelines", "assigned"):
        if stage is not None:
            stage("scheduling")
        started = time.perf_counter()
        schedule, report = schedule_and_validate(
            plan,
            instance,
            rearrangement.ctx.scene,
            world.planner.shape,
            stage=stage,
            scheduler="retime" if config.execution == "async" else config.execution,
        )
        plan = schedule.plan
        figures = dataclasses.replace(figures, schedule_time=time.perf_counter() - started)
    else:
        if stage is not None:
            stage("validating")
        report = validate_plan(instance, plan, rearrangement.ctx.scene)
    violation = "" if report.ok or report.violation is None else describe(report.violation)
    return SolveOutcome(instance, "solved", plan, report.ok, violation, figures, (), bound)


def describe(violation: Violation) -> str:
    """One line: when [s], what kind, what the replay found."""
    return f"t={violation.t:.3f} s: {violation.kind}: {violation.message}"
