"""h_max of many states at once, vectorised with NumPy (:class:`BatchHMax`).

A* with h_max on the optimistic tasks of stream planning spends most of its time in the
heuristic: a few dozen to a few hundred facts and relaxed operators, thousands of states, each
evaluated by a Python priority queue. Here the states of one expansion's successors are
evaluated together: a cost matrix (one row a state) and Bellman-Ford sweeps over every relaxed
operator, each sweep a handful of array operations whatever the number of states, until no
cost drops.

The values are exactly the queue's: a fact's h_max cost is the minimum over its derivations of
``max(precondition costs) + operator cost``, evaluated in the same floating-point operations
by either algorithm (``max`` is exact and addition of a non-negative cost is monotone), so the
least fixed point the sweeps reach is the cost the queue settles.
"""

from __future__ import annotations

from collections.abc import Sequence
from math import inf

import numpy as np
import numpy.typing as npt


class BatchHMax:
    """h_max of states given as fact bitsets (already extended by their complements).

    ``upre``/``ueff``/``ucost``: the relaxed operators' preconditions, added facts and costs;
    ``goal``: the goal facts; ``count``: the number of facts. A state's value is ``inf`` when a
    goal fact is unreachable from it.
    """

    def __init__(
        self,
        count: int,
        upre: Sequence[Sequence[int]],
        ueff: Sequence[Sequence[int]],
        ucost: Sequence[float],
        goal: Sequence[int],
    ) -> None:
        self.count = count
        # operators with the same preconditions share one maximum; for each fact they add,
        # only the cheapest of them counts (min(m + a, m + b) == m + min(a, b) exactly)
        cheapest: dict[tuple[tuple[int, ...], int], float] = {}
        for pre, eff, cost in zip(upre, ueff, ucost, strict=True):
            key = tuple(sorted(set(pre)))
            for fact in eff:
                known = cheapest.get((key, fact))
                if known is None or cost < known:
                    cheapest[(key, fact)] = cost
        # widest precondition first: column j covers the leading groups with more than j
        groups = sorted({key for key, _fact in cheapest}, key=lambda key: (-len(key), key))
        group_of = {key: i for i, key in enumerate(groups)}
        width = len(groups[0]) if groups else 0
        self.n_groups = len(groups)
        self.columns = [
            np.asarray([key[j] for key in groups if len(key) > j], dtype=np.intp)
            for j in range(width)
        ]
        pairs = sorted((fact, group_of[key], cost) for (key, fact), cost in cheapest.items())
        self.pair_group = np.asarray([g for _f, g, _c in pairs], dtype=np.intp)
        self.pair_cost = np.asarray([c for _f, _g, c in pairs], dtype=np.float64)[:, None]
        facts = np.asarray([f for f, _g, _c in pairs], dtype=np.intp)
        self.achieved, self.starts = np.unique(facts, return_index=True)
        self.goal = np.asarray(sorted(set(goal)), dtype=np.intp)
        self.nbytes = count // 8 + 1

    def true_facts(self, states: Sequence[int]) -> npt.NDArray[np.bool_]:
        """One column per state: which facts hold."""
        raw = np.frombuffer(
            b"".join(state.to_bytes(self.nbytes, "little") for state in states), dtype=np.uint8
        ).reshape(len(states), self.nbytes)
        true = np.unpackbits(raw, axis=1, bitorder="little")[:, : self.count]
        return np.ascontiguousarray(true.T).astype(bool)

    def evaluate(self, states: Sequence[int]) -> list[float]:
        """h_max of each state, in order."""
        if not states:
            return []
        if not len(self.goal):
            return [0.0] * len(states)
        # one row a fact, one column a state: a gather takes whole rows
        cost = np.where(self.true_facts(states), 0.0, inf)
        achieved, starts, columns = self.achieved, self.starts, self.columns
        if len(achieved):
            width = len(states)
            current = cost[achieved]
            maximum = np.empty((self.n_groups, width))
            gathered = np.empty((len(columns[0]) if columns else 0, width))
            reached = np.empty((len(self.pair_group), width))
            while True:
                maximum[:] = 0.0
                for column in columns:
                    head = gathered[: len(column)]
                    cost.take(column, axis=0, out=head)
                    np.maximum(maximum[: len(column)], head, out=maximum[: len(column)])
                maximum.take(self.pair_group, axis=0, out=reached)
                reached += self.pair_cost
                best = np.minimum.reduceat(reached, starts, axis=0)
                if not (best < current).any():
                    break
                np.minimum(current, best, out=current)
                cost[achieved] = current
        values: list[float] = cost[self.goal].max(axis=0).tolist()
        return values
