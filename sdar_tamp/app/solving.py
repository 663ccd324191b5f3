"""How a rearrangement is solved: ``solve(problem, algorithm="sdar")`` with its configuration.

:func:`solve_rearrangement` is the same call a user makes with
``solve(r.problem, algorithm="sdar", task_planner=..., sdar_options=r.config.sdar_options())``,
so both entry points plan alike; :func:`rearrangement_steps` runs the same solver
(:func:`solvers.solve.sdar_solver`, which ``solve`` builds it with) one step at a time.
Before either, the quick infeasibility proofs of :mod:`streams.feasibility` run (well under
a second for 24 objects): when they prove the instance unsolvable, the solution says
``infeasible`` at once, naming the stuck objects and what their grasps hit (at the
planner's IK clearance; the diagnosis says when no valid plan exists at all).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Generator

from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.problem import Rearrangement, table_plane
from sdar_tamp.arguments import MAX_TIME
from solvers.sdar.options import SdarOptions
from solvers.sdar.report import PlannedStep
from solvers.solution import Solution, Status
from solvers.solve import sdar_solver, solve
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
    run = _run_config(rearrangement, task_planner, max_time, config)
    proof, proof_time = _proof(rearrangement, run, prove)
    if proof is not None:
        return proof
    solution = solve(
        rearrangement.problem,
        algorithm="sdar",
        task_planner=run.task_planner,
        max_time=run.max_time,
        sdar_options=_sdar_options(rearrangement, run, progress),
        verbose=False,
    )
    return _with_proof_time(solution, proof_time) if prove else solution


def rearrangement_steps(
    rearrangement: Rearrangement,
    task_planner: str | None = None,
    max_time: float | None = None,
    progress: Callable[[int, int], None] | None = None,
    *,
    config: PlannerConfig | None = None,
    prove: bool = True,
) -> Generator[PlannedStep, None, Solution]:
    """:func:`solve_rearrangement` (same arguments) one step at a time: the proofs, then the
    solver that ``solve(r.problem, algorithm="sdar", ...)`` runs
    (:func:`solvers.solve.sdar_solver`), each executed decision yielded as soon as it is
    planned (:meth:`~solvers.sdar.solver.SdarSolver.steps`); returns the solution.

    Raises:
        ParameterError: ``max_time`` out of range or an unknown ``task_planner``.
    """
    run = _run_config(rearrangement, task_planner, max_time, config)
    proof, proof_time = _proof(rearrangement, run, prove)
    if proof is not None:
        return proof
    options = _sdar_options(rearrangement, run, progress)
    solver = sdar_solver(rearrangement.problem, run.task_planner, run.max_time, None, options)
    solution = yield from solver.steps()
    return _with_proof_time(solution, proof_time) if prove else solution


def _run_config(
    rearrangement: Rearrangement,
    task_planner: str | None,
    max_time: float | None,
    config: PlannerConfig | None,
) -> PlannerConfig:
    if max_time is not None:
        MAX_TIME.check("max_time", max_time)
    base = config or rearrangement.config
    return base.replace(
        task_planner=task_planner,
        max_time=max_time,
        motion_planner=rearrangement.config.motion_planner,
    )


def _sdar_options(
    rearrangement: Rearrangement,
    run: PlannerConfig,
    progress: Callable[[int, int], None] | None,
) -> SdarOptions:
    return dataclasses.replace(
        run.sdar_options(progress),
        plane=table_plane(rearrangement.ctx),
        home=None if rearrangement.start is None else rearrangement.home,
    )


def _proof(
    rearrangement: Rearrangement, run: PlannerConfig, prove: bool
) -> tuple[Solution | None, float]:
    """The infeasibility proofs (with ``prove``): an ``infeasible`` solution when they prove
    it, and their time [s]."""
    if not prove:
        return None, 0.0
    started = time.perf_counter()
    proof = prove_unplannable(rearrangement.ctx, rearrangement.instance, run.grasps)
    proof_time = time.perf_counter() - started
    if proof is None:
        return None, proof_time
    figures = {"planning_time": proof_time, "proof_time": proof_time}
    solution = Solution(None, status=Status.INFEASIBLE, statistics=figures, diagnosis=proof.lines())
    return solution, proof_time


def _with_proof_time(solution: Solution, proof_time: float) -> Solution:
    stats = dict(solution.statistics)
    stats["proof_time"] = proof_time
    stats["planning_time"] = float(stats.get("planning_time", 0.0)) + proof_time
    return dataclasses.replace(solution, statistics=stats)
