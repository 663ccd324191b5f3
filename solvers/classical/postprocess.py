"""Plan post-processing: greedy action elimination.

A step is redundant when the plan still reaches the goal after dropping it together with every
later step that is no longer applicable without it. Dropping such steps never raises the cost
(costs are non-negative), and it removes the detours a greedy search tends to leave, such as
picking a block up only to put it back.
"""

from __future__ import annotations

import time

from solvers.classical.bitset_task import CompiledTask


def eliminate_redundant_actions(
    compiled: CompiledTask, plan: list[int], deadline: float | None = None
) -> list[int]:
    """``plan`` (operator indices) without redundant steps; stops early at ``deadline``."""
    operators, costs = compiled.operators, compiled.costs
    successor, is_goal = compiled.successor, compiled.is_goal
    states = [compiled.init]
    for op in plan:
        states.append(successor(states[-1], op))
    i = 0
    while i < len(plan):
        if deadline is not None and time.perf_counter() > deadline:
            break
        state = states[i]
        kept: list[int] = []
        for op in plan[i + 1 :]:
            pre, negative = operators[op][0], operators[op][1]
            if state & pre == pre and not state & negative:
                state = successor(state, op)
                kept.append(op)
        if is_goal(state) and sum(costs[o] for o in kept) <= sum(costs[o] for o in plan[i:]):
            plan = plan[:i] + kept
            del states[i + 1 :]
            for op in kept:
                states.append(successor(states[-1], op))
            i = max(i - 1, 0)  # an earlier step may have become redundant too
        else:
            i += 1
    return plan
