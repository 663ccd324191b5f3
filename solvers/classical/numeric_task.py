"""Planning tasks with numeric fluents: compiled away before grounding
(:func:`sdar_tamp.language.numeric_compile.compile_numeric`), the plan's steps given back with
their original arguments."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from sdar_tamp.language.numeric_compile import compile_numeric
from solvers.classical.problem import GroundAction, PlanningTask, SearchResult


def plan_numeric(
    task: PlanningTask, planner: Callable[[PlanningTask], SearchResult]
) -> SearchResult:
    """``planner``'s result on ``task`` with its numeric fluents compiled away.

    Raises:
        UnsupportedFeatureError: a numeric fluent with too many values (see
            :func:`~sdar_tamp.language.numeric_compile.compile_numeric`).
    """
    compilation = compile_numeric(task.domain, task.objects, task.init, task.numeric_init)
    extra = task.extra_cost
    penalty = None
    if extra is not None:

        def penalty(name: str, args: tuple[str, ...]) -> float:
            return extra(name, compilation.original_args(name, args))

    compiled = dataclasses.replace(
        task,
        domain=compilation.domain,
        objects=compilation.objects,
        init=compilation.init,
        numeric_init=compilation.numeric_init,
        extra_cost=penalty,
    )
    result = planner(compiled)
    if result.plan is None:
        return result
    steps = tuple(
        GroundAction(step.name, compilation.original_args(step.name, step.args))
        for step in result.plan
    )
    return dataclasses.replace(result, plan=steps)
