"""Conjunctive queries over a growing set of relational facts (the grounding engine).

A query is a list of positive atoms (joined) plus *filters*: equality literals and negated
literals over predicates whose facts are fixed (checked as soon as their variables are bound).
Queries are compiled once into join plans that bind variables atom by atom, each step looking
up only the facts that agree with the values already bound (hash indexes built on demand).
"""

from __future__ import annotations

import time
from collections.abc import Collection, Iterable, Iterator, Mapping
from dataclasses import dataclass

from sdar_tamp.language.formula_model import EQUALITY
from solvers.classical.normalize import Lit

Fact = tuple[str, ...]

#: a join with a deadline looks at the clock once per this many candidate facts
DEADLINE_STRIDE = 1024


class GroundingTimeout(Exception):
    """The deadline passed while grounding (internal; :func:`plan` reports a timeout)."""


class FactBase:
    """Relations ``predicate -> set of argument tuples`` with lazily built hash indexes."""

    def __init__(self, facts: Iterable[tuple[str, Fact]] = ()) -> None:
        self.relations: dict[str, set[Fact]] = {}
        self._indexes: dict[str, dict[tuple[int, ...], dict[Fact, list[Fact]]]] = {}
        relations = self.relations
        for predicate, args in facts:  # no index exists yet: filling the sets is enough
            relation = relations.get(predicate)
            if relation is None:
                relation = relations[predicate] = set()
            relation.add(args)

    def add(self, predicate: str, args: Fact) -> bool:
        """Add a fact; False when it was already there."""
        relation = self.relations.setdefault(predicate, set())
        if args in relation:
            return False
        relation.add(args)
        for positions, index in self._indexes.get(predicate, {}).items():
            index.setdefault(tuple(args[p] for p in positions), []).append(args)
        return True

    def contains(self, predicate: str, args: Fact) -> bool:
        return args in self.relations.get(predicate, ())

    def index(self, predicate: str, positions: tuple[int, ...]) -> dict[Fact, list[Fact]]:
        by_positions = self._indexes.setdefault(predicate, {})
        index = by_positions.get(positions)
        if index is None:
            index = {}
            for args in self.relations.get(predicate, ()):
                index.setdefault(tuple(args[p] for p in positions), []).append(args)
            by_positions[positions] = index
        return index


@dataclass(frozen=True)
class _Step:
    predicate: str
    arity: int
    key_positions: tuple[int, ...]
    key_terms: tuple[str, ...]  # variables (already bound) or constants
    outputs: tuple[tuple[int, str], ...]  # first occurrences of new variables
    repeats: tuple[tuple[int, int], ...]  # (position, earlier position) of a repeated variable
    filters: tuple[Lit, ...]  # checked once this step has bound its variables


@dataclass(frozen=True)
class JoinPlan:
    steps: tuple[_Step, ...]
    initial_filters: tuple[Lit, ...]


def compile_join(
    atoms: list[Lit],
    filters: list[Lit],
    prebound: Collection[str] = (),
    first: int | None = None,
    sizes: Mapping[str, int] | None = None,
) -> JoinPlan:
    """Order ``atoms`` (``first`` leads) so that each step binds as few candidates as it can.

    Atoms whose terms are all bound come first (each is a lookup that can only prune), then
    those sharing the most bound terms; ``sizes`` (facts per predicate, when known) breaks a
    tie in favour of the smaller relation, so a join starts from the few facts of a fluent
    rather than from a large static relation over the same variables.
    """
    bound = set(prebound)
    remaining = list(range(len(atoms)))
    pending = list(filters)
    steps: list[_Step] = []

    def ready(lit: Lit) -> bool:
        return all(not a.startswith("?") or a in bound for a in lit.args)

    initial = [f for f in pending if ready(f)]
    pending = [f for f in pending if not ready(f)]
    while remaining:
        if first is not None and not steps:
            chosen = first
        else:
            # on a full tie the later atom, since callers put the broad type literals
            # ``(type ?x)`` before the body atoms, which are usually smaller
            chosen = max(remaining, key=lambda i: _priority(atoms[i], bound, sizes, i))
        remaining.remove(chosen)
        atom = atoms[chosen]
        key_positions: list[int] = []
        key_terms: list[str] = []
        outputs: list[tuple[int, str]] = []
        repeats: list[tuple[int, int]] = []
        seen: dict[str, int] = {}
        for position, term in enumerate(atom.args):
            if not term.startswith("?") or term in bound:
                key_positions.append(position)
                key_terms.append(term)
            elif term in seen:
                repeats.append((position, seen[term]))
            else:
                seen[term] = position
                outputs.append((position, term))
        bound.update(seen)
        now = [f for f in pending if ready(f)]
        pending = [f for f in pending if not ready(f)]
        steps.append(
            _Step(
                atom.predicate,
                len(atom.args),
                tuple(key_positions),
                tuple(key_terms),
                tuple(outputs),
                tuple(repeats),
                tuple(now),
            )
        )
    if pending:
        unbound = sorted({a for f in pending for a in f.args if a.startswith("?")} - bound)
        raise ValueError(f"unbound variables in filter literals: {unbound}")
    return JoinPlan(tuple(steps), tuple(initial))


def _priority(
    atom: Lit, bound: Collection[str], sizes: Mapping[str, int] | None, index: int
) -> tuple[bool, int, int, int]:
    known = sum(1 for a in atom.args if not a.startswith("?") or a in bound)
    size = sizes.get(atom.predicate, 0) if sizes is not None else 0
    return (known == len(atom.args), known, -size, index)


def _value(term: str, binding: dict[str, str]) -> str:
    return binding[term] if term.startswith("?") else term


def check_filter(lit: Lit, binding: dict[str, str], facts: FactBase) -> bool:
    args = tuple(_value(a, binding) for a in lit.args)
    if lit.predicate == EQUALITY:
        holds = len(set(args)) <= 1
    else:
        holds = facts.contains(lit.predicate, args)
    return holds == lit.positive


def run_join(
    plan: JoinPlan,
    facts: FactBase,
    binding: dict[str, str] | None = None,
    delta: Collection[Fact] | None = None,
    deadline: float | None = None,
) -> Iterator[dict[str, str]]:
    """All bindings extending ``binding``; with ``delta`` the first step ranges over it only.

    The yielded dictionary is reused: read it before asking for the next binding. With a
    ``deadline`` (a ``time.perf_counter()`` value) the join checks the clock every
    :data:`DEADLINE_STRIDE` candidate facts, so one large join cannot overrun it.

    Raises:
        GroundingTimeout: the deadline passed during the join.
    """
    current = dict(binding or {})
    if not all(check_filter(f, current, facts) for f in plan.initial_filters):
        return
    steps = plan.steps
    count = len(steps)
    ticks = 0

    def extend(i: int) -> Iterator[dict[str, str]]:
        if i == count:
            yield current
            return
        step = steps[i]
        key = tuple(_value(t, current) for t in step.key_terms)
        candidates: Iterable[Fact]
        if i == 0 and delta is not None:
            positions = step.key_positions
            candidates = [
                c for c in delta if all(c[p] == k for p, k in zip(positions, key, strict=True))
            ]
        elif len(step.key_positions) == step.arity:
            candidates = (key,) if facts.contains(step.predicate, key) else ()
        elif step.key_positions:
            candidates = facts.index(step.predicate, step.key_positions).get(key, ())
        else:
            candidates = facts.relations.get(step.predicate, ())
        for args in candidates:
            if deadline is not None:
                nonlocal ticks
                ticks += 1
                if ticks % DEADLINE_STRIDE == 0 and time.perf_counter() > deadline:
                    raise GroundingTimeout
            if step.repeats and any(args[p] != args[q] for p, q in step.repeats):
                continue
            for position, var in step.outputs:
                current[var] = args[position]
            if all(check_filter(f, current, facts) for f in step.filters):
                yield from extend(i + 1)
        for _position, var in step.outputs:
            current.pop(var, None)

    yield from extend(0)
