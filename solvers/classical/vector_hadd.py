"""h_add vectorised with NumPy (:class:`VectorHAdd`): the engine of
:class:`~solvers.classical.heuristics.RelaxedHeuristic` for larger tasks without numba, giving the
same costs and (canonical) best supporters as its queue-based engine."""

from __future__ import annotations

from math import inf

import numpy as np
import numpy.typing as npt


class VectorHAdd:
    """h_add by NumPy Bellman-Ford sweeps, with the same costs and best supporters.

    A sweep computes every relaxed operator's cost (its cost plus the sum of its precondition
    costs, one precondition column at a time over the operators that have one) and lowers
    every fact's cost to its cheapest achiever's; sweeps repeat until nothing drops. Achiever
    lists are sorted by (fact, operator id), so the first achiever at the fact's cost is the one
    of lowest id.
    """

    def __init__(
        self,
        count: int,
        upre: list[tuple[int, ...]],
        ueff: list[tuple[int, ...]],
        ucost: list[float],
    ) -> None:
        self.count = count
        # operators are stored widest precondition first, so that precondition column j only
        # covers the leading operators with more than j preconditions (no padding)
        order = sorted(range(len(upre)), key=lambda u: -len(upre[u]))
        position = np.empty(len(upre), dtype=np.intp)
        position[order] = np.arange(len(upre))
        width = max((len(pre) for pre in upre), default=0)
        self.columns = [
            np.asarray([upre[u][j] for u in order if len(upre[u]) > j], dtype=np.intp)
            for j in range(width)
        ]
        self.ucost = np.asarray([ucost[u] for u in order], dtype=np.float64)
        pairs = sorted({(g, u) for u, eff in enumerate(ueff) for g in eff})
        self.eff_fact = np.asarray([g for g, _u in pairs], dtype=np.intp)
        self.eff_id = np.asarray([u for _g, u in pairs], dtype=np.intp)  # relaxed operator id
        self.eff_op = position[self.eff_id]  # its position in the stored order
        achieved, starts, counts = np.unique(self.eff_fact, return_index=True, return_counts=True)
        self.achieved = achieved  # facts with at least one achiever
        self.starts = starts  # where each achieved fact's achievers start in eff_op
        self.segment = np.repeat(np.arange(len(achieved)), counts)  # eff entry -> achieved fact
        self.nbytes = count // 8 + 1
        self.extra = 1 << count

    def initial_costs(self, state: int) -> npt.NDArray[np.float64]:
        """0 for the facts of ``state`` and the extra fact, inf for the others."""
        raw = np.frombuffer((state | self.extra).to_bytes(self.nbytes, "little"), dtype=np.uint8)
        true = np.unpackbits(raw, bitorder="little")[: self.count + 1]
        return np.where(true, 0.0, inf)

    def propagate(self, state: int, supporters: bool = True) -> tuple[list[float], list[int]]:
        """Fact costs (as a list) and, if asked, best supporters (-1 where none is needed)."""
        cost = self.initial_costs(state)
        if not len(self.achieved):
            return cost.tolist(), [-1] * (self.count + 1)
        achieved, starts, eff_op, columns = self.achieved, self.starts, self.eff_op, self.columns
        ucost = self.ucost
        current = cost[achieved]
        while True:
            op_cost = ucost.copy()
            for column in columns:
                op_cost[: len(column)] += cost[column]
            reached = op_cost[eff_op]
            best = np.minimum.reduceat(reached, starts)
            if not np.count_nonzero(best < current):
                break
            np.minimum(current, best, out=current)
            cost[achieved] = current
        if not supporters:
            return cost.tolist(), []
        match = np.flatnonzero(reached == current[self.segment])
        segment = self.segment[match]
        leading = np.ones(len(match), dtype=bool)
        leading[1:] = segment[1:] != segment[:-1]
        chosen = match[leading]
        supporter = np.full(self.count + 1, -1, dtype=np.intp)
        supporter[self.eff_fact[chosen]] = self.eff_id[chosen]
        return cost.tolist(), supporter.tolist()
