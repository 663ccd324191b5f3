"""How a rearrangement is solved: ``solve(problem, algorithm="sdar")`` with its configuration.

:func:`solve_rearrangement` is the same call a user makes with
``solve(r.problem, algorithm="sdar", task_planner=..., sdar_options=r.config.sdar_options())``,
so both entry points plan alike; before it, the quick infeasibility proofs of
:mod:`streams.feasibility` run (well under a second for 24 objects): when they prove the
instance unsolvable, the solution says ``infeasible`` at once, naming the stuck objects and
what their grasps hit (at the planner's IK clearance; the diagnosis says when no valid plan
exists at all).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable

from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.problem import Rearrangement, table_plane
from sdar_tamp.arguments import MAX_TIME
from solvers.solution import Solution, Status
from solvers.solve import solve
from streams.feasibility import prove_unplannable


def solve_rearrangement(
    rearrangement: Rearrangement,
    task_planner: str | None = None,
    max_time: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    *,
    config: PlannerConfig | None = None,
    prove: bool = True,
) -> Solution:
    """Solve with SDAR-M over the task planner (``sdar`` or ``baseline``) within ``max_time``
    [s] (> 0, ``inf`` for no limit, checked as by :func:`solvers.solve.solve`);
    ``progress(done, total)`` is called before every step and at the end.

    The configuration is ``config`` or the one the rearrangement was built with;
    ``task_planner`` and ``max_time``, when given, replace its fields. The motion planner
    is the problem's (its streams are built for it). ``prove``: run the infeasibility proofs
    first (their time is ``statistics["proof_time"]`` [s], part of ``planning_time``).

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
    started = time.perf_counter()
    proof = (
        prove_unplannable(rearrangement.ctx, rearrangement.instance, run.grasps) if prove else None
    )
    proof_time = time.perf_counter() - started if prove else 0.0
    if proof is not None:
        figures = {"planning_time": proof_time, "proof_time": proof_time}
        return Solution(None, status=Status.INFEASIBLE, statistics=figures, diagnosis=proof.lines())
    solution = solve(
        rearrangement.problem,
        algorithm="sdar",
        task_planner=run.task_planner,
        max_time=run.max_time,
        sdar_options=dataclasses.replace(
            run.sdar_options(progress),
            plane=table_plane(rearrangement.ctx),
            home=None if rearrangement.start is None else rearrangement.home,
        ),
        verbose=False,
    )
    if not prove:
        return solution
    stats = dict(solution.statistics)
    stats["proof_time"] = proof_time
    stats["planning_time"] = float(stats.get("planning_time", 0.0)) + proof_time
    return dataclasses.replace(solution, statistics=stats)
