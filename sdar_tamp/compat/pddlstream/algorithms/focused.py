"""``pddlstream.algorithms.focused``: the optimistic (focused-family) algorithms."""

from __future__ import annotations

from typing import Any

from sdar_tamp.compat.pddlstream.algorithms.meta import solve
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Solution

__all__ = [
    "solve_abstract",
    "solve_adaptive",
    "solve_binding",
    "solve_focused",
    "solve_focused_original",
]


def solve_abstract(
    problem: PDDLProblem,
    max_skeletons: float | None = None,
    bind: bool | None = True,
    **kwargs: Any,
) -> Solution:
    """PDDLStream's ``solve_focused``: adaptive with a skeleton queue when ``max_skeletons``
    is given, else binding (``bind=True``) or focused."""
    if max_skeletons is not None:
        return solve(problem, algorithm="adaptive", max_skeletons=max_skeletons, **kwargs)
    algorithm = "binding" if bind else "focused"
    kwargs.pop("search_sample_ratio", None)
    return solve(problem, algorithm=algorithm, **kwargs)


solve_focused = solve_abstract


def solve_focused_original(
    problem: PDDLProblem, fail_fast: bool = False, **kwargs: Any
) -> Solution:
    """The focused algorithm (optimistic plans, first-layer streams evaluated)."""
    kwargs.pop("max_skeletons", None)
    kwargs.pop("search_sample_ratio", None)
    return solve(problem, algorithm="focused", **kwargs)


def solve_binding(problem: PDDLProblem, fail_fast: bool = False, **kwargs: Any) -> Solution:
    """The binding algorithm (whole stream plans, outputs bound along the way)."""
    kwargs.pop("max_skeletons", None)
    kwargs.pop("search_sample_ratio", None)
    return solve(problem, algorithm="binding", **kwargs)


def solve_adaptive(
    problem: PDDLProblem,
    max_skeletons: float | None = None,
    search_sample_ratio: float = 1,
    **kwargs: Any,
) -> Solution:
    """The adaptive algorithm (a queue of skeletons revisited between searches)."""
    return solve(
        problem,
        algorithm="adaptive",
        max_skeletons=max_skeletons,
        search_sample_ratio=search_sample_ratio,
        **kwargs,
    )
