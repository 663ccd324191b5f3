"""``sdar solve``: plan a rearrangement instance, time it, validate it, write the plan file.

:func:`solve_instance` is the one entry point the command line, the demo and the benchmarks
share: instance file -> world -> problem -> SDAR -> plan file -> independent replay.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from sdar_tamp.arguments import SEED, TIME_LIMIT
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.instance import Instance, load_instance


@dataclass(frozen=True)
class SolveOutcome:
    """What one solve produced. ``valid`` is the independent replay's verdict."""

    instance: Instance
    status: str  # solved, infeasible, timeout
    plan: PlanFile | None
    valid: bool
    violation: str
    figures: dict[str, Any] = field(default_factory=dict)
    diagnosis: tuple[str, ...] = ()

    @property
    def success(self) -> bool:
        return self.status == "solved" and self.valid


def solve_instance(
    instance_path: Path,
    *,
    time_limit: float = 60.0,
    seed: int = 0,
    task_planner: str = "sdar",
    motion_planner: str = "sdar",
    progress: Callable[[int, int], None] | None = None,
    shared: dict[str, Any] | None = None,
) -> SolveOutcome:
    """Solve the instance in ``instance_path`` and validate the plan.

    ``time_limit`` [s]: finite and > 0; ``seed``: an integer >= 0 (else ParameterError).

    ``shared``: a dict in which the world and the motion planner are kept between calls with
    the same scene (building the optimiser takes a few seconds; it is reported as
    ``setup_time``, not as planning time).
    """
    from sdar_tamp.rearrangement import (
        MOTION_PLANNERS,
        TASK_PLANNERS,
        plan_file_from_solution,
        rearrangement_problem,
        solve_rearrangement,
        step_times,
    )
    from sdar_tamp.replay import validate_plan
    from streams.context import WorldContext
    from streams.motion import DualMotionPlanner

    time_limit = TIME_LIMIT.check("time_limit", time_limit)
    seed = SEED.check("seed", seed)
    for name, value, choices in (
        ("task_planner", task_planner, TASK_PLANNERS),
        ("motion_planner", motion_planner, MOTION_PLANNERS),
    ):
        if value not in choices:
            raise ParameterError(f"{name} must be one of {', '.join(choices)}; got {value!r}")
    instance = load_instance(instance_path)
    cache = shared if shared is not None else {}
    scene_path = instance.scene_path(instance_path)
    setup_start = time.perf_counter()
    if "ctx" not in cache or cache.get("scene") != scene_path:
        ctx = WorldContext.load(scene_path)
        cache.update(scene=scene_path, ctx=ctx, planner=DualMotionPlanner(ctx))
    setup_time = time.perf_counter() - setup_start
    problem = rearrangement_problem(
        instance, cache["ctx"], seed=seed, motion=motion_planner, planner=cache["planner"]
    )
    solution = solve_rearrangement(problem, task_planner, time_limit, progress)
    figures: dict[str, Any] = {
        "task_planner": task_planner,
        "motion_planner": motion_planner,
        "seed": seed,
        "setup_time": setup_time,
        "optimiser_build_time": cache["planner"].build.build_time,  # CPU [s], in the background
        "optimiser_wait": cache["planner"].build.waited,  # [s] planning waited for the build
        **{k: float(v) for k, v in solution.statistics.items()},
    }
    if solution.plan is None:
        return SolveOutcome(
            instance, solution.status.value, None, False, "no plan", figures,
            tuple(solution.diagnosis),
        )  # fmt: skip
    per_step = step_times(solution)
    totals = [s + m for s, m in per_step]
    levels = Counter(str(a.args[1].level) for a in solution.plan if a.name == "move")
    figures.update(
        step_time_median=statistics.median(totals) if totals else 0.0,
        step_time_max=max(totals, default=0.0),
        step_selection_median=statistics.median(s for s, _ in per_step) if per_step else 0.0,
        step_motion_median=statistics.median(m for _, m in per_step) if per_step else 0.0,
        levels=dict(sorted(levels.items())),
        step_times=per_step,
        buffer_moves=sum(sum(r["to_buffer"]) for r in solution.trace),
    )
    metrics = {
        k: figures[k]
        for k in ("task_planner", "motion_planner", "seed", "step_time_median", "buffer_moves")
    }
    plan = plan_file_from_solution(problem, solution, metrics)
    report = validate_plan(instance, plan, problem.ctx.scene)
    violation = "" if report.ok or report.violation is None else _describe(report.violation)
    return SolveOutcome(instance, "solved", plan, report.ok, violation, figures)


def _describe(violation: Any) -> str:
    return f"t={violation.t:.3f} s: {violation.kind}: {violation.message}"


def format_summary(outcome: SolveOutcome) -> str:
    """A few lines for people: result, actions, steps, times."""
    f = outcome.figures
    head = f"{outcome.instance.name}: {outcome.status}"
    if outcome.plan is None:
        return "\n".join([head, *(f"  {d}" for d in outcome.diagnosis)])
    m = outcome.plan.metrics
    lines = [
        head + (", plan valid" if outcome.valid else f", plan INVALID ({outcome.violation})"),
        f"  actions {m['actions']} ({f['buffer_moves']} to buffers), synchronous steps "
        f"{m['steps']} ({m['dual_arm_steps']} with both arms moving at once)",
        f"  execution time {float(m['execution_time']):.2f} s",
        f"  planning time {f['planning_time']:.2f} s: selection/IK {f['selection_time']:.2f} s, "
        f"motion {f['motion_time']:.2f} s (setup {f['setup_time']:.2f} s not counted; "
        f"optimiser built in the background, waited for {f['optimiser_wait']:.2f} s)",
        f"  per step: median {f['step_time_median']:.3f} s (selection "
        f"{f['step_selection_median']:.3f} s, motion {f['step_motion_median']:.3f} s), "
        f"max {f['step_time_max']:.3f} s",
        "  motion levels: " + ", ".join(f"{k} {v}" for k, v in f["levels"].items()),
    ]
    return "\n".join(lines)


class ProgressBar:
    """A ``progress(done, total)`` callback drawing a tqdm bar of the objects at their goals.
    The bar appears at once and its clock ticks every ``tick`` [s] between steps (set-up,
    long steps, validation), so no wait passes silently."""

    def __init__(self, label: str, stream: TextIO = sys.stderr, tick: float = 0.5) -> None:
        import threading

        from tqdm import tqdm

        self.label = label
        self.stream = stream
        self._bar: Any = tqdm(total=None, desc=label, unit="obj", file=stream)
        self._stop = threading.Event()
        self._ticker = threading.Thread(target=self._tick, args=(tick,), daemon=True)
        self._ticker.start()

    def _tick(self, tick: float) -> None:
        while not self._stop.wait(tick):
            self._bar.refresh()

    def __call__(self, done: int, total: int) -> None:
        if self._bar.total != total:
            self._bar.total = total
        self._bar.update(done - self._bar.n)

    def close(self) -> None:
        self._stop.set()
        self._ticker.join()
        self._bar.close()
