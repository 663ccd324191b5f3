"""Best-first search over bitset states: eager and lazy, with alternating queues.

One loop covers greedy best-first (``f = h``), A* (``f = g + h``) and weighted A*
(``f = g + w h``). An :class:`Evaluator` gives one or more heuristic values per state (LAMA's
configuration: h_FF and landmark count) and, optionally, preferred operators. Each value has a
queue of its own, and with preferred operators a second queue that only takes successors
reached by a preferred operator. The search takes turns between the queues (the one used least
goes next); each time a heuristic reaches a new best value the preferred queues get 1000 extra
turns (boosting). Lazy search stores (parent, operator) and evaluates a state only when it is
taken out of a queue, with its parent's values as the priority. Greedy lazy search can add a
type-based exploration queue to the rotation (:class:`~.open_lists.TypeBuckets`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from math import inf

from solvers.classical.bitset_task import CompiledTask
from solvers.classical.landmarks import LandmarkCount
from solvers.classical.open_lists import BatchedOpenLists, OpenLists

Heuristic = Callable[[int, bool], tuple[float, "set[int] | None"]]


@dataclass(frozen=True)
class SearchOutcome:
    status: str  # "solved", "unsolvable", "timeout"
    operators: tuple[int, ...]
    expanded: int
    generated: int
    evaluated: int


class Evaluator:
    """A relaxed heuristic, a landmark count, or both (in that order of values).

    ``evaluate(state, parent_reached, preferred)`` returns the values, the preferred operators
    (from the relaxed heuristic) and the state's accepted-landmark set (0 without landmarks);
    ``parent_reached`` is None for the initial state.
    """

    def __init__(self, relaxed: Heuristic | None, landmarks: LandmarkCount | None) -> None:
        self.relaxed = relaxed
        self.landmarks = landmarks
        self.size = (relaxed is not None) + (landmarks is not None)

    def evaluate(
        self, state: int, parent_reached: int | None, preferred: bool
    ) -> tuple[tuple[float, ...], set[int] | None, int]:
        values: tuple[float, ...] = ()
        prefs = None
        if self.relaxed is not None:
            h, prefs = self.relaxed(state, preferred)
            if h == inf:
                return (inf,), None, 0
            values = (h,)
        reached = 0
        if self.landmarks is not None:
            lm = self.landmarks
            if parent_reached is None:
                reached = lm.initial(state)
            else:
                reached = lm.update(parent_reached, state)
            values = (*values, float(lm.value(reached, state)))
        return values, prefs, reached


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
    heuristic: Heuristic | Evaluator,
    *,
    g_weight: float,
    h_weight: float,
    preferred: bool,
    lazy: bool,
    reopen: bool,
    deadline: float | None,
    cost_bound: float = inf,
    exploration: bool = False,
) -> SearchOutcome:
    """Search from ``compiled.init``; ``reopen`` re-expands states reached more cheaply.
    States whose cost so far reaches ``cost_bound`` are pruned (only cheaper plans).
    ``exploration`` adds a type-based queue (greedy lazy search only, see
    :class:`~.open_lists.TypeBuckets`)."""
    evaluator = heuristic if isinstance(heuristic, Evaluator) else Evaluator(heuristic, None)
    if not lazy:
        return _eager(
            compiled, evaluator, g_weight, h_weight, preferred, reopen, deadline, cost_bound
        )
    return _lazy(
        compiled,
        evaluator,
        g_weight,
        h_weight,
        preferred,
        reopen,
        deadline,
        cost_bound,
        exploration and g_weight == 0.0,
    )


def _eager(
    compiled: CompiledTask,
    evaluator: Evaluator,
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
    evaluate = evaluator.evaluate
    values, prefs, reached = evaluate(init, None, preferred)
    expanded, generated, evaluated = 0, 1, 1
    if values[0] == inf:
        return SearchOutcome("unsolvable", (), 0, generated, evaluated)
    queues = OpenLists(evaluator.size, preferred)
    queues.best = list(values)  # the initial state's values improve nothing: no boost
    queues.push(values, 0.0, h_weight, 0, (init, -1, 0.0), False)
    best_g: dict[int, float] = {init: 0.0}
    parent: dict[int, tuple[int, int] | None] = {init: None}
    info: dict[int, tuple[set[int] | None, int]] = {init: (prefs, reached)}
    closed: set[int] = set()
    counter = 1
    while True:
        entry = queues.pop()
        if entry is None:
            return SearchOutcome("unsolvable", (), expanded, generated, evaluated)
        state, _op, g = entry[3]
        if state in closed or g > best_g[state]:
            continue
        if is_goal(state):
            return SearchOutcome("solved", _trace(parent, state), expanded, generated, evaluated)
        if deadline is not None and time.perf_counter() > deadline:
            return SearchOutcome("timeout", (), expanded, generated, evaluated)
        closed.add(state)
        expanded += 1
        prefs, reached = info[state]
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
            values, succ_prefs, succ_reached = evaluate(succ, reached, preferred)
            evaluated += 1
            if values[0] == inf:
                continue
            info[succ] = (succ_prefs, succ_reached)
            queues.note(values)
            queues.push(
                values,
                g_weight * new_g,
                h_weight,
                counter,
                (succ, op, new_g),
                prefs is not None and op in prefs,
            )
            counter += 1


def _lazy(
    compiled: CompiledTask,
    evaluator: Evaluator,
    g_weight: float,
    h_weight: float,
    preferred: bool,
    reopen: bool,
    deadline: float | None,
    cost_bound: float,
    exploration: bool = False,
) -> SearchOutcome:
    costs = compiled.costs
    applicable, successor, is_goal = compiled.applicable, compiled.successor, compiled.is_goal
    evaluate = evaluator.evaluate
    expanded, generated, evaluated = 0, 1, 0
    greedy = g_weight == 0.0  # one queue entry per expansion (see BatchedOpenLists)
    queues = BatchedOpenLists(evaluator.size, preferred, explore=exploration and greedy)
    init = compiled.init
    if greedy:
        queues.push_batch((0.0,) * evaluator.size, h_weight, 0, -1, 0.0, [-1], [])
    else:
        queues.push((0.0,) * evaluator.size, 0.0, h_weight, 0, (-1, -1, 0.0), False)
    parent: dict[int, tuple[int, int] | None] = {}
    closed: dict[int, float] = {}
    reached_of: dict[int, int] = {}
    counter = 1
    while True:
        if greedy:
            taken = queues.pop_successor()
            if taken is None:
                return SearchOutcome("unsolvable", (), expanded, generated, evaluated)
            origin, op, g = taken
            if op >= 0:
                g += costs[op]
        else:
            entry = queues.pop()
            if entry is None:
                return SearchOutcome("unsolvable", (), expanded, generated, evaluated)
            origin, op, g = entry[3]
        state = init if op < 0 else successor(origin, op)
        known = closed.get(state)
        if known is not None and (not reopen or g >= known):
            continue
        if deadline is not None and time.perf_counter() > deadline:
            return SearchOutcome("timeout", (), expanded, generated, evaluated)
        closed[state] = g
        parent[state] = None if op < 0 else (origin, op)
        values, prefs, reached = evaluate(state, None if op < 0 else reached_of[origin], preferred)
        reached_of[state] = reached
        evaluated += 1
        if values[0] == inf:
            continue
        if is_goal(state):
            return SearchOutcome("solved", _trace(parent, state), expanded, generated, evaluated)
        queues.note(values)
        expanded += 1
        if greedy:
            successors = applicable(state)
            if cost_bound != inf:
                successors = [o for o in successors if g + costs[o] < cost_bound]
            generated += len(successors)
            chosen = [o for o in successors if o in prefs] if prefs else []
            queues.push_batch(values, h_weight, counter, state, g, successors, chosen)
            counter += 1
            continue
        push = queues.push
        for succ_op in applicable(state):
            new_g = g + costs[succ_op]
            if new_g >= cost_bound:
                continue
            generated += 1
            push(
                values,
                g_weight * new_g,
                h_weight,
                counter,
                (state, succ_op, new_g),
                prefs is not None and succ_op in prefs,
            )
            counter += 1
