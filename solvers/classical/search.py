"""Best-first search over bitset states: eager and lazy, with alternating queues.

One loop covers greedy best-first (``f = h``), A* (``f = g + h``) and weighted A*
(``f = g + w h``). An :class:`Evaluator` gives one or more heuristic values per state (LAMA's
configuration: h_FF and landmark count) and, optionally, preferred operators. Each value has a
queue of its own, and with preferred operators a second queue that only takes successors
reached by a preferred operator. The search takes turns between the queues (the one used least
goes next); each time a heuristic reaches a new best value the preferred queues get 1000 extra
turns (boosting). Lazy search stores (parent, operator) and evaluates a state only when it is
taken out of a queue, with its parent's values as the priority. Greedy lazy search can add a
type-based exploration queue to the rotation (:class:`_TypeBuckets`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from heapq import heappop, heappush
from math import inf
from random import Random
from typing import Any

from solvers.classical.bitset_task import CompiledTask
from solvers.classical.landmarks import LandmarkCount

Heuristic = Callable[[int, bool], tuple[float, "set[int] | None"]]
BOOST = 1000
# queue entry: (priority, tie-breaking h, insertion counter, payload)
Entry = tuple[float, float, int, tuple[int, int, float]]


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


class _Queues:
    """One regular queue per heuristic value, plus one preferred queue each, alternated."""

    def __init__(self, size: int, use_preferred: bool) -> None:
        self.size = size
        self.count = 2 * size if use_preferred else size
        # Entry tuples; lists of _BatchQueues' form in lazy greedy search
        self.heaps: list[list[Any]] = [[] for _ in range(self.count)]
        self.priority = [0] * self.count
        self.best = [inf] * size  # the lowest value seen of each heuristic

    def push(
        self,
        values: tuple[float, ...],
        g_part: float,
        h_weight: float,
        counter: int,
        payload: tuple[int, int, float],
        preferred: bool,
    ) -> None:
        heaps = self.heaps
        for i, h in enumerate(values):
            entry = (g_part + h_weight * h, h, counter, payload)
            heappush(heaps[i], entry)
            if preferred and self.count > self.size:
                heappush(heaps[self.size + i], entry)

    def boost(self) -> None:
        for i in range(self.size, self.count):
            self.priority[i] -= BOOST

    def note(self, values: tuple[float, ...]) -> None:
        """Record a state's heuristic values; boost the preferred queues when one improves."""
        best = self.best
        improved = False
        for i, h in enumerate(values):
            if h < best[i]:
                best[i] = h
                improved = True
        if improved:
            self.boost()

    def _take_turn(self) -> int:
        """The non-empty queue whose turn it is (lowest priority count), its count raised;
        -1 when every queue is empty."""
        best = -1
        priority = self.priority
        for i, heap in enumerate(self.heaps):
            if heap and (best < 0 or priority[i] < priority[best]):
                best = i
        if best >= 0:
            priority[best] += 1
        return best

    def pop(self) -> Entry | None:
        best = self._take_turn()
        if best < 0:
            return None
        entry: Entry = heappop(self.heaps[best])
        return entry


class _TypeBuckets:
    """Type-based exploration (Xie, Mueller, Holte 2014): batches of successors grouped by the
    type ``(h, g)`` of their parent; a pop takes a random type, then a random successor of a
    random batch of that type. It samples every region of the open list alike, so a search
    stuck on a plateau of its heuristic still reaches states the heuristic ranks badly."""

    def __init__(self, seed: int) -> None:
        self.rng = Random(seed)
        self.buckets: dict[tuple[float, float], list[list[Any]]] = {}
        self.keys: list[tuple[float, float]] = []

    def __bool__(self) -> bool:
        return bool(self.keys)

    def push(self, key: tuple[float, float], origin: int, g: float, operators: list[int]) -> None:
        bucket = self.buckets.get(key)
        if bucket is None:
            bucket = self.buckets[key] = []
            self.keys.append(key)
        bucket.append([origin, g, list(operators)])

    def pop(self) -> tuple[int, int, float]:
        rng = self.rng
        k = rng.randrange(len(self.keys))
        key = self.keys[k]
        bucket = self.buckets[key]
        b = rng.randrange(len(bucket))
        origin, g, operators = bucket[b]
        i = rng.randrange(len(operators))
        operators[i], operators[-1] = operators[-1], operators[i]
        op = operators.pop()
        if not operators:
            bucket[b] = bucket[-1]
            bucket.pop()
            if not bucket:
                del self.buckets[key]
                self.keys[k] = self.keys[-1]
                self.keys.pop()
        return origin, op, g


class _BatchQueues(_Queues):
    """Queues whose entries hold every successor of one expanded state (greedy lazy search).

    In greedy search all successors of a state share its priority and have consecutive
    insertion counters, so no other entry can come between them: one heap entry per expansion
    (``[priority, h, counter, origin, g, operators, next position]``) taken one operator at a
    time gives the same order as one entry per successor, at a fraction of the heap work.
    """

    def __init__(self, size: int, use_preferred: bool, explore: bool = False) -> None:
        super().__init__(size, use_preferred)
        self.typed = _TypeBuckets(seed=0) if explore else None
        if explore:
            self.priority.append(0)

    def push_batch(
        self,
        values: tuple[float, ...],
        h_weight: float,
        counter: int,
        origin: int,
        g: float,
        operators: list[int],
        preferred: list[int],
    ) -> None:
        heaps = self.heaps
        if self.typed is not None and operators:
            self.typed.push((values[0], g), origin, g, operators)
        for i, h in enumerate(values):
            if operators:
                heappush(heaps[i], [h_weight * h, h, counter, origin, g, operators, 0])
            if preferred and self.count > self.size:
                heappush(heaps[self.size + i], [h_weight * h, h, counter, origin, g, preferred, 0])

    def _take_turn(self) -> int:
        best = -1
        priority = self.priority
        for i, heap in enumerate(self.heaps):
            if heap and (best < 0 or priority[i] < priority[best]):
                best = i
        typed = len(self.heaps)
        if self.typed and (best < 0 or priority[typed] < priority[best]):
            best = typed
        if best >= 0:
            priority[best] += 1
        return best

    def pop_successor(self) -> tuple[int, int, float] | None:
        """``(origin, operator, origin's g)`` of the next successor, or None when empty."""
        best = self._take_turn()
        if best < 0:
            return None
        if best == len(self.heaps):
            assert self.typed is not None
            return self.typed.pop()
        heap = self.heaps[best]
        entry: list[Any] = heap[0]
        operators, position = entry[5], entry[6]
        if position + 1 == len(operators):
            heappop(heap)
        else:
            entry[6] = position + 1
        return entry[3], operators[position], entry[4]


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
    ``exploration`` adds a type-based queue (greedy lazy search only, see :class:`_TypeBuckets`)."""
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
    queues = _Queues(evaluator.size, preferred)
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
    greedy = g_weight == 0.0  # one queue entry per expansion (see _BatchQueues)
    queues = _BatchQueues(evaluator.size, preferred, explore=exploration and greedy)
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
