"""``StreamInfo(negate=True)``: a test stream whose certified fact the domain may use negated.

Such a test becomes a ``:predicate`` external over its certified fact: it is evaluated as soon as
its domain holds, the fact is known when the test passes, and ``(not (fact ...))`` holds exactly
when it fails. :func:`resolve_negated_uses` sets ``negate`` where PDDLStream sets it itself and
notes in the log every other negated use of a test's certified fact (read, as there, against the
facts known).

:func:`negated_predicates` says which predicates the domain uses negated (through derived
predicates too): those the refusal above is about, and those whose predicates on placeholders
the optimistic world leaves false.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import replace
from typing import Any

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import (
    And,
    AndEffect,
    Atom,
    Effect,
    Exists,
    ForAllEffect,
    Formula,
    Imply,
    Not,
    When,
)
from sdar_tamp.language.generators import ListGenFn, WildOutput
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.stream_model import Stream, StreamFile, StreamPredicate
from sdar_tamp.logs import get_logger
from solvers.stream_planning.externals import FunctionExternal, StreamExternal

LOG = get_logger(__name__)


def resolve_negated_uses(
    stream_file: StreamFile,
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None,
    domain: Domain,
    negated: frozenset[str],
) -> dict[str, StreamInfo | FunctionInfo]:
    """``stream_info`` with ``negate=True`` set where PDDLStream sets it itself.

    PDDLStream's focused algorithms negate a test stream automatically when it is a plain test
    (no outputs, no fluents) that certifies nothing any stream, function or predicate needs in
    its domain, is the only source of its certified predicates, and each of them appears
    negated directly in the body of a derived predicate that an action precondition uses
    negated (``(not (unsafe ?q))`` with ``unsafe`` derived from ``(not (cfree ?q ?p))``).
    The same rule applies here (logged at info level).

    Any other negated use of a test's certified fact (in ``negated``) is read as in PDDLStream,
    against the facts known: the optimistic algorithms assume the test passes, so the negation
    fails until a real plan is found without it; the incremental algorithm lets it hold until
    the test certifies the fact. The meaning depends on the algorithm, so each such stream is
    noted in the log with the remedy, ``StreamInfo(negate=True)``.
    """
    info: dict[str, StreamInfo | FunctionInfo] = dict(stream_info or {})
    by_name = {k.lower(): k for k in info}
    needed = {atom.predicate for stream in stream_file.streams for atom in stream.domain}
    needed |= {a.predicate for f in stream_file.functions for a in f.domain}
    needed |= {a.predicate for f in stream_file.predicates for a in f.domain}
    sources: dict[str, int] = {}
    for stream in stream_file.streams:
        for predicate in {atom.predicate for atom in stream.certified}:
            sources[predicate] = sources.get(predicate, 0) + 1
    under_axioms = _negated_in_negated_axioms(domain)
    for stream in stream_file.streams:
        key = by_name.get(stream.name, stream.name)
        options = info.get(key)
        if not stream.is_test or (isinstance(options, StreamInfo) and options.negate):
            continue
        certified = {atom.predicate for atom in stream.certified}
        if (
            not stream.fluents
            and certified
            and not certified & needed
            and all(p in under_axioms and sources[p] == 1 for p in certified)
        ):
            base = options if isinstance(options, StreamInfo) else StreamInfo()
            info[key] = replace(base, negate=True)
            LOG.info(
                "stream %r: negate=True set automatically (its certified fact is used negated "
                "in a derived predicate, as PDDLStream does)",
                stream.name,
            )
            continue
        used = sorted(certified & negated)
        if used:
            LOG.warning(
                "stream %r certifies %s, which the domain uses negated: as in PDDLStream, the "
                "negation is read against the facts known, so the optimistic algorithms assume "
                "the test passes (the negation fails) and the incremental one lets it hold "
                "until the test certifies the fact; give stream_info[%r] = "
                "StreamInfo(negate=True) to evaluate the negation by calling the test",
                stream.name,
                ", ".join(repr(p) for p in used),
                stream.name,
            )
    return info


def _negated_in_negated_axioms(domain: Domain) -> frozenset[str]:
    """PDDLStream's rule: predicates negated among the conjuncts of a derived predicate's
    body (below its existential quantifiers), for derived predicates that some action's
    precondition uses negated among its conjuncts."""
    negated_heads = {
        part.formula.predicate
        for action in domain.actions
        for part in _conjuncts(action.precondition)
        if isinstance(part, Not) and isinstance(part.formula, Atom)
    }
    return frozenset(
        part.formula.predicate
        for axiom in domain.axioms
        if axiom.predicate in negated_heads
        for part in _conjuncts(axiom.body)
        if isinstance(part, Not) and isinstance(part.formula, Atom)
    )


def _conjuncts(formula: Formula) -> list[Formula]:
    if isinstance(formula, And):
        return [c for part in formula.parts for c in _conjuncts(part)]
    if isinstance(formula, Exists):
        return _conjuncts(formula.body)
    return [formula]


def split_negated(
    streams: Mapping[str, StreamExternal], taken: Iterable[str], debug: bool = False
) -> tuple[dict[str, StreamExternal], dict[str, FunctionExternal]]:
    """The streams without ``negate``, and the negated tests as predicate externals keyed by
    their certified predicate (``taken``: names of the other functions and predicates). With
    ``debug`` (``stream_map="debug"``) a negated test fails, like a debug ``:predicate``."""
    kept: dict[str, StreamExternal] = {}
    predicates: dict[str, FunctionExternal] = {}
    names = set(taken)
    for name, external in streams.items():
        if not external.info.negate:
            kept[name] = external
            continue
        head = _head(external.declaration)
        if head.predicate in names:
            raise ParameterError(
                f"stream_info[{name!r}].negate: {head.predicate!r} is already a :predicate or "
                "the certified fact of another negated test; a predicate can have one source"
            )
        names.add(head.predicate)
        declaration = StreamPredicate(head, external.declaration.domain)
        order = [head.args.index(v) for v in external.declaration.inputs]
        test = _never if debug else _as_predicate(external.gen_fn, order)
        predicates[head.predicate] = FunctionExternal(declaration, test, external.info, stream=name)
    return kept, predicates


def _head(stream: Stream) -> Atom:
    certified = stream.certified
    if (
        stream.outputs
        or stream.fluents
        or len(certified) != 1
        or sorted(certified[0].args) != sorted(stream.inputs)
    ):
        raise ParameterError(
            f"stream_info[{stream.name!r}].negate needs a test stream (no :outputs, no "
            ":fluents) that certifies exactly one fact whose arguments are its inputs; got "
            f":outputs ({' '.join(stream.outputs)}), :fluents ({' '.join(stream.fluents)}), "
            f":certified {' '.join(str(a) for a in certified)}"
        )
    return certified[0]


def _never(*_values: Any) -> bool:
    return False


def _as_predicate(gen_fn: ListGenFn, order: list[int]) -> Callable[..., bool]:
    """The test's first answer as a boolean; ``order`` maps the stream's inputs to the
    certified fact's arguments."""

    def test(*values: Any) -> bool:
        produced = next(iter(gen_fn(*(values[i] for i in order))), None)
        if isinstance(produced, WildOutput):
            return bool(produced.values)
        return bool(produced)

    return test


def negated_predicates(domain: Domain, goal: Formula) -> frozenset[str]:
    """Predicates that some action precondition, effect condition or the goal uses negated.

    Polarity flows through derived predicates: an atom in the body of an axiom whose head is used
    negated counts as used negated too (``(not (unsafe ?t))`` with ``unsafe`` derived from
    ``(collides ?t ?o)`` negates ``collides``), and an ``Imply`` negates its antecedent.
    """
    axioms: dict[str, list[Formula]] = {}
    for axiom in domain.axioms:
        axioms.setdefault(axiom.predicate, []).append(axiom.body)
    roots: list[Formula] = [goal, *(a.precondition for a in domain.actions)]
    roots += [w.condition for a in domain.actions for w in _conditions(a.effect)]
    found: set[str] = set()
    seen: set[tuple[str, bool]] = set()
    stack: list[tuple[Formula, bool]] = [(formula, True) for formula in roots]
    while stack:
        node, positive = stack.pop()
        if isinstance(node, Atom):
            if not positive:
                found.add(node.predicate)
            if node.predicate in axioms and (node.predicate, positive) not in seen:
                seen.add((node.predicate, positive))
                stack.extend((body, positive) for body in axioms[node.predicate])
        elif isinstance(node, Not):
            stack.append((node.formula, not positive))
        elif isinstance(node, Imply):
            stack += [(node.antecedent, not positive), (node.consequent, positive)]
        else:
            stack.extend((child, positive) for child in _children(node))
    return frozenset(found)


def _conditions(effect: Effect) -> list[When]:
    if isinstance(effect, When):
        return [effect, *_conditions(effect.effect)]
    if isinstance(effect, AndEffect):
        return [w for part in effect.parts for w in _conditions(part)]
    if isinstance(effect, ForAllEffect):
        return _conditions(effect.effect)
    return []


def _children(node: Formula) -> list[Formula]:
    parts = getattr(node, "parts", None)
    if parts is not None:
        return list(parts)
    return [node.body]  # type: ignore[union-attr]
