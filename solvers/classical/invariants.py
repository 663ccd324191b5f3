"""Mutex groups by invariant synthesis: sets of facts of which at most one holds in any state.

An *invariant candidate* is a set of parts, each a predicate with the argument positions of the
invariant's parameters (every part has the same number ``k`` of them, and at most one other,
*counted*, position). For a value of the parameters it names a group of ground facts: those of
its predicates whose arguments at the parameter positions are those values. The candidate is an
invariant when no reachable state has two facts of one group true (Helmert 2009, "Concise
finite-domain representations for PDDL planning tasks").

Candidates start from single predicates (no argument counted, or each in turn) and are
proven inductively on the ground task: no group has two facts in the initial state, and every
operator that adds a fact of a group it did not require also requires and deletes a fact of
that group. An operator that requires two facts of one group is never applicable (the
invariant holds before it, by induction) and is skipped. An operator that adds a group fact
without such a balancing delete refines the candidate: each fact it requires and deletes
that carries the group's parameter values gives a candidate with one more part (``drop``
adds ``(at ?c ?p)`` and deletes ``(lifting ?h ?c)``: ``{at(c, *)}`` grows into ``{at(c, *),
lifting(*, c)}``). A conditional effect that adds a group fact, or two group facts added at
once, rejects the candidate. Derived predicates are never part of a candidate.

The proof runs on the grounded operators (those relaxed-reachable from the initial state), so
it is sound for every state the task can reach. The work is bounded by a count of operator
checks (:data:`MAX_CHECKS`), not by time, so results do not depend on the machine.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from itertools import permutations

from solvers.classical.task import GroundTask

#: Operator checks (one operator against one candidate) spent at most on the synthesis.
MAX_CHECKS = 400_000
#: Parts a candidate may have.
MAX_PARTS = 4

Part = tuple[str, tuple[int, ...]]  # predicate, positions of the parameters in its arguments
Candidate = frozenset[Part]


@dataclass(frozen=True)
class MutexGroups:
    """Groups of facts (ids of a ground task) of which at most one is true in any reachable
    state, and the invariants they come from."""

    groups: tuple[frozenset[int], ...]
    invariants: tuple[Candidate, ...]
    _of: dict[int, tuple[int, ...]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        of: dict[int, list[int]] = {}
        for index, group in enumerate(self.groups):
            for fact in group:
                of.setdefault(fact, []).append(index)
        self._of.update((f, tuple(g)) for f, g in of.items())

    def of(self, fact: int) -> tuple[int, ...]:
        """The indices of the groups that contain ``fact``."""
        return self._of.get(fact, ())

    def mutex(self, a: int, b: int) -> bool:
        """Whether facts ``a`` and ``b`` (distinct) can never hold together."""
        if a == b:
            return False
        groups = self.of(a)
        return any(g in groups for g in self.of(b))


class _Synthesis:
    def __init__(self, task: GroundTask, max_checks: int) -> None:
        self.task = task
        self.budget = max_checks
        facts = task.facts
        fluent: set[int] = set()
        for op in task.operators:
            fluent.update(op.adds, op.deletes)
            for effect in op.conditional:
                fluent.update(effect.adds, effect.deletes)
        fluent -= task.derived
        self.fluent = fluent
        self._keys: dict[Part, dict[int, tuple[str, ...]]] = {}
        self.by_predicate: dict[str, list[int]] = {}
        for fact in sorted(fluent):
            self.by_predicate.setdefault(facts[fact].predicate, []).append(fact)
        self.arity = {p: len(facts[fs[0]].args) for p, fs in self.by_predicate.items()}
        # operators by the predicates they add, unconditionally or under a condition
        self.adding: dict[str, list[int]] = {}
        self.conditional_adds: dict[str, bool] = {}
        for index, op in enumerate(task.operators):
            for predicate in {facts[f].predicate for f in op.adds}:
                self.adding.setdefault(predicate, []).append(index)
            for effect in op.conditional:
                for fact in effect.adds:
                    self.conditional_adds[facts[fact].predicate] = True

    def initial(self) -> list[Candidate]:
        out: list[Candidate] = []
        for predicate in sorted(self.by_predicate):
            arity = self.arity[predicate]
            out.append(frozenset({(predicate, tuple(range(arity)))}))  # nothing counted
            for counted in range(arity):
                positions = tuple(i for i in range(arity) if i != counted)
                out.append(frozenset({(predicate, positions)}))
        return out

    def key(self, fact: int, positions: tuple[int, ...]) -> tuple[str, ...]:
        args = self.task.facts[fact].args
        return tuple(args[i] for i in positions)

    def keys(self, part: Part) -> dict[int, tuple[str, ...]]:
        """The group key of every fluent fact of ``part``'s predicate."""
        found = self._keys.get(part)
        if found is None:
            predicate, positions = part
            found = {f: self.key(f, positions) for f in self.by_predicate.get(predicate, ())}
            self._keys[part] = found
        return found

    def check(self, candidate: Candidate) -> tuple[bool, list[Candidate]]:
        """Whether ``candidate`` is an invariant; if not, the refinements to try."""
        if any(self.conditional_adds.get(p) for p, _ in candidate):
            return False, []
        key_of: dict[int, tuple[str, ...]] = {}
        for part in candidate:
            key_of.update(self.keys(part))
        seen: set[tuple[str, ...]] = set()
        for fact in self.task.init:
            key = key_of.get(fact)
            if key is not None:
                if key in seen:
                    return False, []
                seen.add(key)
        operators = sorted({i for p, _ in candidate for i in self.adding.get(p, ())})
        all_operators = self.task.operators
        for index in operators:
            self.budget -= 1
            if self.budget < 0:
                return False, []
            op = all_operators[index]
            required: dict[tuple[str, ...], int] = {}
            for fact in op.precondition:
                key = key_of.get(fact)
                if key is not None and required.setdefault(key, fact) != fact:
                    break  # requires two facts of one group: never applicable
            else:
                added: dict[tuple[str, ...], int] = {}
                for fact in op.adds:
                    key = key_of.get(fact)
                    if key is None or required.get(key) == fact:
                        continue  # not in a group, or required: no new fact
                    if added.setdefault(key, fact) != fact:
                        return False, []  # two new facts of one group at once
                for key in added:
                    gone = required.get(key)
                    if gone is None or gone not in op.deletes or gone in op.adds:
                        deleted = [
                            d for d in op.precondition if d in op.deletes and d not in op.adds
                        ]
                        return False, self._refinements(candidate, key, deleted)
        return True, []

    def _refinements(
        self, candidate: Candidate, key: tuple[str, ...], deleted: Iterable[int]
    ) -> list[Candidate]:
        if len(candidate) >= MAX_PARTS:
            return []
        used = {p for p, _ in candidate}
        out: list[Candidate] = []
        for fact in sorted(deleted):
            atom = self.task.facts[fact]
            if atom.predicate in used or fact not in self.fluent:
                continue
            arity = len(atom.args)
            if not 0 <= arity - len(key) <= 1:
                continue
            for positions in permutations(range(arity), len(key)):
                if all(atom.args[i] == v for i, v in zip(positions, key, strict=True)):
                    out.append(candidate | {(atom.predicate, positions)})
        return out


def mutex_groups(task: GroundTask, max_checks: int = MAX_CHECKS) -> MutexGroups:
    """The mutex groups of ``task`` found by invariant synthesis (see the module docstring);
    groups of one fact are left out, and so are groups another one contains."""
    synthesis = _Synthesis(task, max_checks)
    queue = deque(synthesis.initial())
    tried: set[Candidate] = set(queue)
    proven: list[Candidate] = []
    while queue and synthesis.budget > 0:
        candidate = queue.popleft()
        ok, refinements = synthesis.check(candidate)
        if ok:
            proven.append(candidate)
            continue
        for refined in refinements:
            if refined not in tried:
                tried.add(refined)
                queue.append(refined)
    groups: set[frozenset[int]] = set()
    for candidate in proven:
        members: dict[tuple[str, ...], set[int]] = {}
        for predicate, positions in candidate:
            for fact in synthesis.by_predicate.get(predicate, ()):
                members.setdefault(synthesis.key(fact, positions), set()).add(fact)
        groups.update(frozenset(m) for m in members.values() if len(m) > 1)
    containing: dict[int, list[frozenset[int]]] = {}
    for group in groups:
        for fact in group:
            containing.setdefault(fact, []).append(group)
    kept = [
        g for g in groups if not any(g < other for other in containing[min(g)] if other is not g)
    ]
    kept.sort(key=lambda g: (-len(g), sorted(g)))
    return MutexGroups(tuple(kept), tuple(proven))
