"""How a rearrangement is solved: ``solve(problem, algorithm="sdar")`` with its configuration.

:func:`solve_rearrangement` is the same call a user makes with
``solve(r.problem, algorithm="sdar", task_planner=..., sdar_options=r.config.sdar_options())``,
so both entry points plan alike.
"""

from __future__ import annotations

from collections.abc import Callable

from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.problem import Rearrangement
from sdar_tamp.arguments import MAX_TIME
from solvers.solution import Solution
from solvers.solve import solve


def solve_rearrangement(
    rearrangement: Rearrangement,
    task_planner: str | None = None,
    max_time: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    *,
    config: PlannerConfig | None = None,
) -> Solution:
    """Solve with SDAR-M over the task planner (``sdar`` or ``baseline``) within ``max_time``
    [s] (> 0, ``inf`` for no limit, checked as by :func:`solvers.solve.solve`);
    ``progress(done, total)`` is called before every step and at the end.

    The configuration is ``config`` or the one the rearrangement was built with;
    ``task_planner`` and ``max_time``, when given, replace its fields. The motion planner
    is the problem's (its streams are built for it).

    Raises:
        ParameterError: ``max_time`` out of range or an unknown ``task_planner``.
    """
    if max_time is not None:
        MAX_TIME.check("max_time", max_time)
    base = config or rearrangement.config
    run = base.replace(
        task_planner=task_planner,
        max_time=max_time,
        motion_planner=rearrangement.config.motion_planner,
    )
    return solve(
        rearrangement.problem,
        algorithm="sdar",
        task_planner=run.task_planner,
        max_time=run.max_time,
        sdar_options=run.sdar_options(progress),
        verbose=False,
    )
