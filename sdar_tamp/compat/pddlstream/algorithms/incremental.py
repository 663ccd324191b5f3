"""``pddlstream.algorithms.incremental``: the incremental algorithm and its variants."""

from __future__ import annotations

from typing import Any

from sdar_tamp.compat.pddlstream.algorithms.meta import solve
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Solution

__all__ = ["solve_exhaustive", "solve_immediate", "solve_incremental"]


def solve_incremental(problem: PDDLProblem, verbose: bool = False, **kwargs: Any) -> Solution:
    """Evaluate every stream instance up to the complexity limit, plan on real facts, raise
    the limit (PDDLStream's keywords, ``verbose`` off by default as there)."""
    for name in ("stream_info", "max_skeletons", "search_sample_ratio"):
        kwargs.pop(name, None)
    return solve(problem, algorithm="incremental", verbose=verbose, **kwargs)


def solve_immediate(problem: PDDLProblem, **kwargs: Any) -> Solution:
    """Plan on the initial facts only (no stream is called)."""
    kwargs.update(initial_complexity=0, max_complexity=0)
    return solve_incremental(problem, **kwargs)


def solve_exhaustive(problem: PDDLProblem, **kwargs: Any) -> Solution:
    """Evaluate every stream instance (the set must be finite), then plan once."""
    kwargs.update(initial_complexity=10**9, max_complexity=10**9)
    return solve_incremental(problem, **kwargs)
