"""The relaxed heuristics (h_max, h_add, h_FF) compiled with numba: the same values and relaxed
plans as the queue-based engine of :class:`~solvers.classical.heuristics.RelaxedHeuristic`,
5-15x faster per state.

The relaxed task is stored as flat arrays (compressed rows: the preconditions and adds of each
unary relaxed operator, the relaxed operators of each precondition fact). One call of
:func:`_evaluate` unpacks the state's bytes, runs the preconditions-left counter algorithm with
a binary heap ordered by (cost, fact), as :meth:`RelaxedHeuristic._propagate` does, and
extracts the relaxed plan, with the first-found or (canonical) the lowest-id best supporters: it
returns exactly what the queue-based engine returns from its heap in the same mode (in
canonical mode the queue's order does not matter, so its bucket lists give the same too).
Loading and compiling: :mod:`.jit`.
"""

from __future__ import annotations

from functools import lru_cache
from math import inf
from typing import Any

import numpy as np
import numpy.typing as npt

from solvers.classical.jit import (
    FloatArray,
    IntArray,
    compile_kernel,
    compressed_rows,
    mark_unavailable,
)


def _evaluate(
    raw: npt.NDArray[np.uint8],
    count: int,
    use_max: bool,
    want_plan: bool,
    pre_start: IntArray,
    pre_flat: IntArray,
    eff_start: IntArray,
    eff_flat: IntArray,
    of_start: IntArray,
    of_flat: IntArray,
    ucost: FloatArray,
    uop: IntArray,
    no_pre: IntArray,
    goal: IntArray,
    is_goal: npt.NDArray[np.bool_],
    op_cost: FloatArray,
    canonical: bool,
) -> tuple[float, float, IntArray]:
    units = ucost.shape[0]
    cost = np.full(count, np.inf)
    supporter = np.full(count, -1, dtype=np.int64)
    left = np.empty(units, dtype=np.int64)
    acc = np.empty(units, dtype=np.float64)
    for u in range(units):
        left[u] = pre_start[u + 1] - pre_start[u]
        acc[u] = 0.0 if use_max else ucost[u]
    goals_left = goal.shape[0]
    # the state's facts: bit i of the little-endian bytes
    true_facts = np.empty(count, dtype=np.int64)
    n_true = 0
    for byte in range(raw.shape[0]):
        value = raw[byte]
        bit = 0
        while value:
            if value & 1:
                fact = byte * 8 + bit
                if fact < count:
                    true_facts[n_true] = fact
                    n_true += 1
            value >>= 1
            bit += 1
    for i in range(n_true):
        fact = true_facts[i]
        cost[fact] = 0.0
        if is_goal[fact]:
            goals_left -= 1
    empty = np.empty(0, dtype=np.int64)
    if goals_left == 0:
        return 0.0, 0.0, empty
    fired = np.empty(units, dtype=np.int64)
    n_fired = 0
    for i in range(no_pre.shape[0]):
        fired[n_fired] = no_pre[i]
        n_fired += 1
    for i in range(n_true):
        fact = true_facts[i]
        for k in range(of_start[fact], of_start[fact + 1]):
            u = of_flat[k]
            left[u] -= 1
            if left[u] == 0:
                fired[n_fired] = u
                n_fired += 1
    capacity = eff_flat.shape[0] + count + 1
    heap_value = np.empty(capacity, dtype=np.float64)
    heap_fact = np.empty(capacity, dtype=np.int64)
    size = 0
    for i in range(n_fired):
        u = fired[i]
        value = acc[u] + ucost[u] if use_max else acc[u]
        for k in range(eff_start[u], eff_start[u + 1]):
            g = eff_flat[k]
            if value < cost[g]:
                cost[g] = value
                supporter[g] = u
                # push (value, g)
                j = size
                size += 1
                while j > 0:
                    parent = (j - 1) >> 1
                    pv = heap_value[parent]
                    if pv < value or (pv == value and heap_fact[parent] <= g):
                        break
                    heap_value[j] = pv
                    heap_fact[j] = heap_fact[parent]
                    j = parent
                heap_value[j] = value
                heap_fact[j] = g
            elif canonical and value == cost[g] and u < supporter[g]:
                supporter[g] = u
    limit = np.inf
    while size > 0:
        value = heap_value[0]
        fact = heap_fact[0]
        # pop: move the last entry down from the root
        size -= 1
        last_value = heap_value[size]
        last_fact = heap_fact[size]
        j = 0
        while True:
            child = 2 * j + 1
            if child >= size:
                break
            right = child + 1
            if right < size and (
                heap_value[right] < heap_value[child]
                or (heap_value[right] == heap_value[child] and heap_fact[right] < heap_fact[child])
            ):
                child = right
            cv = heap_value[child]
            if last_value < cv or (last_value == cv and last_fact <= heap_fact[child]):
                break
            heap_value[j] = cv
            heap_fact[j] = heap_fact[child]
            j = child
        heap_value[j] = last_value
        heap_fact[j] = last_fact
        if value > cost[fact]:
            continue
        if value > limit:
            break
        if is_goal[fact]:
            goals_left -= 1
            if goals_left == 0:
                if not canonical:
                    break
                limit = value
        for k in range(of_start[fact], of_start[fact + 1]):
            u = of_flat[k]
            if use_max:
                if value > acc[u]:
                    acc[u] = value
            else:
                acc[u] += value
            left[u] -= 1
            if left[u] == 0:
                new = acc[u] + ucost[u] if use_max else acc[u]
                for e in range(eff_start[u], eff_start[u + 1]):
                    g = eff_flat[e]
                    if new < cost[g]:
                        cost[g] = new
                        supporter[g] = u
                        j = size
                        size += 1
                        while j > 0:
                            parent = (j - 1) >> 1
                            pv = heap_value[parent]
                            if pv < new or (pv == new and heap_fact[parent] <= g):
                                break
                            heap_value[j] = pv
                            heap_fact[j] = heap_fact[parent]
                            j = parent
                        heap_value[j] = new
                        heap_fact[j] = g
                    elif canonical and new == cost[g] and u < supporter[g]:
                        supporter[g] = u
    # the goal value: sum (h_add) or max (h_max) of the goal costs
    h = 0.0
    for i in range(goal.shape[0]):
        c = cost[goal[i]]
        if c == np.inf:
            return np.inf, np.inf, empty
        if use_max:
            if c > h:
                h = c
        else:
            h += c
    if not want_plan:
        return h, 0.0, empty
    # the relaxed plan: the best supporters of every needed fact, from the goals down
    stack = np.empty(count, dtype=np.int64)
    n_stack = 0
    seen = np.zeros(count, dtype=np.bool_)
    for i in range(goal.shape[0]):
        g = goal[i]
        if cost[g] > 0.0 and not seen[g]:
            seen[g] = True
            stack[n_stack] = g
            n_stack += 1
    used = np.zeros(units, dtype=np.bool_)
    taken = np.zeros(op_cost.shape[0], dtype=np.bool_)
    operators = np.empty(units, dtype=np.int64)
    n_ops = 0
    h_ff = 0.0
    while n_stack > 0:
        n_stack -= 1
        u = supporter[stack[n_stack]]
        if used[u]:
            continue
        used[u] = True
        op = uop[u]
        if op >= 0 and not taken[op]:
            taken[op] = True
            operators[n_ops] = op
            n_ops += 1
            h_ff += op_cost[op]
        for k in range(pre_start[u], pre_start[u + 1]):
            p = pre_flat[k]
            if cost[p] > 0.0 and not seen[p]:
                seen[p] = True
                stack[n_stack] = p
                n_stack += 1
    return h, h_ff, operators[:n_ops].copy()


@lru_cache(maxsize=1)
def _kernel() -> Any:
    """:func:`_evaluate` compiled (or loaded from numba's cache) on first use."""
    return compile_kernel(_evaluate)


def kernel_loaded() -> bool:
    """Whether this process has loaded the compiled evaluator already (a later task then
    switches to it at no cost: only its arrays are built)."""
    info = getattr(_kernel, "cache_info", None)  # (None: the kernel was replaced)
    return info is not None and info().currsize > 0


class JitRelaxed:
    """The relaxed task as arrays and the compiled evaluator over it.

    ``canonical``: best supporters of lowest relaxed-operator id among those of least cost (else
    the first found, as the queue-based engine's heap finds it).
    ``evaluate(state, use_max, want_plan)`` returns ``(h, h_ff, relaxed-plan operators)``: ``h``
    is h_add (or h_max with ``use_max``), ``inf`` at a dead end; ``h_ff`` and the operators are
    only computed with ``want_plan`` (else 0 and empty).
    """

    def __init__(
        self,
        count: int,
        upre: list[tuple[int, ...]],
        ueff: list[tuple[int, ...]],
        ucost: list[float],
        uop: list[int],
        pre_of: list[tuple[int, ...]],
        goal: list[int],
        op_cost: list[float],
        canonical: bool = True,
    ) -> None:
        self.count = count
        self.canonical = canonical
        self.nbytes = count // 8 + 1
        pre_start, pre_flat = compressed_rows(upre)
        eff_start, eff_flat = compressed_rows(ueff)
        of_start, of_flat = compressed_rows(pre_of)
        is_goal = np.zeros(count, dtype=np.bool_)
        is_goal[goal] = True
        self.arrays = (
            pre_start,
            pre_flat,
            eff_start,
            eff_flat,
            of_start,
            of_flat,
            np.asarray(ucost, dtype=np.float64),
            np.asarray(uop, dtype=np.int64),
            np.asarray([u for u, pre in enumerate(upre) if not pre], dtype=np.int64),
            np.asarray(goal, dtype=np.int64),
            is_goal,
            np.asarray(op_cost, dtype=np.float64),
        )
        self.kernel = _kernel()
        try:  # compiles, or loads from numba's cache, now rather than in the first evaluation
            self.evaluate(0, False, True)
        except Exception as error:
            raise mark_unavailable("the heuristic", error) from error

    def evaluate(
        self, state: int, use_max: bool, want_plan: bool
    ) -> tuple[float, float, list[int]]:
        raw = np.frombuffer(state.to_bytes(self.nbytes, "little"), dtype=np.uint8)
        h, h_ff, operators = self.kernel(
            raw,
            self.count,
            use_max,
            want_plan,
            *self.arrays,
            self.canonical,
        )
        if h == inf:
            return inf, inf, []
        return float(h), float(h_ff), operators.tolist()
