"""Fact landmarks and the landmark-count heuristic (as in LAMA).

A *landmark* is a fact that every plan makes true at some point. They are found by label
propagation over the delete relaxation (Zhu & Givan): the label of a fact is the set of facts
that any relaxed plan reaching it must reach first, ``label(f) = {f} ∪ ⋂_achievers ⋃_pre
label(pre)``, shrunk to a fixpoint from "everything". The goal's landmarks are the union of the
goal facts' labels. ``q`` in ``label(p)`` orders ``q`` before ``p`` (natural ordering); ``q`` is
*greedy-necessary* for ``p`` when it is a precondition of every achiever of ``p``.

The heuristic is path-dependent: a state carries the set of landmarks *accepted* on the path to
it (a landmark is accepted when it becomes true after all its predecessors were accepted).
``h = |not accepted| + |accepted but needed again|``, where a landmark is needed again when it is
false now and is a goal, or greedy-necessary for a landmark not yet accepted. All sets are
Python ``int`` bitsets over fact ids, so an update costs a few big-integer operations.

The propagation runs on the relaxed task with the complements of negated facts
(:mod:`solvers.classical.complements`), so a complement can be a landmark (a negative goal, a
negated precondition every achiever shares). *Disjunctive landmarks* (Richter, Helmert and
Westphal 2008, one level deep): when every achiever of a landmark has a precondition of one
predicate, one of those facts (at most :data:`MAX_DISJUNCTION`) must hold first; they get bits
after the facts and are accepted once any of their facts holds. Landmark states carry their
complements and satisfied disjunctions.

*Reasonable orderings* (Hoffmann, Porteous and Sebastia 2004) use the mutex groups of
:mod:`solvers.classical.invariants`: when achieving ``a`` destroys ``b`` and both are goals, or
both must hold together to first achieve a third landmark, ``b`` is accepted only after ``a``
(achieving ``b`` first would be undone). Without them, greedy search on depot spends its time
stacking crates that a later goal has to unstack again.
"""

from __future__ import annotations

from collections import deque

from solvers.classical.bitset_task import CompiledTask, bits, mask
from solvers.classical.complements import complements, relaxed_operators
from solvers.classical.invariants import MutexGroups, mutex_groups
from solvers.classical.task import GroundTask

#: The largest disjunctive landmark kept (as in Fast Downward's RHW landmarks).
MAX_DISJUNCTION = 4


class LandmarkCount:
    """Landmarks of a compiled task and the count heuristic over accepted-landmark sets."""

    def __init__(
        self, compiled: CompiledTask, disjunctive: bool = True, mutexes: bool = True
    ) -> None:
        task = compiled.task
        comp = complements(task)
        count = comp.count
        relaxed = relaxed_operators(task, comp)
        upre = [condition for condition, _adds, _op in relaxed]
        ueff = [adds for _condition, adds, _op in relaxed]
        pre_of: list[list[int]] = [[] for _ in range(count)]
        for u, pre in enumerate(upre):
            for fact in pre:
                pre_of[fact].append(u)
        init = comp.extend(compiled.init)
        label: list[int | None] = [None] * count
        for fact in bits(init):
            label[fact] = 1 << fact
        # greedy-necessary candidates: the preconditions shared by every reachable achiever
        shared: list[int | None] = [None] * count
        queue = deque(u for u, pre in enumerate(upre) if all(label[p] is not None for p in pre))
        queued = [False] * len(upre)
        for u in queue:
            queued[u] = True
        while queue:
            u = queue.popleft()
            queued[u] = False
            op_label = 0
            for p in upre[u]:
                lab = label[p]
                if lab is None:
                    break
                op_label |= lab
            else:
                pre_mask = mask(upre[u])
                for e in ueff[u]:
                    if init >> e & 1:
                        continue
                    old = label[e]
                    bit = 1 << e
                    new = op_label | bit if old is None else old & (op_label | bit)
                    previous = shared[e]
                    shared[e] = pre_mask if previous is None else previous & pre_mask
                    if new != old:
                        label[e] = new
                        for v in pre_of[e]:
                            if not queued[v]:
                                queued[v] = True
                                queue.append(v)
        goal = comp.positive(task.goal, task.negative_goal)
        self.reachable = all(label[g] is not None for g in goal)
        landmarks = 0
        for g in goal:
            landmarks |= label[g] or 0
        self.landmarks = landmarks
        self.goal_mask = mask(goal)
        self.complements = comp
        self._last = (-1, -1)  # the last state extended with its complements, and the result
        # parents: every landmark ordered before p (natural orderings, from the labels)
        self.parents: dict[int, int] = {}
        children_gn: dict[int, int] = {}
        for p in bits(landmarks):
            self.parents[p] = (label[p] or 0) & landmarks & ~(1 << p)
            for q in bits((shared[p] or 0) & landmarks):
                children_gn[q] = children_gn.get(q, 0) | 1 << p
        self.children_gn = children_gn
        self.gn_sources = mask(children_gn)
        self.reasonable = 0  # orderings added by :meth:`_reasonable_orders`
        if mutexes and self.reachable:
            self._reasonable_orders(task, mutex_groups(task), relaxed, label, init)
        # disjunctive landmarks, numbered after the facts: (their facts, their bit)
        self.disjunctions: list[tuple[int, int]] = []
        self._members = 0  # every fact of a disjunctive landmark
        self._of_member: dict[int, int] = {}  # such a fact -> the bits of its disjunctions
        if disjunctive:
            self._disjunctions(task, upre, ueff, label, init, count)

    def _ancestors(self, fact: int) -> int:
        """Every landmark ordered (transitively) before ``fact``."""
        seen = 0
        stack = [fact]
        while stack:
            for q in bits(self.parents.get(stack.pop(), 0) & ~seen):
                seen |= 1 << q
                stack.append(q)
        return seen

    def _reasonable_orders(
        self,
        task: GroundTask,
        groups: MutexGroups,
        relaxed: list[tuple[tuple[int, ...], tuple[int, ...], int]],
        label: list[int | None],
        init: int,
    ) -> None:
        """Reasonable orderings (Hoffmann, Porteous and Sebastia 2004, as LAMA approximates
        them): ``a`` before ``b`` when achieving ``a`` destroys ``b`` and both are goals, or
        both must hold together when a third landmark is first achieved (greedy-necessary for
        it). ``b`` is then accepted only after ``a``. Achieving ``a`` destroys ``b`` when they
        are mutex, every first achiever of ``a`` deletes ``b``, the first achievers share an
        add mutex with ``b``, or a greedy-necessary predecessor of ``a`` is mutex with ``b``."""
        base = len(task.facts)
        first: dict[int, list[int]] = {}  # landmark -> operators that can first achieve it
        wanted = {f for f in bits(self.landmarks) if f < base}
        for condition, adds, index in relaxed:
            if index < 0:
                continue
            for fact in adds:
                if fact in wanted and all(
                    (label[p] or 0) >> fact & 1 == 0 and label[p] is not None for p in condition
                ):
                    first.setdefault(fact, []).append(index)
        gn_parents: dict[int, int] = {}
        for q, children in self.children_gn.items():
            for p in bits(children):
                gn_parents[p] = gn_parents.get(p, 0) | 1 << q
        operators = task.operators
        destroys: dict[int, tuple[set[tuple[int, int]], set[int]]] = {}

        def destroyed(a: int, among: frozenset[int]) -> set[int]:
            """The facts of ``among`` that achieving ``a`` destroys."""
            found = destroys.get(a)
            if found is None:
                # what is mutex with a, with an add its first achievers share, or with one of
                # its greedy-necessary predecessors (groups, each with the fact it is kin of);
                # and what every first achiever deletes
                kin = {(g, a) for g in groups.of(a)}
                deleted: set[int] = set()
                ops = [operators[i] for i in sorted(set(first.get(a, ())))]
                if ops:
                    deleted = set(ops[0].deletes).difference(ops[0].adds)
                    shared = set(ops[0].adds)
                    for op in ops[1:]:
                        deleted.intersection_update(op.deletes)
                        deleted.difference_update(op.adds)
                        shared.intersection_update(op.adds)
                    kin.update((g, e) for e in shared for g in groups.of(e))
                for x in bits(gn_parents.get(a, 0)):
                    if x < base:
                        kin.update((g, x) for g in groups.of(x))
                found = destroys[a] = (kin, deleted)
            kin, deleted = found
            out = deleted & among
            for g, fact in kin:
                out |= (groups.groups[g] & among) - {fact}
            out.discard(a)
            return out

        pairs: set[tuple[int, int]] = set()
        goals = frozenset(f for f in bits(self.goal_mask & self.landmarks) if f < base)
        pairs.update((a, b) for a in goals for b in destroyed(a, goals))
        for q in sorted(gn_parents):
            together = frozenset(p for p in bits(gn_parents[q]) if p < base)
            pairs.update((a, b) for a in together for b in destroyed(a, together))
        ancestors: dict[int, int] = {}  # cleared whenever an ordering is added
        for a, b in sorted(pairs):
            if init >> b & 1 and not self.goal_mask >> b & 1:
                continue
            if self.parents[b] >> a & 1:
                continue
            if a not in ancestors:
                ancestors[a] = self._ancestors(a)
            if ancestors[a] >> b & 1:
                continue  # b is ordered before a already: no cycle
            self.parents[b] |= 1 << a
            self.reasonable += 1
            ancestors.clear()

    def _disjunctions(
        self,
        task: GroundTask,
        upre: list[tuple[int, ...]],
        ueff: list[tuple[int, ...]],
        label: list[int | None],
        init: int,
        count: int,
    ) -> None:
        """Disjunctive landmarks (Richter, Helmert and Westphal 2008, one level): for a fact
        landmark false initially, if every reachable achiever has a precondition of predicate
        P, one of those facts must hold before the landmark first does. Kept when they are at
        most :data:`MAX_DISJUNCTION` facts, none true initially and none a fact landmark; each
        is ordered before its landmark."""
        base = len(task.facts)
        achievers: dict[int, list[int]] = {}
        for u, adds in enumerate(ueff):
            if all(label[p] is not None for p in upre[u]):
                for fact in adds:
                    achievers.setdefault(fact, []).append(u)
        found: dict[int, int] = {}  # members mask -> bit
        for fact in bits(self.landmarks):
            if init >> fact & 1 or fact >= base or not achievers.get(fact):
                continue
            groups: dict[str, int] | None = None
            for u in achievers[fact]:
                mine: dict[str, int] = {}
                for p in upre[u]:
                    if p < base:
                        name = task.facts[p].predicate
                        mine[name] = mine.get(name, 0) | 1 << p
                if groups is None:
                    groups = mine
                else:
                    groups = {k: v | mine[k] for k, v in groups.items() if k in mine}
                if not groups:
                    break
            for members in (groups or {}).values():
                size = members.bit_count()
                if not 2 <= size <= MAX_DISJUNCTION or members & (init | self.landmarks):
                    continue
                bit = found.get(members)
                if bit is None:
                    bit = 1 << (count + len(found))
                    found[members] = bit
                    self.disjunctions.append((members, bit))
                    self.parents[bit.bit_length() - 1] = 0
                    self.landmarks |= bit
                self.parents[fact] |= bit
        for members, bit in self.disjunctions:
            self._members |= members
            for fact in bits(members):
                self._of_member[fact] = self._of_member.get(fact, 0) | bit

    def __len__(self) -> int:
        return self.landmarks.bit_count()

    def _extended(self, state: int) -> int:
        """``state`` with its complements (landmarks may be complements of facts) and the bits
        of the disjunctive landmarks it satisfies."""
        if self._last[0] != state:
            extended = self.complements.extend(state)
            if self.disjunctions:
                of_member = self._of_member
                for fact in bits(state & self._members):
                    extended |= of_member[fact]
            self._last = (state, extended)
        return self._last[1]

    def initial(self, state: int) -> int:
        """The accepted set of the initial state: the landmarks true in it."""
        return self._extended(state) & self.landmarks

    def update(self, reached: int, state: int) -> int:
        """The accepted set of ``state``, reached from a state whose accepted set is ``reached``."""
        state = self._extended(state)
        new = state & self.landmarks & ~reached
        if not new:
            return reached
        parents = self.parents
        accepted = reached
        while new:
            low = new & -new
            new ^= low
            if not parents[low.bit_length() - 1] & ~reached:
                accepted |= low
        return accepted

    def value(self, reached: int, state: int) -> int:
        """Landmarks not accepted, plus accepted ones needed again."""
        state = self._extended(state)
        h = (self.landmarks & ~reached).bit_count()
        lost = reached & ~state
        if not lost:
            return h
        h += (lost & self.goal_mask).bit_count()
        candidates = lost & self.gn_sources & ~self.goal_mask
        children = self.children_gn
        while candidates:
            low = candidates & -candidates
            candidates ^= low
            if children[low.bit_length() - 1] & ~reached:
                h += 1
        return h
