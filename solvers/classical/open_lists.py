"""The open lists of best-first search (:mod:`.search`): one queue per heuristic value, plus a
preferred-operator queue each, taken in turns (the one used least goes next, the preferred ones
boosted by :data:`BOOST` turns when a heuristic reaches a new best value); the batched form of
lazy greedy search (one entry per expanded state and its successors); the type-based
exploration queue (:class:`TypeBuckets`).
"""

from __future__ import annotations

from heapq import heappop, heappush
from math import inf
from random import Random
from typing import Any

BOOST = 1000
# queue entry: (priority, tie-breaking h, insertion counter, payload)
Entry = tuple[float, float, int, tuple[int, int, float]]


class OpenLists:
    """One regular queue per heuristic value, plus one preferred queue each, alternated."""

    def __init__(self, size: int, use_preferred: bool) -> None:
        self.size = size
        self.count = 2 * size if use_preferred else size
        # Entry tuples; lists of BatchedOpenLists' form in lazy greedy search
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


class TypeBuckets:
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


class BatchedOpenLists(OpenLists):
    """Queues whose entries hold every successor of one expanded state (greedy lazy search).

    In greedy search all successors of a state share its priority and have consecutive
    insertion counters, so no other entry can come between them: one heap entry per expansion
    (``[priority, h, counter, origin, g, operators, next position]``) taken one operator at a
    time gives the same order as one entry per successor, at a fraction of the heap work.
    """

    def __init__(self, size: int, use_preferred: bool, explore: bool = False) -> None:
        super().__init__(size, use_preferred)
        self.typed = TypeBuckets(seed=0) if explore else None
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
