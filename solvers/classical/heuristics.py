"""Delete-relaxation heuristics: h_max, h_add, h_FF, and blind.

Every operator becomes one *unary* relaxed operator per add group: its unconditional adds under
its precondition, and each conditional effect under precondition + condition. Axioms are relaxed
operators of cost 0. A negative literal becomes a positive condition on the fact's complement
(:mod:`solvers.classical.complements`: achieved by the effects that delete a fluent, derived by
rules for a derived fact; states are extended with the complements of their false facts), or is
ignored where there is none; the relaxation stays an over-approximation.

Costs are propagated with the preconditions-left counter algorithm: a relaxed operator fires when
its counter of unreached preconditions drops to 0, and facts are settled cheapest first from a
binary heap, or for whole-number costs from first-in first-out lists per cost (generalised
Dijkstra). The search stops as soon as every goal fact is settled. h_FF extracts a relaxed plan
from the h_add best supporters and sums the costs of its distinct operators; that plan's
operators are the *preferred* operators. A fact's best supporter is the first relaxed operator
found reaching it at its cost (the exploration order's choice), or in *canonical* mode the one
of lowest id among them, so that the relaxed plan does not depend on the order of exploration.

On larger tasks the same algorithm runs compiled by numba (:mod:`solvers.classical.jit_relaxed`;
the same values, supporters and relaxed plans in either mode, 5-15x faster per state), switched
to once the queue has spent :data:`JIT_AFTER_SECONDS` on the task. Without numba, h_add (and so
h_FF) on larger tasks can instead run vectorised (:class:`~.vector_hadd.VectorHAdd`): NumPy
Bellman-Ford sweeps over all relaxed operators until no fact cost drops, canonical only; the
heuristic then times both engines on the initial state and keeps the faster (few sweeps over
many operators favour NumPy, long chains of cheap steps the queue). On 65 IPC problems the
exploration order's supporters expanded 21% fewer states than the canonical ones
(``benchmarks/bench_classical.py``).
"""

from __future__ import annotations

import time
from heapq import heappop, heappush
from math import inf

from sdar_tamp.errors import ParameterError
from sdar_tamp.logs import get_logger
from solvers.classical import jit, jit_relaxed
from solvers.classical.batch_hmax import BatchHMax
from solvers.classical.bitset_task import CompiledTask, bits, mask
from solvers.classical.complements import complements, relaxed_operators
from solvers.classical.jit_relaxed import JitRelaxed
from solvers.classical.vector_hadd import VectorHAdd

logger = get_logger(__name__)

ENGINES = ("auto", "python", "numpy", "numba")
# below this many (precondition + effect) entries the queue-based h_add is always used (the
# compiled engine's one-off cost, importing numba and loading its code, is about 0.5 s)
VECTOR_MIN_SIZE = 4000
# under "auto", a large task switches to the compiled engine once the queue has spent this long
# [s] (CPU) on it: the same values, without numba's import for searches that end sooner (at once
# when an earlier task of the process loaded the compiled code)
JIT_AFTER_SECONDS = 0.5

# "lmcount": landmark count; "ff-lmcount": h_FF and landmark count in alternating queues
HEURISTICS = ("ff", "add", "max", "blind", "lmcount", "ff-lmcount")


class RelaxedHeuristic:
    """Callable ``state -> (h, preferred operator ids or None)``; ``h`` is ``inf`` at dead ends.

    ``costs`` are the operator costs the heuristic uses (the search may pass adjusted costs).
    ``engine``: ``"python"`` (queue-based), ``"numba"`` (the queue, compiled), ``"numpy"``
    (vectorised; h_add and h_FF only) or ``"auto"`` (the queue below :data:`VECTOR_MIN_SIZE`,
    else numba if installed, else the faster of the queue and NumPy on the initial state).
    """

    def __init__(
        self, compiled: CompiledTask, name: str, costs: list[float], engine: str = "auto"
    ) -> None:
        if engine not in ENGINES:
            raise ParameterError(f"engine must be one of {', '.join(ENGINES)}; got {engine!r}")
        self.name = name
        self.costs = costs
        task = compiled.task
        self.complements = comp = complements(task)
        relaxed = relaxed_operators(task, comp)
        upre = [condition for condition, _adds, _op in relaxed]
        ueff = [adds for _condition, adds, _op in relaxed]
        uop = [op for _condition, _adds, op in relaxed]
        ucost = [costs[op] if op >= 0 else 0.0 for op in uop]
        count = comp.count
        pre_of: list[list[int]] = [[] for _ in range(count)]
        for u, pre in enumerate(upre):
            for fact in pre:
                pre_of[fact].append(u)
        self.pre_of = [tuple(us) for us in pre_of]
        self.upre, self.ueff, self.ucost, self.uop = upre, ueff, ucost, uop
        self.left = [len(pre) for pre in upre]
        self.no_pre = [u for u, pre in enumerate(upre) if not pre]
        self.goal = sorted(set(comp.positive(task.goal, task.negative_goal)))
        self.goal_mask = mask(self.goal)
        self.is_goal = [False] * count
        for fact in self.goal:
            self.is_goal[fact] = True
        self.count = count
        self.zeros = [0.0] * len(upre)
        self.min_cost = min(costs, default=0.0)
        # with whole-number costs h_add settles facts from a bucket queue instead of a heap
        self.integral = all(c == int(c) and c < 2**20 for c in costs)
        self.int_cost = [int(c) for c in ucost] if self.integral else []
        self.vector: VectorHAdd | None = None
        self.jit: JitRelaxed | None = None
        size = sum(map(len, upre)) + sum(map(len, ueff))
        large = engine == "auto" and size >= VECTOR_MIN_SIZE
        self.spent = 0.0  # CPU time of the queue-based engine while the compiled one is pending
        self.jit_pending = large and name != "blind" and jit.available()
        # "auto" keeps the first supporter found (the exploration order's) on small tasks and,
        # with numba, on large ones (the compiled engine finds the same); otherwise supporters
        # of lowest id, so that every engine gives the same relaxed plans
        self.canonical = engine != "auto" or (large and not self.jit_pending)
        # a task bound for the compiled engine settles facts from the heap even with whole
        # costs (in compiled code the heap is about 1.8x faster than the bucket lists), so that
        # both engines find the same first supporters before and after the switch
        self.heap_order = self.jit_pending
        if name != "blind" and engine == "numba":
            if not jit.available():
                raise ParameterError(f"engine 'numba' is unavailable: {jit.why_unavailable()}")
            self.use_compiled()
        elif self.jit_pending:
            if jit_relaxed.kernel_loaded():
                # an earlier task of this process loaded the compiled code (the rounds of a
                # stream planning solve ground one task each): switch at once, same values
                self.use_compiled()
        elif name in ("add", "ff") and (engine == "numpy" or large):
            self.vector = VectorHAdd(count, upre, ueff, ucost)
            if engine == "auto" and not self._vector_is_faster(comp.extend(compiled.init)):
                self.vector = None
        self.engine = (
            "numba"
            if self.jit or self.jit_pending
            else ("python" if self.vector is None else "numpy")
        )
        # h_max on a small task under "auto": the states of an expansion can be evaluated
        # together (:meth:`values`; the same values as the queue)
        self.batch = (
            BatchHMax(count, upre, ueff, ucost, self.goal)
            if name == "max" and engine == "auto" and self.engine == "python"
            else None
        )

    def values(self, states: list[int]) -> list[float]:
        """h of each of ``states`` (as ``self(state)[0]``), evaluated together when the
        heuristic has a batch engine."""
        if self.batch is None:
            return [self(state)[0] for state in states]
        extend = self.complements.extend
        return self.batch.evaluate([extend(state) for state in states])

    def use_compiled(self) -> None:
        """Evaluate with the compiled engine from now on (numba must be installed). It settles
        facts from a heap: first-found supporters then follow the heap's order."""
        self.heap_order = True
        self.jit = JitRelaxed(
            self.count,
            self.upre,
            self.ueff,
            self.ucost,
            self.uop,
            self.pre_of,
            self.goal,
            list(self.costs),
            canonical=self.canonical,
        )
        self.jit_pending = False

    def _vector_is_faster(self, state: int) -> bool:
        """Time both h_add engines on ``state`` (best of three runs each)."""
        assert self.vector is not None
        best = [inf, inf]
        for _ in range(3):
            for i, run in enumerate((self._propagate_scalar, self.vector.propagate)):
                start = time.perf_counter()
                run(state)
                best[i] = min(best[i], time.perf_counter() - start)
        return best[1] < best[0]

    def _propagate_scalar(self, state: int) -> tuple[list[float], list[int]]:
        if self.integral and self.name != "max" and not self.heap_order:
            return self._propagate_buckets(state)
        return self._propagate(state, self.name == "max")

    def __call__(self, state: int, preferred: bool = False) -> tuple[float, set[int] | None]:
        state = self.complements.extend(state)
        if self.name == "blind":
            return (0.0 if state & self.goal_mask == self.goal_mask else self.min_cost), None
        if self.jit_pending:
            start = time.process_time()
            result = self._evaluate_queue(state, preferred)
            self.spent += time.process_time() - start
            if self.spent >= JIT_AFTER_SECONDS:
                try:
                    self.use_compiled()
                except jit.CompiledCodeUnavailable as error:
                    logger.warning("%s; the search goes on without compiled code", error)
                    self.jit_pending = False
            return result
        if self.jit is not None:
            h, h_ff, operators = self.jit.evaluate(
                state, self.name == "max", self.name == "ff" or preferred
            )
            if self.name == "ff":
                return h_ff, set(operators)
            if h == inf:
                return inf, None
            return h, (set(operators) if preferred else None)
        return self._evaluate_queue(state, preferred)

    def _evaluate_queue(self, state: int, preferred: bool) -> tuple[float, set[int] | None]:
        if self.vector is not None:
            if state & self.goal_mask == self.goal_mask:
                return 0.0, (set() if preferred or self.name == "ff" else None)
            cost, supporter = self.vector.propagate(state, self.name == "ff" or preferred)
        else:
            cost, supporter = self._propagate_scalar(state)
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
        canonical = self.canonical
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
                elif canonical and value == cost[g] and u < supporter[g]:
                    supporter[g] = u
        limit = inf  # once every goal is settled: finish the facts of the same cost, then stop
        while heap:
            value, fact = heappop(heap)
            if value > cost[fact]:
                continue
            if value > limit:
                break
            if is_goal[fact]:
                goals_left -= 1
                if not goals_left:
                    if not canonical:
                        break
                    limit = value
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
                        elif canonical and new == cost[g] and u < supporter[g]:
                            supporter[g] = u
        return cost, supporter

    def _propagate_buckets(self, state: int) -> tuple[list[float], list[int]]:
        """h_add costs like :meth:`_propagate`, for whole-number costs (bucket queue)."""
        cost: list[float] = [inf] * self.count
        supporter = [-1] * self.count
        left = self.left[:]
        acc = self.int_cost[:]
        ueff, pre_of, is_goal = self.ueff, self.pre_of, self.is_goal
        canonical = self.canonical
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
                elif canonical and value == cost[g] and u < supporter[g]:
                    supporter[g] = u
        value = 0
        while value < len(buckets):
            for fact in buckets[value]:  # zero-cost operators append to the bucket being read
                if cost[fact] != value:
                    continue
                if is_goal[fact]:
                    goals_left -= 1
                    if not goals_left and not canonical:
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
                            elif canonical and new == cost[g] and u < supporter[g]:
                                supporter[g] = u
            if not goals_left:  # every goal settled, and every fact as cheap as the last one
                break
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
