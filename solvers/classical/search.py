"""Best-first search over bitset states: eager and lazy, with preferred-operator queues.

One loop covers greedy best-first (``f = h``), A* (``f = g + h``) and weighted A*
(``f = g + w h``). With preferred operators, successors reached by a preferred operator go into
a second queue as well; the queues alternate, and each time a new best h is seen the preferred
queue gets 1000 extra turns (boosting). Lazy search stores (parent, operator) and evaluates a
state only when it is taken out of a queue, with its parent's h as the priority.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from heapq import heappop, heappush
from math import inf
from typing import Generic, TypeVar

from solvers.classical.compiled import CompiledTask

Heuristic = Callable[[int, bool], tuple[float, "set[int] | None"]]
BOOST = 1000
Payload = TypeVar("Payload")


@dataclass(frozen=True)
class SearchOutcome:
    status: str  # "solved", "unsolvable", "timeout"
    operators: tuple[int, ...]
    expanded: int
    generated: int
    evaluated: int


class _Queues(Generic[Payload]):
    """A regular and a preferred priority queue, alternated with boosting."""

    def __init__(self, use_preferred: bool) -> None:
        self.heaps: list[list[tuple[float, float, int, Payload]]] = [[], []]
        self.priority = [0, 0]
        self.use_preferred = use_preferred

    def push(self, entry: tuple[float, float, int, Payload], preferred: bool) -> None:
        heappush(self.heaps[0], entry)
        if preferred and self.use_preferred:
            heappush(self.heaps[1], entry)

    def boost(self) -> None:
        if self.use_preferred:
            self.priority[1] -= BOOST

    def pop(self) -> tuple[float, float, int, Payload] | None:
        regular, preferred = self.heaps
        if preferred and (not regular or self.priority[1] < self.priority[0]):
            self.priority[1] += 1
            return heappop(preferred)
        if regular:
            self.priority[0] += 1
            return heappop(regular)
        return None


def _trace(parent: dict[int, tuple[int, int] | None], state: int) -> tuple[int, ...]:
    ops: list[int] = []
    link = parent[state]
    while link is not None:
        state, op = link
        ops.append(op)
        link = parent[state]
    return tuple(reversed(ops))


def best_first_search(
    compiled: CompiledTask,
    heuristic: Heuristic,
    *,
    g_weight: float,
    h_weight: float,
    preferred: bool,
    lazy: bool,
    reopen: bool,
    deadline: float | None,
    cost_bound: float = inf,
) -> SearchOutcome:
    """Search from ``compiled.init``; ``reopen`` re-expands states reached more cheaply.
    States whose cost so far reaches ``cost_bound`` are pruned (only cheaper plans)."""
    run = _lazy if lazy else _eager
    return run(compiled, heuristic, g_weight, h_weight, preferred, reopen, deadline, cost_bound)


def _eager(
    compiled: CompiledTask,
    heuristic: Heuristic,
    g_weight: float,
    h_weight: float,
    preferred: bool,
    reopen: bool,
    deadline: float | None,
    cost_bound: float,
) -> SearchOutcome:
    costs = compiled.costs
    applicable, successor, is_goal = compiled.applicable, compiled.successor, compiled.is_goal
    init = compiled.init
    h, prefs = heuristic(init, preferred)
    expanded, generated, evaluated = 0, 1, 1
    if h == inf:
        return SearchOutcome("unsolvable", (), 0, generated, evaluated)
    best_h = h
    queues: _Queues[tuple[int, float, set[int] | None]] = _Queues(preferred)
    queues.push((h_weight * h, h, 0, (init, 0.0, prefs)), False)
    best_g: dict[int, float] = {init: 0.0}
    parent: dict[int, tuple[int, int] | None] = {init: None}
    closed: set[int] = set()
    counter = 1
    while True:
        entry = queues.pop()
        if entry is None:
            return SearchOutcome("unsolvable", (), expanded, generated, evaluated)
        state, g, prefs = entry[3]
        if state in closed or g > best_g[state]:
            continue
        if is_goal(state):
            return SearchOutcome("solved", _trace(parent, state), expanded, generated, evaluated)
        if deadline is not None and time.perf_counter() > deadline:
            return SearchOutcome("timeout", (), expanded, generated, evaluated)
        closed.add(state)
        expanded += 1
        for op in applicable(state):
            succ = successor(state, op)
            new_g = g + costs[op]
            if new_g >= cost_bound:
                continue
            known = best_g.get(succ)
            if known is not None and (not reopen or new_g >= known):
                continue
            generated += 1
            best_g[succ] = new_g
            parent[succ] = (state, op)
            closed.discard(succ)
            h, succ_prefs = heuristic(succ, preferred)
            evaluated += 1
            if h == inf:
                continue
            if h < best_h:
                best_h = h
                queues.boost()
            entry = (g_weight * new_g + h_weight * h, h, counter, (succ, new_g, succ_prefs))
            counter += 1
            queues.push(entry, prefs is not None and op in prefs)


def _lazy(
    compiled: CompiledTask,
    heuristic: Heuristic,
    g_weight: float,
    h_weight: float,
    preferred: bool,
    reopen: bool,
    deadline: float | None,
    cost_bound: float,
) -> SearchOutcome:
    costs = compiled.costs
    applicable, successor, is_goal = compiled.applicable, compiled.successor, compiled.is_goal
    expanded, generated, evaluated = 0, 1, 0
    best_h = inf
    queues: _Queues[tuple[int | None, int, float]] = _Queues(preferred)
    queues.push((0.0, 0.0, 0, (None, -1, 0.0)), False)
    parent: dict[int, tuple[int, int] | None] = {}
    closed: dict[int, float] = {}
    counter = 1
    while True:
        entry = queues.pop()
        if entry is None:
            return SearchOutcome("unsolvable", (), expanded, generated, evaluated)
        origin, op, g = entry[3]
        state = compiled.init if origin is None else successor(origin, op)
        known = closed.get(state)
        if known is not None and (not reopen or g >= known):
            continue
        if deadline is not None and time.perf_counter() > deadline:
            return SearchOutcome("timeout", (), expanded, generated, evaluated)
        closed[state] = g
        parent[state] = None if origin is None else (origin, op)
        h, prefs = heuristic(state, preferred)
        evaluated += 1
        if h == inf:
            continue
        if is_goal(state):
            return SearchOutcome("solved", _trace(parent, state), expanded, generated, evaluated)
        if h < best_h:
            best_h = h
            queues.boost()
        expanded += 1
        for succ_op in applicable(state):
            new_g = g + costs[succ_op]
            if new_g >= cost_bound:
                continue
            generated += 1
            key = g_weight * new_g + h_weight * h
            queues.push(
                (key, h, counter, (state, succ_op, new_g)), bool(prefs and succ_op in prefs)
            )
            counter += 1
