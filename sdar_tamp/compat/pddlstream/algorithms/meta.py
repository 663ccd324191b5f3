"""``pddlstream.algorithms.meta``: ``solve`` with PDDLStream's keywords, ``create_parser``.

Every keyword of PDDLStream's ``solve``, ``solve_focused``, ``solve_incremental`` and
``solve_adaptive`` is accepted. Those the core solver acts on are passed on (``planner`` names
such as ``'max-astar'`` or ``'ff-wastar2'`` are mapped by :func:`solvers.solve.parse_planner`,
``max_cost`` bounds the plan cost); the others are noted in the log and do not change the
result (a returned plan is always fully evaluated and checked).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import logging
import math
import time
from collections.abc import Iterable, Mapping
from typing import Any

from sdar_tamp.compat.pddlstream.algorithms.common import Solution as SolutionRecord
from sdar_tamp.compat.pddlstream.algorithms.common import record_solutions
from sdar_tamp.compat.pddlstream.algorithms.constraints import PlanConstraints
from sdar_tamp.compat.pddlstream.language.stream import StreamInfo as PddlstreamStreamInfo
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.options import PlanConstraints as _CorePlanConstraints
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Solution
from solvers.solve import solve as core_solve  # replaced by the runner's --report

__all__ = [
    "ALGORITHMS",
    "DEFAULT_ALGORITHM",
    "FOCUSED_ALGORITHMS",
    "analyze_goal",
    "create_parser",
    "solve",
    "solve_restart",
]

LOG = logging.getLogger(__name__)
INF = math.inf
FOCUSED_ALGORITHMS = ["focused", "binding", "adaptive"]
ALGORITHMS = ["incremental", *FOCUSED_ALGORITHMS]
DEFAULT_ALGORITHM = "adaptive"

#: Keywords accepted for PDDLStream programs that do not change what the core solver does,
#: with the value at which they are silent (anything else is noted in the log).
NOTED_KEYWORDS: dict[str, Any] = {
    "replan_actions": None,
    "max_memory": INF,
    "max_failures": None,
    "max_effort": INF,
    "reorder": True,
    "visualize": False,
    "debug": False,
    "hierarchy": None,
    "temp_dir": None,
    "clean": False,
    "fail_fast": None,
    "bind": None,
    "eager_disabled": None,
    "start_complexity": None,
}


def create_parser(default_algorithm: str = DEFAULT_ALGORITHM) -> argparse.ArgumentParser:
    """PDDLStream's example parser: ``-a/--algorithm`` and ``-u/--unit``."""
    parser = argparse.ArgumentParser()
    parser.add_argument(
        "-a",
        "--algorithm",
        type=str,
        default=default_algorithm,
        choices=ALGORITHMS,
        required=False,
        help="the PDDLStream algorithm to use",
    )
    parser.add_argument("-u", "--unit", action="store_true", help="use unit costs")
    return parser


def _is_silent(name: str, value: Any, silent: Any) -> bool:
    if value is silent or value == silent:
        return True
    return silent is None and (value is None or (isinstance(value, Iterable) and not value))


def _note(name: str, value: Any) -> None:
    silent = NOTED_KEYWORDS[name]
    if _is_silent(name, value, silent):
        return
    LOG.info("solve(%s=%r) is accepted and has no effect here", name, value)


def _constraints(constraints: Any, max_cost: float) -> _CorePlanConstraints | None:
    if constraints is None:
        constraints = PlanConstraints()
    if not isinstance(constraints, _CorePlanConstraints):
        raise ParameterError(
            f"constraints must be a PlanConstraints, got {type(constraints).__name__}"
        )
    result: _CorePlanConstraints = constraints
    if max_cost < result.max_cost:
        result = dataclasses.replace(result, max_cost=max_cost)
    if result.skeletons is None and math.isinf(result.max_cost):
        return None
    return result


def solve(
    problem: PDDLProblem,
    algorithm: str = DEFAULT_ALGORITHM,
    constraints: _CorePlanConstraints | None = None,
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    unit_costs: bool = False,
    success_cost: float = INF,
    max_time: float = INF,
    max_iterations: float = INF,
    initial_complexity: int = 0,
    complexity_step: int = 1,
    max_complexity: float = INF,
    max_skeletons: float | None = INF,
    search_sample_ratio: float | None = 1,
    unit_efforts: bool = False,
    effort_weight: float | None = None,
    verbose: bool = True,
    planner: str = "ff-astar2",
    max_planner_time: float = INF,
    max_cost: float = INF,
    seed: int | None = None,
    **keywords: Any,
) -> Solution:
    """Solve a PDDLStream problem with ``algorithm`` (``incremental``, ``focused``,
    ``binding`` or ``adaptive``); returns ``plan, cost, certificate``.

    Keywords of PDDLStream's ``solve`` and ``solve_*`` that have no counterpart here
    (:data:`NOTED_KEYWORDS`) are accepted and noted in the log.

    Raises:
        ParameterError: an unknown keyword (the message names it), an unknown algorithm or
            planner name (the message lists the valid ones), or a value out of range.
    """
    unknown = sorted(set(keywords) - set(NOTED_KEYWORDS))
    if unknown:
        raise ParameterError(
            f"unknown solve() argument(s): {', '.join(unknown)} (PDDLStream keywords accepted: "
            f"{', '.join(sorted(NOTED_KEYWORDS))})"
        )
    for name, value in keywords.items():
        _note(name, value)
    if algorithm not in ALGORITHMS:
        raise ParameterError(f"algorithm must be one of {', '.join(ALGORITHMS)}; got {algorithm!r}")
    if max_skeletons is None:  # PDDLStream: not adaptive
        max_skeletons = INF
    if search_sample_ratio is None or search_sample_ratio <= 0:
        search_sample_ratio = 1.0
    start = time.perf_counter()
    solution = core_solve(
        problem,
        algorithm=algorithm,
        stream_info=_without_defer_fns(
            _with_default_info(problem, stream_info), keywords.get("replan_actions")
        ),
        constraints=_constraints(constraints, max_cost),
        unit_costs=unit_costs,
        success_cost=success_cost,
        max_time=max_time,
        max_iterations=max_iterations,
        max_skeletons=max_skeletons,
        search_sample_ratio=search_sample_ratio,
        initial_complexity=initial_complexity,
        complexity_step=max(1, complexity_step),
        max_complexity=max_complexity,
        unit_efforts=unit_efforts,
        effort_weight=effort_weight,
        max_planner_time=max_planner_time if max_planner_time > 0 else INF,
        verbose=verbose,
        seed=seed,
        planner=planner,
    )
    plan = getattr(solution, "plan", None)  # a stand-in solver may return anything
    found = (
        [] if plan is None else [SolutionRecord(plan, solution.cost, time.perf_counter() - start)]
    )
    record_solutions(found)
    return solution


def solve_restart(
    problem: PDDLProblem,
    max_time: float = INF,
    max_restarts: int = 0,
    iteration_time: float = INF,
    abort: bool = True,
    **kwargs: Any,
) -> Solution:
    """``solve`` with a fresh start up to ``max_restarts`` times within ``max_time`` [s]."""
    start = time.time()
    solution = Solution(None)
    for _ in range(1 + max_restarts):
        remaining = min(iteration_time, max_time - (time.time() - start))
        if remaining <= 0:
            break
        solution = solve(problem, max_time=remaining, **kwargs)
        if solution.plan is not None or abort:
            break
    return solution


def analyze_goal(*_args: Any, **_kwargs: Any) -> None:
    """PDDLStream's goal analysis (a debugging aid over its internal stream plans). Not
    available: it returns None, as PDDLStream does when it finds nothing to report."""
    LOG.info("analyze_goal is not available; nothing is reported")
    return None


def _with_default_info(
    problem: PDDLProblem, stream_info: Mapping[str, StreamInfo | FunctionInfo] | None
) -> dict[str, StreamInfo | FunctionInfo]:
    """``stream_info`` with PDDLStream's default ``StreamInfo()`` for every stream it omits
    (shared optimistic outputs, refined when a plan uses them)."""
    info = dict(stream_info or {})
    given = {name.lower() for name in info}
    for stream in problem.streams.streams:
        if stream.name.lower() not in given:
            info[stream.name] = PddlstreamStreamInfo()
    return info


def _without_defer_fns(
    info: dict[str, StreamInfo | FunctionInfo], replan_actions: Any
) -> dict[str, StreamInfo | FunctionInfo]:
    """``info`` with every ``defer_fn`` removed, after saying what that changes.

    PDDLStream consults a defer function only for the stream results a plan needs at or after
    the step following its first action named in ``replan_actions`` (they are returned as
    stream actions, unevaluated, for the program to re-plan at that action). Without such
    actions no result is deferred there either, so the functions are dropped silently. With
    them, the plan returned here is evaluated in full instead (noted in the log).
    """
    deferring = sorted(name for name, item in info.items() if _defer_fn(item) is not None)
    if not deferring:
        return info
    if replan_actions:
        LOG.info(
            "defer_fn of %s with replan_actions=%r: deferral is not built here; the plan "
            "returned is evaluated in full (no stream actions are left in it)",
            ", ".join(deferring),
            sorted(replan_actions),
        )
    return {name: _no_defer_fn(item) for name, item in info.items()}


def _no_defer_fn(item: StreamInfo | FunctionInfo) -> StreamInfo | FunctionInfo:
    """A copy of ``item`` without its defer function (copied, not rebuilt: the compat
    classes' constructors take PDDLStream's arguments, not the stored values)."""
    if _defer_fn(item) is None:
        return item
    bare = copy.copy(item)
    object.__setattr__(bare, "defer_fn", None)
    return bare


def _defer_fn(item: StreamInfo | FunctionInfo) -> Any:
    """The defer function of ``item`` (the core ``FunctionInfo`` has none)."""
    return getattr(item, "defer_fn", None)
