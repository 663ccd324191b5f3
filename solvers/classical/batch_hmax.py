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
        # widest precondition first (those without any last): every precondition fact of
        # every group in one gather, each group's maximum one segment of a reduction
        groups = sorted({key for key, _fact in cheapest}, key=lambda key: (-len(key), key))
        group_of = {key: i for i, key in enumerate(groups)}
        self.n_groups = len(groups)
        self.n_wide = sum(1 for key in groups if key)  # groups with a precondition
        self.entries = np.asarray([f for key in groups for f in key], dtype=np.intp)
        self.segments = np.cumsum([0] + [len(key) for key in groups[: self.n_wide]])[:-1]
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
        achieved, starts, entries, segments = (
            self.achieved,
            self.starts,
            self.entries,
            self.segments,
        )
        if len(achieved):
            width = len(states)
            current = cost[achieved]
            wide = self.n_wide
            maximum = np.zeros((self.n_groups, width))  # groups without preconditions: 0
            gathered = np.empty((len(entries), width))
            reached = np.empty((len(self.pair_group), width))
            while True:
                if wide:
                    # (costs are >= 0: a group's maximum over its facts is the maximum of 0
                    # and those, the same floats)
                    cost.take(entries, axis=0, out=gathered)
                    np.maximum.reduceat(gathered, segments, axis=0, out=maximum[:wide])
                maximum.take(self.pair_group, axis=0, out=reached)
                reached += self.pair_cost
                best = np.minimum.reduceat(reached, starts, axis=0)
                if not (best < current).any():
                    break
                np.minimum(current, best, out=current)
                cost[achieved] = current
        values: list[float] = cost[self.goal].max(axis=0).tolist()
        return values
