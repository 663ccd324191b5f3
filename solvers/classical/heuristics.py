"""Delete-relaxation heuristics: h_max, h_add, h_FF, and blind.

Every operator becomes one *unary* relaxed operator per add group: its unconditional adds under
its precondition, and each conditional effect under precondition + condition. Axioms are relaxed
operators of cost 0. Negative literals are ignored (the relaxation stays an over-approximation).

Costs are propagated with the preconditions-left counter algorithm: a relaxed operator fires when
its counter of unreached preconditions drops to 0, and facts are settled cheapest first from a
binary heap (generalised Dijkstra). The search stops as soon as every goal fact is settled.
h_FF extracts a relaxed plan from the h_add best supporters and sums the costs of its distinct
operators; that plan's operators are the *preferred* operators.
"""

from __future__ import annotations

from heapq import heappop, heappush
from math import inf

from solvers.classical.compiled import CompiledTask, bits

# "lmcount": landmark count; "ff-lmcount": h_FF and landmark count in alternating queues
HEURISTICS = ("ff", "add", "max", "blind", "lmcount", "ff-lmcount")


class RelaxedHeuristic:
    """Callable ``state -> (h, preferred operator ids or None)``; ``h`` is ``inf`` at dead ends.

    ``costs`` are the operator costs the heuristic uses (the search may pass adjusted costs).
    """

    def __init__(self, compiled: CompiledTask, name: str, costs: list[float]) -> None:
        self.name = name
        self.costs = costs
        task = compiled.task
        upre: list[tuple[int, ...]] = []
        ueff: list[tuple[int, ...]] = []
        ucost: list[float] = []
        uop: list[int] = []
        for index, op in enumerate(task.operators):
            groups = [(op.precondition, op.adds)]
            groups += [(op.precondition + c.condition, c.adds) for c in op.conditional]
            for pre, adds in groups:
                if adds:
                    upre.append(tuple(sorted(set(pre))))
                    ueff.append(adds)
                    ucost.append(costs[index])
                    uop.append(index)
        for axiom in task.axioms:
            upre.append(tuple(sorted(set(axiom.body))))
            ueff.append((axiom.head,))
            ucost.append(0.0)
            uop.append(-1)
        count = len(task.facts)
        pre_of: list[list[int]] = [[] for _ in range(count)]
        for u, pre in enumerate(upre):
            for fact in pre:
                pre_of[fact].append(u)
        self.pre_of = [tuple(us) for us in pre_of]
        self.upre, self.ueff, self.ucost, self.uop = upre, ueff, ucost, uop
        self.left = [len(pre) for pre in upre]
        self.no_pre = [u for u, pre in enumerate(upre) if not pre]
        self.goal = sorted(set(task.goal))
        self.goal_mask = compiled.goal_mask
        self.is_goal = [False] * count
        for fact in self.goal:
            self.is_goal[fact] = True
        self.count = count
        self.zeros = [0.0] * len(upre)
        self.min_cost = min(costs, default=0.0)
        # with whole-number costs h_add settles facts from a bucket queue instead of a heap
        self.integral = all(c == int(c) and c < 2**20 for c in costs)
        self.int_cost = [int(c) for c in ucost] if self.integral else []

    def __call__(self, state: int, preferred: bool = False) -> tuple[float, set[int] | None]:
        if self.name == "blind":
            return (0.0 if state & self.goal_mask == self.goal_mask else self.min_cost), None
        if self.integral and self.name != "max":
            cost, supporter = self._propagate_buckets(state)
        else:
            cost, supporter = self._propagate(state, self.name == "max")
        goal = self.goal
        if self.name == "ff":
            return self._relaxed_plan(cost, supporter)
        values = [cost[g] for g in goal]
        h = (max(values) if self.name == "max" else sum(values)) if values else 0.0
        if h == inf:
            return inf, None
        return h, (self._relaxed_plan(cost, supporter)[1] if preferred else None)

    def _propagate(self, state: int, use_max: bool) -> tuple[list[float], list[int]]:
        """Settled fact costs and best supporters (unary operator ids, -1 for none)."""
        cost = [inf] * self.count
        supporter = [-1] * self.count
        left = self.left[:]
        acc = self.zeros[:] if use_max else self.ucost[:]
        ucost, ueff, pre_of, is_goal = self.ucost, self.ueff, self.pre_of, self.is_goal
        heap: list[tuple[float, int]] = []
        true_facts = bits(state)
        goals_left = len(self.goal)
        for fact in true_facts:
            cost[fact] = 0.0
            if is_goal[fact]:
                goals_left -= 1
        if goals_left == 0:
            return cost, supporter
        fired: list[int] = list(self.no_pre)
        for fact in true_facts:
            for u in pre_of[fact]:
                left[u] -= 1
                if not left[u]:
                    fired.append(u)
        for u in fired:
            value = acc[u] + ucost[u] if use_max else acc[u]
            for g in ueff[u]:
                if value < cost[g]:
                    cost[g] = value
                    supporter[g] = u
                    heappush(heap, (value, g))
        while heap:
            value, fact = heappop(heap)
            if value > cost[fact]:
                continue
            if is_goal[fact]:
                goals_left -= 1
                if not goals_left:
                    break
            for u in pre_of[fact]:
                if use_max:
                    if value > acc[u]:
                        acc[u] = value
                else:
                    acc[u] += value
                left[u] -= 1
                if not left[u]:
                    new = acc[u] + ucost[u] if use_max else acc[u]
                    for g in ueff[u]:
                        if new < cost[g]:
                            cost[g] = new
                            supporter[g] = u
                            heappush(heap, (new, g))
        return cost, supporter

    def _propagate_buckets(self, state: int) -> tuple[list[float], list[int]]:
        """h_add costs like :meth:`_propagate`, for whole-number costs (bucket queue)."""
        cost: list[float] = [inf] * self.count
        supporter = [-1] * self.count
        left = self.left[:]
        acc = self.int_cost[:]
        ueff, pre_of, is_goal = self.ueff, self.pre_of, self.is_goal
        true_facts = bits(state)
        goals_left = len(self.goal)
        for fact in true_facts:
            cost[fact] = 0
            if is_goal[fact]:
                goals_left -= 1
        if goals_left == 0:
            return cost, supporter
        fired: list[int] = list(self.no_pre)
        for fact in true_facts:
            for u in pre_of[fact]:
                left[u] -= 1
                if not left[u]:
                    fired.append(u)
        buckets: list[list[int]] = [[] for _ in range(32)]
        for u in fired:
            value = acc[u]
            for g in ueff[u]:
                if value < cost[g]:
                    cost[g] = value
                    supporter[g] = u
                    while len(buckets) <= value:
                        buckets.append([])
                    buckets[value].append(g)
        value = 0
        while value < len(buckets):
            for fact in buckets[value]:  # zero-cost operators append to the bucket being read
                if cost[fact] != value:
                    continue
                if is_goal[fact]:
                    goals_left -= 1
                    if not goals_left:
                        return cost, supporter
                for u in pre_of[fact]:
                    acc[u] += value
                    left[u] -= 1
                    if not left[u]:
                        new = acc[u]
                        for g in ueff[u]:
                            if new < cost[g]:
                                cost[g] = new
                                supporter[g] = u
                                while len(buckets) <= new:
                                    buckets.append([])
                                buckets[new].append(g)
            value += 1
        return cost, supporter

    def _relaxed_plan(self, cost: list[float], supporter: list[int]) -> tuple[float, set[int]]:
        """(cost of the relaxed plan's distinct operators, those operators)."""
        stack = [g for g in self.goal if cost[g] > 0.0]
        if any(cost[g] == inf for g in stack):
            return inf, set()
        seen = set(stack)
        used: set[int] = set()
        operators: set[int] = set()
        h = 0.0
        upre, uop, costs = self.upre, self.uop, self.costs
        while stack:
            u = supporter[stack.pop()]
            if u in used:
                continue
            used.add(u)
            op = uop[u]
            if op >= 0 and op not in operators:
                operators.add(op)
                h += costs[op]
            for p in upre[u]:
                if cost[p] > 0.0 and p not in seen:
                    seen.add(p)
                    stack.append(p)
        return h, operators
