"""Exogenous streams: a stream whose domain mentions a fluent fact (one that actions change).

Such a stream cannot be evaluated once and for all: whether its outputs are usable depends on
the state. It is compiled, as PDDLStream does with ``EXOGENOUS_AXIOMS``, into

- a static stream: its domain without the fluent facts, every certified fact ``P`` of every
  stream renamed ``f-P`` (its *future* form), plus a ``<stream>-result`` fact over its inputs
  and outputs; rules give ``f-P`` for every static ``P`` fact;
- derived predicates ``d-P`` used by the actions in place of ``P``: ``d-P`` holds where ``P``
  holds (a fact of ``init``) and where a stream result holds together with the stream's whole
  domain, fluent facts included, in the current state.

The samplers are the program's own, unchanged (``EXOGENOUS_AXIOMS`` and ``REPLACE_STREAM``
are accepted as module flags; only the axiom compilation is implemented).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import replace

from sdar_tamp.language.domain_model import Axiom, Domain, Predicate
from sdar_tamp.language.formula_model import And, Atom, Effect, Exists, Formula, Parameter
from sdar_tamp.language.stream_model import Rule, Stream, StreamFile
from sdar_tamp.language.traversal import iter_effect_literals, map_atoms, map_conditions

#: PDDLStream's public names here (the functions below are this tree's compilation)
__all__ = ["EXOGENOUS_AXIOMS", "REPLACE_STREAM"]

LOG = logging.getLogger(__name__)
EXOGENOUS_AXIOMS = True
REPLACE_STREAM = True


def fluent_predicates(domain: Domain) -> frozenset[str]:
    """Predicates some action adds or deletes."""
    return frozenset(
        literal.atom.predicate
        for action in domain.actions
        for literal in iter_effect_literals(action.effect)
    )


def exogenous_streams(domain: Domain, streams: StreamFile) -> list[str]:
    """Names of the streams whose domain mentions a fluent predicate."""
    fluent = fluent_predicates(domain)
    return [s.name for s in streams.streams if any(atom.predicate in fluent for atom in s.domain)]


def _rename(formula: Formula, mapping: Mapping[str, str]) -> Formula:
    return map_atoms(formula, lambda atom, _positive: _renamed(atom, mapping))


def _rename_conditions(effect: Effect, mapping: Mapping[str, str]) -> Effect:
    return map_conditions(effect, lambda condition: _rename(condition, mapping))


def _renamed(atom: Atom, mapping: Mapping[str, str]) -> Atom:
    return Atom(mapping.get(atom.predicate, atom.predicate), atom.args)


def _predicate(name: str, arity: int) -> Predicate:
    return Predicate(name, tuple(Parameter(f"?x{i}") for i in range(arity)))


def rename_predicates(formula: Formula, mapping: Mapping[str, str]) -> Formula:
    """``formula`` with the predicates in ``mapping`` renamed."""
    return _rename(formula, mapping)


def compile_exogenous(
    domain: Domain, streams: StreamFile
) -> tuple[Domain, StreamFile, Mapping[str, str]]:
    """``domain`` and ``streams`` with exogenous streams compiled away, and the renaming the
    goal needs (all unchanged, and an empty renaming, when there is no exogenous stream)."""
    names = exogenous_streams(domain, streams)
    if not names:
        return domain, streams, {}
    LOG.info("streams with fluent domain facts, compiled as exogenous: %s", ", ".join(names))
    fluent = fluent_predicates(domain)
    arity: dict[str, int] = {p.name: p.arity for p in domain.predicates.values()}
    for stream in streams.streams:
        for atom in (*stream.domain, *stream.certified):
            arity.setdefault(atom.predicate, len(atom.args))
    certified = sorted({a.predicate for s in streams.streams for a in s.certified})
    future = {p: f"f-{p}" for p in certified}
    derived = {p: f"d-{p}" for p in certified}
    predicates = dict(domain.predicates)
    for name in certified:
        predicates[future[name]] = _predicate(future[name], arity[name])
        predicates[derived[name]] = _predicate(derived[name], arity[name])
    new_streams: list[Stream] = []
    axioms = list(domain.axioms)
    for stream in streams.streams:
        result = Atom(f"{stream.name}-result", (*stream.inputs, *stream.outputs))
        predicates[result.predicate] = _predicate(result.predicate, len(result.args))
        static = tuple(_renamed(a, future) for a in stream.domain if a.predicate not in fluent)
        new_streams.append(
            replace(
                stream,
                domain=static,
                certified=(result, *(_renamed(a, future) for a in stream.certified)),
            )
        )
        condition = (result, *(_renamed(a, derived) for a in stream.domain))
        for fact in stream.certified:
            outer = tuple(dict.fromkeys(a for a in fact.args if a.startswith("?")))
            inner = tuple(Parameter(v) for v in (*stream.inputs, *stream.outputs) if v not in outer)
            body: Formula = And(condition)
            if inner:
                body = Exists(inner, body)
            head = _renamed(fact, derived)
            if len(set(head.args)) != len(head.args) or any(
                not a.startswith("?") for a in head.args
            ):
                LOG.warning("exogenous stream %r: certified fact %s skipped", stream.name, fact)
                continue
            axioms.append(Axiom(head.predicate, tuple(Parameter(a) for a in head.args), body))
    for name in certified:
        params = tuple(f"?x{i}" for i in range(arity[name]))
        atom = Atom(name, params)
        axioms.append(Axiom(derived[name], tuple(Parameter(p) for p in params), And((atom,))))
    rules = list(streams.rules)
    for name in certified:
        params = tuple(f"?x{i}" for i in range(arity[name]))
        rules.append(Rule(params, (Atom(name, params),), (Atom(future[name], params),)))
    actions = tuple(
        replace(
            action,
            precondition=_rename(action.precondition, derived),
            effect=_rename_conditions(action.effect, derived),
        )
        for action in domain.actions
    )
    axioms = [
        replace(axiom, body=_rename(axiom.body, derived))
        if axiom.predicate not in derived.values()
        else axiom
        for axiom in axioms
    ]
    new_domain = replace(domain, predicates=predicates, actions=actions, axioms=tuple(axioms))
    new_file = replace(streams, streams=tuple(new_streams), rules=tuple(rules))
    return new_domain, new_file, derived
