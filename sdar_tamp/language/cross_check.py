"""The stream file checked against the domain: what one certifies that the other never reads,
and what the domain reads that nothing can make true.

``unused-certified``
    a stream (or rule) certifies a predicate that no action precondition or effect
    condition, derived predicate, stream ``:domain`` or goal reads: the fact can never help a
    plan (often a typo of the predicate the domain uses). Located at the stream.
``unachievable-predicate``
    an action or derived predicate reads a predicate that no action adds, no derived predicate
    defines, no stream, rule or external predicate certifies and no initial fact holds: every
    use of it is false (often a typo in the domain or the stream file). Located at the first
    action or derived predicate that reads it.
``untyped-output``
    an action parameter of a declared type (``?p - room``) sits, in a precondition atom, where
    a stream certifies one of its outputs. A stream's outputs are new objects of type
    ``object`` unless the stream also certifies a type fact for them (``(room ?p)``), so the
    action can never use them there: often PDDL's typed-list rule bit (``?p ?r - room`` gives
    both variables the type ``room``). Located at the action.

Both are :class:`~sdar_tamp.language.leniency.Leniency` items: ``PDDLProblem.leniencies``
records them for a problem with streams (logged: ``unachievable-predicate`` as a warning,
``unused-certified`` at info level), and ``sdar check`` prints both as warnings (``--strict``
makes them errors).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import (
    OBJECT_TYPE,
    AndEffect,
    Atom,
    Effect,
    ForAllEffect,
    Formula,
    When,
)
from sdar_tamp.language.leniency import (
    UNACHIEVABLE_PREDICATE,
    UNTYPED_OUTPUT,
    UNUSED_CERTIFIED,
    Leniency,
)
from sdar_tamp.language.stream_model import (
    Rule,
    Stream,
    StreamFile,
    StreamFunction,
    StreamPredicate,
)
from sdar_tamp.language.traversal import iter_atoms, iter_effect_literals

EQUALITY = "="


def _effect_conditions(effect: Effect) -> Iterator[Formula]:
    """The conditions of the conditional effects inside ``effect``."""
    stack = [effect]
    while stack:
        node = stack.pop()
        if isinstance(node, When):
            yield node.condition
            stack.append(node.effect)
        elif isinstance(node, AndEffect):
            stack.extend(node.parts)
        elif isinstance(node, ForAllEffect):
            stack.append(node.effect)


def _reads(domain: Domain) -> Iterator[tuple[str, SourceLocation | None]]:
    """Each predicate an action or derived predicate reads, with where it is read."""
    for action in domain.actions:
        for formula in (action.precondition, *_effect_conditions(action.effect)):
            for atom in iter_atoms(formula):
                yield atom.predicate, action.location
    for axiom in domain.axioms:
        for atom in iter_atoms(axiom.body):
            yield atom.predicate, axiom.location


def _output_slots(domain: Domain, streams: StreamFile) -> dict[tuple[str, int], tuple[str, str]]:
    """(predicate, argument position) -> (stream, output) for every certified atom position
    filled by an output the stream gives no type (no certified unary type fact)."""
    types = domain.types
    slots = dict[tuple[str, int], tuple[str, str]]()
    for stream in streams.streams:
        typed = {
            a.args[0] for a in stream.certified if len(a.args) == 1 and a.predicate in types.parents
        }
        for atom in stream.certified:
            for position, arg in enumerate(atom.args):
                if arg in stream.outputs and arg not in typed:
                    slots.setdefault((atom.predicate, position), (stream.name, arg))
    return slots


def _untyped_outputs(domain: Domain, streams: StreamFile) -> Iterator[Leniency]:
    """The ``untyped-output`` warnings (see the module's docstring)."""
    slots = _output_slots(domain, streams)
    for action in domain.actions:
        typed = {p.name: p.type for p in action.parameters if p.type != OBJECT_TYPE}
        seen = set[str]()
        for atom in iter_atoms(action.precondition):
            for position, arg in enumerate(atom.args):
                slot = slots.get((atom.predicate, position))
                if arg not in typed or arg in seen or slot is None:
                    continue
                seen.add(arg)
                stream, output = slot
                yield Leniency(
                    UNTYPED_OUTPUT,
                    f"action {action.name!r}: parameter {arg} has type {typed[arg]!r}, but "
                    f"argument {position + 1} of {atom.predicate!r} is stream {stream!r}'s "
                    f"output {output}, an object of type 'object'; in a typed list "
                    f"'?a ?b - {typed[arg]}' both variables get the type (write '?a - object "
                    f"?b - {typed[arg]}'), or certify ({typed[arg]} {output}) in the stream",
                    action.location,
                )


def has_streams(streams: StreamFile) -> bool:
    return bool(streams.streams or streams.functions or streams.predicates or streams.rules)


def cross_check(
    domain: Domain,
    streams: StreamFile,
    init: Iterable[Atom] | None = None,
    goal: Formula | None = None,
) -> tuple[Leniency, ...]:
    """The warnings of ``streams`` against ``domain`` (see the module's docstring).

    Without ``init`` (the initial facts are not known), predicates the domain reads are not
    checked; without ``goal``, a certified predicate only the goal reads is reported.
    """
    reads = dict[str, SourceLocation | None]()
    for predicate, location in _reads(domain):
        reads.setdefault(predicate, location)
    read = set(reads)
    declarations: tuple[Stream | StreamFunction | StreamPredicate | Rule, ...] = (
        *streams.streams,
        *streams.functions,
        *streams.predicates,
        *streams.rules,
    )
    producers: tuple[Stream | Rule, ...] = (*streams.streams, *streams.rules)
    for declaration in declarations:
        read.update(a.predicate for a in declaration.domain)
    if goal is not None:
        read.update(a.predicate for a in iter_atoms(goal))
    found: list[Leniency] = list(_untyped_outputs(domain, streams))
    for producer in producers:
        label = "a rule" if isinstance(producer, Rule) else f"stream {producer.name!r}"
        for predicate in dict.fromkeys(a.predicate for a in producer.certified):
            if predicate not in read:
                found.append(
                    Leniency(
                        UNUSED_CERTIFIED,
                        f"{label} certifies {predicate!r}, which no action, derived "
                        "predicate, stream domain or goal reads",
                        producer.location,
                    )
                )
    if init is not None:
        made = {a.predicate for a in init}
        made.update(ax.predicate for ax in domain.axioms)
        for action in domain.actions:
            adds = (e for e in iter_effect_literals(action.effect) if not e.negated)
            made.update(e.atom.predicate for e in adds)
        for producer in producers:
            made.update(a.predicate for a in producer.certified)
        made.update(p.name for p in streams.predicates)
        made.update(domain.types.types())
        made.add(EQUALITY)
        for predicate, location in reads.items():
            if predicate not in made:
                found.append(
                    Leniency(
                        UNACHIEVABLE_PREDICATE,
                        f"{predicate!r} is read but no action adds it, no derived predicate "
                        "defines it, no stream certifies it and no initial fact holds it",
                        location,
                    )
                )
    return tuple(found)
