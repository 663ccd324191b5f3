"""Complements of negated facts, so that the delete relaxation sees negative conditions.

The delete relaxation ignores negative conditions, so ``(not p)`` costs nothing there and a
heuristic can miss everything it asks for. Two cases, as Fast Downward's translation into
binary variables treats them:

* **A fluent** ``p`` that some condition or the goal negates gets a fact of its own, the
  *complement* ``~p``: true where ``p`` is false, and achieved by every effect that deletes
  ``p`` (and does not add it). IPC's quantum-layout has only negative goals: without them
  every state looks like a goal to h_FF.
* **A derived fact** ``A`` (``(not (exists ...))``, ``(forall ...)``, ``(imply ...)`` in ADL
  domains) holds when no rule of ``A`` applies. ``~A`` gets rules that derive it when every
  rule of ``A`` is blocked: a rule is blocked by the negation of one of its literals, so the
  complement's rules are the conjunctions that pick one negated literal from every rule (CNF to
  DNF). A rule with a positive fluent literal never needs blocking here (its negation counts
  as free); ``not q`` is blocked by ``q``; a derived literal ``B`` by ``~B`` unless ``B``
  depends on ``A`` in turn (then it counts as free, which keeps the relaxation an
  over-approximation under recursion); ``not B`` by ``B``. A rule with an empty body makes
  ``A`` always true, so ``~A`` has no rules. When the conjunctions would number more than
  ``max_rules``, ``not A`` stays ignored. In IPC's assembly, ``complete ?whole`` needs every
  part of the whole incorporated: h_FF of the initial state goes from 1 to 24.

A state's complements are those of its false facts (:meth:`Complements.extend`); from there the
relaxed exploration may reach more. Every complement that holds in a state reachable from it is
reachable in the relaxation, so heuristics stay as safe about dead ends as before, and better
informed.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

from solvers.classical.bitset_task import bits
from solvers.classical.task import GroundTask

#: The most rules one complement may get (the CNF-to-DNF product can grow exponentially).
MAX_RULES = 64


@dataclass(frozen=True)
class Complements:
    """Complement facts numbered from ``base`` (the task's fact count): ``of`` maps a negated
    fact (derived or fluent) to its complement; ``rules`` are the derived complements'
    ``(body, complement)`` pairs (bodies of fact ids, complements included)."""

    base: int
    of: dict[int, int]
    rules: tuple[tuple[tuple[int, ...], int], ...]
    _mask: int = field(default=0, init=False, repr=False)  # the facts with complements
    _all: int = field(default=0, init=False, repr=False)  # every complement

    @property
    def count(self) -> int:
        """Facts of the relaxed task: the task's, then the complements."""
        return self.base + len(self.of)

    def positive(self, positive: tuple[int, ...], negative: tuple[int, ...]) -> tuple[int, ...]:
        """A condition's positive facts with the complements of its negated facts (those that
        have one)."""
        extra = tuple(self.of[f] for f in negative if f in self.of)
        return positive + extra if extra else positive

    def deleted(self, deletes: tuple[int, ...], adds: tuple[int, ...]) -> tuple[int, ...]:
        """The complements an effect achieves: of the facts it deletes and does not add."""
        return tuple(self.of[f] for f in deletes if f in self.of and f not in adds)

    def extend(self, state: int) -> int:
        """``state`` with the complement of every fact false in it."""
        if not self.of:
            return state
        out = state | self._all
        for fact in bits(state & self._mask):
            out ^= 1 << self.of[fact]
        return out

    def __post_init__(self) -> None:
        mask = all_ = 0
        for fact, complement in self.of.items():
            mask |= 1 << fact
            all_ |= 1 << complement
        object.__setattr__(self, "_mask", mask)
        object.__setattr__(self, "_all", all_)


def relaxed_operators(
    task: GroundTask, comp: Complements
) -> list[tuple[tuple[int, ...], tuple[int, ...], int]]:
    """The delete relaxation of ``task`` with the complements ``comp``, as unary operators
    ``(condition, adds, operator index)``: per operator, its unconditional adds under its
    precondition and each conditional effect under precondition + condition (groups without
    adds dropped), then the axioms and the complements' rules (index -1). Conditions are
    sorted and free of repeats; negated facts become their complements, deletes add them."""
    out: list[tuple[tuple[int, ...], tuple[int, ...], int]] = []
    for index, op in enumerate(task.operators):
        pre = comp.positive(op.precondition, op.negative_precondition)
        groups = [(pre, op.adds + comp.deleted(op.deletes, op.adds))]
        groups += [
            (
                pre + comp.positive(c.condition, c.negative_condition),
                c.adds + comp.deleted(c.deletes, c.adds),
            )
            for c in op.conditional
        ]
        out += [(tuple(sorted(set(cond))), adds, index) for cond, adds in groups if adds]
    rules = [(comp.positive(a.body, a.negative_body), a.head) for a in task.axioms]
    out += [(tuple(sorted(set(body))), (head,), -1) for body, head in [*rules, *comp.rules]]
    return out


def complements(task: GroundTask, max_rules: int = MAX_RULES) -> Complements:
    """The complements of the facts that some condition of ``task`` negates (see the module
    docstring), and of the derived facts their rules need in turn."""
    base = len(task.facts)
    derived = task.derived
    negated = [f for op in task.operators for f in op.negative_precondition]
    negated += [f for op in task.operators for c in op.conditional for f in c.negative_condition]
    negated += [f for a in task.axioms for f in a.negative_body]
    negated += list(task.negative_goal)
    fluents = sorted({f for f in negated if f not in derived})
    bodies = _derived_bodies(task, [f for f in negated if f in derived], max_rules)
    of: dict[int, int] = {}
    for head in sorted(h for h, d in bodies.items() if d is not None):
        of[head] = base + len(of)
    for fact in fluents:
        of[fact] = base + len(of)
    rules = tuple(
        (tuple(sorted(f if kind == "fact" else of[f] for kind, f in d)), of[head])
        for head in sorted(h for h in of if h in bodies)
        for d in bodies[head] or ()
    )
    return Complements(base, of, rules)


def _derived_bodies(
    task: GroundTask, wanted: list[int], max_rules: int
) -> dict[int, list[frozenset[tuple[str, int]]] | None]:
    """The rules of the complements of the derived facts ``wanted`` and of those their rules
    need, as sets of literals (``("fact", f)`` needs ``f``, ``("not", B)`` needs ``~B``); None
    for a complement that is not built."""
    if not wanted:
        return {}
    rules_of: dict[int, list[tuple[tuple[int, ...], tuple[int, ...]]]] = {}
    for axiom in task.axioms:
        rules_of.setdefault(axiom.head, []).append((axiom.body, axiom.negative_body))
    derived = task.derived
    component = _components(
        {h: {f for body, _ in rules for f in body if f in derived} for h, rules in rules_of.items()}
    )
    bodies: dict[int, list[frozenset[tuple[str, int]]] | None] = {}
    todo = list(dict.fromkeys(wanted))
    while todo:
        head = todo.pop()
        if head in bodies:
            continue
        disjuncts = _negated(head, rules_of.get(head, []), component, derived, max_rules)
        bodies[head] = disjuncts
        if disjuncts is not None:
            todo.extend(b for d in disjuncts for kind, b in d if kind == "not" and b not in bodies)
    # a complement whose rules need one that could not be built is dropped too, to a fixpoint
    changed = True
    while changed:
        changed = False
        for head, disjuncts in bodies.items():
            if disjuncts is not None and any(
                kind == "not" and bodies.get(b) is None for d in disjuncts for kind, b in d
            ):
                bodies[head] = None
                changed = True
    return bodies


def _components(edges: dict[int, set[int]]) -> dict[int, int]:
    """Strongly connected components of a graph (node -> successors): a component number per
    node (iterative Tarjan)."""
    index: dict[int, int] = {}
    low: dict[int, int] = {}
    component: dict[int, int] = {}
    stack: list[int] = []
    on_stack: set[int] = set()
    count = 0
    for root in edges:
        if root in index:
            continue
        work = [(root, iter(edges.get(root, ())))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            for nxt in successors:
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(edges.get(nxt, ()))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component[member] = count
                        if member == node:
                            break
                    count += 1
    return component


def _negated(
    head: int,
    rules: list[tuple[tuple[int, ...], tuple[int, ...]]],
    component: dict[int, int],
    derived: frozenset[int],
    max_rules: int,
) -> list[frozenset[tuple[str, int]]] | None:
    """The rules of ``~head`` (a list of literal sets, one per rule; empty: never derivable),
    or None when they would be more than ``max_rules``."""
    options: list[list[tuple[str, int]]] = []
    for body, negative_body in rules:
        choices: list[tuple[str, int]] = []
        free = False
        for fact in body:
            if fact not in derived or component.get(fact) == component.get(head):
                free = True  # not p is free in the relaxation (or unsafe to use: recursion)
                break
            choices.append(("not", fact))
        if free:
            continue
        choices += [("fact", fact) for fact in negative_body]
        if not choices:
            return []  # a rule with an empty body: head is always true
        options.append(choices)
    total = 1
    for choices in options:
        total *= len(choices)
        if total > max_rules:
            return None
    disjuncts = {frozenset(pick) for pick in itertools.product(*options)}
    # keep the minimal ones: a superset asks for more and derives nothing new
    return sorted(
        (d for d in disjuncts if not any(o < d for o in disjuncts)),
        key=lambda d: sorted(d),
    )
