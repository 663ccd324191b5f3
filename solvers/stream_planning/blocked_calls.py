"""Where a fluent stream failed, a plan may not assume its facts.

A ``:fluents`` stream answers for one state. When its call with the fluent facts ``F`` fails,
the planner must not use the facts it certifies (for those inputs) in a state that holds all of
``F`` (as in PDDLStream: more objects in the way do not make a motion possible). So every
positive use of a predicate a fluent stream certifies, in a precondition, an effect condition or
an axiom body, is guarded by ``(not (@blocked:<stream> <inputs>))`` (:func:`guard_fluent_uses`),
and each failure adds (:class:`Blocks`) the axiom::

    (@blocked:<stream> ?x1 .. ?xn) <- (@failed:<stream>:<k> ?x1 .. ?xn) and F

with the fact ``(@failed:<stream>:<k> <inputs>)``. A failed call of an instance that may still
produce blocks until the complexity level rises; an exhausted instance blocks for good. A use
whose certified fact does not name all the stream's inputs cannot be guarded and is left as is.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass, replace

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_model import Axiom, Domain, Predicate
from sdar_tamp.language.formula_model import And, Atom, Formula, Not, Parameter, is_variable
from sdar_tamp.language.stream_model import Stream
from sdar_tamp.language.traversal import map_atoms, map_conditions

BLOCKED = "@blocked:"
FAILED = "@failed:"


def blocked_predicate(stream: str) -> str:
    """The derived predicate that says a fluent stream failed in a state like the current one."""
    return f"{BLOCKED}{stream}"


def _certifiers(streams: Iterable[Stream]) -> dict[str, tuple[Stream, Atom]]:
    """Predicate -> the fluent stream certifying it and its certified atom."""
    found: dict[str, tuple[Stream, Atom]] = {}
    for stream in streams:
        if not stream.fluents:
            continue
        for atom in stream.certified:
            other = found.get(atom.predicate)
            if other is not None and other[0].name != stream.name:
                raise ParameterError(
                    f"fluent streams {other[0].name!r} and {stream.name!r} both certify "
                    f"{atom.predicate!r}; a predicate can have one fluent stream as its source"
                )
            found.setdefault(atom.predicate, (stream, atom))
    return found


def guard_fluent_uses(domain: Domain, streams: Iterable[Stream]) -> Domain:
    """``domain`` with each positive use of a fluent-certified fact guarded by the stream's
    blocked predicate (unchanged when no stream has ``:fluents``).

    Raises:
        ParameterError: two fluent streams certify the same predicate.
    """
    certifiers = _certifiers(streams)
    if not certifiers:
        return domain

    def guard(atom: Atom, positive: bool) -> Formula:
        found = certifiers.get(atom.predicate) if positive else None
        if found is None:
            return atom
        stream, template = found
        mapping = {t: a for t, a in zip(template.args, atom.args, strict=True) if is_variable(t)}
        if not all(i in mapping for i in stream.inputs):
            return atom
        blocked = Atom(blocked_predicate(stream.name), tuple(mapping[i] for i in stream.inputs))
        return And((atom, Not(blocked)))

    def guarded(formula: Formula) -> Formula:
        return map_atoms(formula, guard)

    predicates = dict(domain.predicates)
    for stream, _ in certifiers.values():
        name = blocked_predicate(stream.name)
        parameters = tuple(Parameter(f"?x{i}") for i in range(len(stream.inputs)))
        predicates[name] = Predicate(name, parameters)
    actions = tuple(
        replace(a, precondition=guarded(a.precondition), effect=map_conditions(a.effect, guarded))
        for a in domain.actions
    )
    axioms = tuple(replace(a, body=guarded(a.body)) for a in domain.axioms)
    return replace(domain, predicates=predicates, actions=actions, axioms=axioms)


@dataclass(frozen=True)
class Block:
    """A failed call of fluent stream ``stream`` on ``inputs`` in a state with ``fluents``."""

    stream: str
    inputs: tuple[str, ...]
    fluents: tuple[Atom, ...]
    permanent: bool
    index: int

    @property
    def fact(self) -> Atom:
        return Atom(f"{FAILED}{self.stream}:{self.index}", self.inputs)

    def axiom(self) -> Axiom:
        parameters = tuple(Parameter(f"?x{i}") for i in range(len(self.inputs)))
        names = tuple(p.name for p in parameters)
        body = And((Atom(self.fact.predicate, names), *self.fluents))
        return Axiom(blocked_predicate(self.stream), parameters, body)


class Blocks:
    """The blocks of one solve over a guarded domain (see :func:`guard_fluent_uses`)."""

    def __init__(self, domain: Domain) -> None:
        self.base = domain
        self._blocks: dict[tuple[str, tuple[str, ...], tuple[Atom, ...]], Block] = {}
        self._ids = itertools.count()
        self._domain: Domain | None = domain

    def __len__(self) -> int:
        return len(self._blocks)

    def add(
        self, stream: str, inputs: tuple[str, ...], fluents: tuple[Atom, ...], permanent: bool
    ) -> bool:
        """Record a failure; True when it blocks something not blocked before."""
        key = (stream, inputs, fluents)
        old = self._blocks.get(key)
        if old is not None and (old.permanent or not permanent):
            return False
        self._blocks[key] = Block(stream, inputs, fluents, permanent, next(self._ids))
        self._domain = None
        return True

    def blocked(self, stream: str, inputs: tuple[str, ...], fluents: Iterable[Atom]) -> bool:
        """Does a block apply to a call in a state holding ``fluents``?"""
        state = set(fluents)
        return any(
            b.stream == stream and b.inputs == inputs and state.issuperset(b.fluents)
            for b in self._blocks.values()
        )

    @property
    def temporary(self) -> int:
        return sum(1 for b in self._blocks.values() if not b.permanent)

    def lift(self) -> None:
        """Drop the blocks of failures that may not repeat (the complexity level rose)."""
        kept = {k: b for k, b in self._blocks.items() if b.permanent}
        if len(kept) != len(self._blocks):
            self._blocks = kept
            self._domain = None

    def domain(self) -> Domain:
        """The guarded domain with one axiom per block."""
        if self._domain is None:
            axioms = tuple(b.axiom() for b in self._blocks.values())
            predicates = dict(self.base.predicates)
            for block in self._blocks.values():
                fact = block.fact
                predicates[fact.predicate] = Predicate(
                    fact.predicate, tuple(Parameter(f"?x{i}") for i in range(len(fact.args)))
                )
            self._domain = replace(
                self.base, predicates=predicates, axioms=(*self.base.axioms, *axioms)
            )
        return self._domain

    def facts(self) -> frozenset[Atom]:
        return frozenset(b.fact for b in self._blocks.values())
