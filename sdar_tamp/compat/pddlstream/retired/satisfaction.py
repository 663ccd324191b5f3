"""``pddlstream.retired.satisfaction``: constraint satisfaction with a chosen algorithm."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from sdar_tamp.compat.pddlstream.algorithms.satisfaction import (
    SatisfactionProblem,
    SatisfactionSolution,
    bindings_from_solution,
    pddl_from_csp,
)

__all__ = ["solve_pddlstream_satisfaction"]


def solve_pddlstream_satisfaction(
    problem: SatisfactionProblem | Sequence[Any], **kwargs: Any
) -> SatisfactionSolution:
    """Solve a :class:`SatisfactionProblem` with ``solve(..., **kwargs)`` (any algorithm)."""
    from sdar_tamp.compat.pddlstream.algorithms.meta import solve

    stream_pddl, stream_map, init, terms = problem
    planning, parameters = pddl_from_csp(stream_pddl, stream_map, init, terms)
    solution = solve(planning, **kwargs)
    return SatisfactionSolution(
        bindings_from_solution(parameters, solution), solution.cost, solution.certificate
    )
