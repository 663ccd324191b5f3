"""A* with deferred evaluation: a state's heuristic is computed when it is taken out of the
open list, not when it is generated.

A successor enters the open list with ``f = g + max(0, h(parent) - cost(op))``. For an
admissible ``h`` that is a lower bound on its own ``h*``: ``h(parent) <= h*(parent) <= cost(op)
+ h*(successor)``. Taken out, it is evaluated; if its real ``f`` is higher it goes back with
that value, else it is expanded at once. The order of expansion stays admissible (every entry's
priority is at most the cost of the cheapest plan through it), so plans stay optimal, while the
successors an eager A* would evaluate and never expand (most of them where the branching is
wide: a robot that may move between any two configurations) are never evaluated. A goal state is
accepted when it is taken out: no entry left can lead to a cheaper plan.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from heapq import heappop, heappush
from math import inf

from solvers.classical.bitset_task import CompiledTask
from solvers.classical.search import Heuristic, SearchOutcome, _trace

# open list entry: (f, h or its lower bound, insertion counter, state, g, evaluated)
_Entry = tuple[float, float, int, int, float, bool]


def deferred_astar(
    compiled: CompiledTask,
    heuristic: Heuristic,
    deadline: float | None,
    cost_bound: float = inf,
    batch: Callable[[list[int]], list[float]] | None = None,
) -> SearchOutcome:
    """Optimal search from ``compiled.init`` with an admissible ``heuristic`` (ties: lower
    ``h``, then the older entry). States whose cost so far reaches ``cost_bound`` are pruned.

    ``batch``, when given, computes ``heuristic``'s values of many states at once: the new
    successors of an expansion are evaluated together right after it, and each value is used
    when its state is taken out, as it would have been computed then (the same expansions and
    plan; more states evaluated, each for less)."""
    costs = compiled.costs
    applicable, successor, is_goal = compiled.applicable, compiled.successor, compiled.is_goal
    init = compiled.init
    h_init, _ = heuristic(init, False)
    expanded, generated, evaluated = 0, 1, 1
    if h_init == inf:
        return SearchOutcome("unsolvable", (), 0, generated, evaluated)
    h_of: dict[int, float] = {init: h_init}
    best_g: dict[int, float] = {init: 0.0}
    parent: dict[int, tuple[int, int] | None] = {init: None}
    closed: set[int] = set()
    heap: list[_Entry] = [(h_init, h_init, 0, init, 0.0, True)]
    counter = 1
    ready: dict[int, float] = {}  # values computed by ``batch``, not yet taken out
    while heap:
        _, h, _, state, g, known = heappop(heap)
        if state in closed or g > best_g[state]:
            continue
        if is_goal(state):
            return SearchOutcome("solved", _trace(parent, state), expanded, generated, evaluated)
        if not known:
            value = h_of.get(state)
            if value is None:
                if state in ready:
                    value = ready.pop(state)
                else:
                    value, _ = heuristic(state, False)
                    evaluated += 1
                h_of[state] = value
            if value == inf:
                continue
            if value > h:
                heappush(heap, (g + value, value, counter, state, g, True))
                counter += 1
                continue
            h = value
        if deadline is not None and time.perf_counter() > deadline:
            return SearchOutcome("timeout", (), expanded, generated, evaluated)
        closed.add(state)
        expanded += 1
        fresh: list[int] = []
        for op in applicable(state):
            succ = successor(state, op)
            new_g = g + costs[op]
            if new_g >= cost_bound:
                continue
            known_g = best_g.get(succ)
            if known_g is not None and new_g >= known_g:
                continue
            succ_h = h_of.get(succ)
            if succ_h == inf:
                continue
            generated += 1
            best_g[succ] = new_g
            parent[succ] = (state, op)
            closed.discard(succ)
            if succ_h is None:
                bound = max(0.0, h - costs[op])
                heappush(heap, (new_g + bound, bound, counter, succ, new_g, False))
                if batch is not None and succ not in ready:
                    ready[succ] = -1.0
                    fresh.append(succ)
            else:
                heappush(heap, (new_g + succ_h, succ_h, counter, succ, new_g, True))
            counter += 1
        if fresh:
            assert batch is not None
            ready.update(zip(fresh, batch(fresh), strict=True))
            evaluated += len(fresh)
    return SearchOutcome("unsolvable", (), expanded, generated, evaluated)
