"""The ground task packed for search: bitset states, a successor generator, axiom closure.

A state is a Python ``int`` whose bit ``i`` is fact ``i``. Operators are tuples of masks. The
successor generator is a trie over the operators' (sorted) positive preconditions: a node lists
the operators whose preconditions end there and branches on further facts, so a state only
visits the branches whose facts it contains instead of testing every operator.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable

from sdar_tamp.logs import get_logger
from solvers.classical import jit, jit_successors
from solvers.classical.jit_successors import JitSuccessors
from solvers.classical.task import GroundAxiom, GroundTask

logger = get_logger(__name__)

# a task with this many operators walks its trie in compiled code once the search has asked for
# this many successor lists (a short search does not pay numba's import)
JIT_MIN_OPERATORS = 300
JIT_AFTER_CALLS = 2000

# (pre mask, negative pre mask, add mask, delete mask, conditional effects, cost)
# conditional effect: (condition mask, negative condition mask, add mask, delete mask)
CondMasks = tuple[tuple[int, int, int, int], ...]
OpMasks = tuple[int, int, int, int, CondMasks, float]
# a derived rule: (head bit, body mask, negative body mask, head fact)
_Rule = tuple[int, int, int, int]
# successor-generator trie node: (operators ending here, ((fact bit, child), ...))
Trie = tuple[tuple[int, ...], tuple[tuple[int, "Trie"], ...]]


def mask(facts: Iterable[int]) -> int:
    result = 0
    for fact in facts:
        result |= 1 << fact
    return result


def bits(state: int) -> list[int]:
    """The fact ids set in ``state``."""
    result = []
    while state:
        low = state & -state
        result.append(low.bit_length() - 1)
        state ^= low
    return result


class _Node:
    __slots__ = ("children", "operators")

    def __init__(self) -> None:
        self.operators: list[int] = []
        self.children: dict[int, _Node] = {}


#: At most this many closures are remembered per task (a large search's memory stays its own).
CLOSED_MEMO = 200_000
#: Strata with at least this many rules are closed by :class:`_CountedStratum`.
COUNTED_STRATUM = 16


class _CountedStratum:
    """One stratum's rules, closed from the facts that can fire them: a rule is looked at
    only when one of its body facts is true, so a state's closure costs what its true facts
    touch, not the size of the stratum.

    A rule whose body has no head of this stratum is looked at when its *trigger* (its body
    fact that the fewest rules share, the least likely to be true) is true in the state; one
    that needs a head of this stratum is looked at again each time such a head becomes true
    (its count of missing heads reaches zero then). A rule fires when its whole body is true
    and its negative body (fixed by lower strata and fluents) false."""

    def __init__(self, axioms: list[GroundAxiom]) -> None:
        own = {a.head for a in axioms}
        shared = Counter(f for a in axioms for f in set(a.body))
        # (head bit, body mask, negative body mask, head fact) of each rule
        rules = [(1 << a.head, mask(a.body), mask(a.negative_body), a.head) for a in axioms]
        always: list[_Rule] = []  # rules with an empty body
        triggers: dict[int, list[_Rule]] = {}  # fact -> rules it triggers
        watchers: dict[int, list[_Rule]] = {}  # head of this stratum -> rules needing it
        for rule, axiom in zip(rules, axioms, strict=True):
            needs = sorted({f for f in axiom.body if f in own})
            if needs:
                for fact in needs:
                    watchers.setdefault(fact, []).append(rule)
            elif axiom.body:
                trigger = min(axiom.body, key=lambda f: (shared[f], f))
                triggers.setdefault(trigger, []).append(rule)
            else:
                always.append(rule)
        self.always = tuple(always)
        self.triggers = {f: tuple(r) for f, r in triggers.items()}
        self.watchers = {f: tuple(r) for f, r in watchers.items()}
        self.trigger_mask = mask(self.triggers)

    def close(self, state: int) -> int:
        # one loop over the rules each true trigger fact (then each new head) names, inline:
        # this runs for every successor a search generates
        watchers = self.watchers
        queue: list[int] = []
        for head, body, negative, fact in self.always:
            if not state & head and state & body == body and not state & negative:
                state |= head
                queue.append(fact)
        triggers = self.triggers
        pending = state & self.trigger_mask
        while pending:
            low = pending & -pending
            pending ^= low
            for head, body, negative, fact in triggers[low.bit_length() - 1]:
                if not state & head and state & body == body and not state & negative:
                    state |= head
                    queue.append(fact)
        while queue:
            for head, body, negative, fact in watchers.get(queue.pop(), ()):
                if not state & head and state & body == body and not state & negative:
                    state |= head
                    queue.append(fact)
        return state


class CompiledTask:
    """Masks, successor generator and axiom evaluator of a :class:`GroundTask`."""

    def __init__(self, task: GroundTask) -> None:
        self.task = task
        self.operators: list[OpMasks] = [
            (
                mask(op.precondition),
                mask(op.negative_precondition),
                mask(op.adds),
                mask(op.deletes),
                tuple(
                    (mask(c.condition), mask(c.negative_condition), mask(c.adds), mask(c.deletes))
                    for c in op.conditional
                ),
                op.cost,
            )
            for op in task.operators
        ]
        self.costs = [op.cost for op in task.operators]
        self.goal_mask = mask(task.goal)
        self.negative_goal_mask = mask(task.negative_goal)
        self.derived_mask = mask(task.derived)
        strata: dict[int, list[tuple[int, int, int]]] = {}
        grouped: dict[int, list[GroundAxiom]] = {}
        for axiom in task.axioms:
            strata.setdefault(axiom.stratum, []).append(
                (1 << axiom.head, mask(axiom.body), mask(axiom.negative_body))
            )
            grouped.setdefault(axiom.stratum, []).append(axiom)
        self.strata = [strata[s] for s in sorted(strata)]
        # large strata are closed by counting each rule's missing body facts (linear in the
        # rules' size) instead of sweeping the rules until nothing changes
        self.counted = [
            _CountedStratum(grouped[s]) if len(grouped[s]) >= COUNTED_STRATUM else None
            for s in sorted(grouped)
        ]
        self._root = self._build_trie()
        # the closure of each basic state met (a search reaches many states more than once)
        self._closed: dict[int, int] = {}
        self.init = self.close(mask(task.init))
        self._calls = 0
        self._jit: JitSuccessors | None = None
        self._jit_pending = len(task.operators) >= JIT_MIN_OPERATORS and jit.available()
        if self._jit_pending and jit_successors.kernel_loaded():
            # an earlier task of this process loaded the compiled walk: use it at once
            self._calls = JIT_AFTER_CALLS

    def _build_trie(self) -> Trie:
        frequency = Counter(f for op in self.task.operators for f in op.precondition)
        root = _Node()
        for index, op in enumerate(self.task.operators):
            node = root
            for fact in sorted(op.precondition, key=lambda f: (-frequency[f], f)):
                node = node.children.setdefault(fact, _Node())
            node.operators.append(index)

        def freeze(node: _Node) -> Trie:
            children = tuple((1 << f, freeze(child)) for f, child in node.children.items())
            return tuple(node.operators), children

        return freeze(root)

    def applicable(self, state: int) -> list[int]:
        """Indices of the operators applicable in ``state`` (the same list, in the same order,
        from the compiled trie walk once it is in use)."""
        if self._jit is not None:
            return self._jit.applicable(state)
        if self._jit_pending:
            self._calls += 1
            if self._calls >= JIT_AFTER_CALLS:
                try:
                    self.use_compiled_successors()
                    return self.applicable(state)
                except jit.CompiledCodeUnavailable as error:
                    logger.warning("%s; the search goes on without compiled code", error)
                    self._jit_pending = False
        result: list[int] = []
        stack = [self._root]
        while stack:
            ops, children = stack.pop()
            if ops:
                result.extend(ops)
            for fact_bit, child in children:
                if state & fact_bit:
                    stack.append(child)
        operators = self.operators
        return [i for i in result if not state & operators[i][1]]

    def use_compiled_successors(self) -> None:
        """Walk the trie in compiled code from now on (numba must be installed)."""
        negative = [tuple(op.negative_precondition) for op in self.task.operators]
        self._jit = JitSuccessors(self._root, negative, len(self.task.facts))
        self._jit_pending = False

    def successor(self, state: int, index: int) -> int:
        _pre, _neg, add, delete, conditional, _cost = self.operators[index]
        if conditional:
            for cond, neg_cond, cond_add, cond_delete in conditional:
                if state & cond == cond and not state & neg_cond:
                    add |= cond_add
                    delete |= cond_delete
        new = (state & ~delete) | add
        if self.strata:
            new = self.close(new)
        return new

    def close(self, state: int) -> int:
        """Recompute the derived facts of ``state`` (stratum by stratum, to a fixpoint)."""
        if not self.strata:
            return state
        state &= ~self.derived_mask
        known = self._closed.get(state)
        if known is not None:
            return known
        basic = state
        for layer, counted in zip(self.strata, self.counted, strict=True):
            if counted is not None:
                state = counted.close(state)
                continue
            pending = layer
            while pending:
                waiting = []
                for head, body, negative in pending:
                    if state & body == body and not state & negative:
                        state |= head
                    else:
                        waiting.append((head, body, negative))
                if len(waiting) == len(pending):
                    break
                pending = waiting
        if len(self._closed) < CLOSED_MEMO:
            self._closed[basic] = state
        return state

    def is_goal(self, state: int) -> bool:
        return state & self.goal_mask == self.goal_mask and not state & self.negative_goal_mask
