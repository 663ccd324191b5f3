"""``StreamInfo(negate=True)``: a test stream whose certified fact the domain may use negated.

Such a test becomes a ``:predicate`` external over its certified fact: it is evaluated as soon as
its domain holds, the fact is known when the test passes, and ``(not (fact ...))`` holds exactly
when it fails. Without ``negate`` a negated use of a test's certified fact would hold merely
because the test had not been called yet, so it is refused with an error naming the stream.

:func:`negated_predicates` says which predicates the domain uses negated (through derived
predicates too): those the refusal above is about, and those whose predicates on placeholders
the optimistic world leaves false.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.formula_model import (
    AndEffect,
    Atom,
    Effect,
    ForAllEffect,
    Formula,
    Imply,
    Not,
    When,
)
from sdar_tamp.language.generators import ListGenFn, WildOutput
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.stream_model import Stream, StreamPredicate
from solvers.stream_planning.externals import FunctionExternal, StreamExternal


def check_negated_uses(
    streams: Iterable[Stream],
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None,
    negated: frozenset[str],
) -> None:
    """Raise when the domain uses negated a fact certified by a test stream without ``negate``.

    (A generator's facts are about its outputs; a derived predicate used negated puts them under
    a negation too, as in ``(not (unsafe ?b ?p))`` over ``(pose ?b ?p)``, and that is fine: a
    placeholder's facts are only assumed where the plan needs them.)
    """
    info = {k.lower(): v for k, v in (stream_info or {}).items()}
    for stream in streams:
        options = info.get(stream.name)
        if not stream.is_test or (isinstance(options, StreamInfo) and options.negate):
            continue
        for atom in stream.certified:
            if atom.predicate in negated:
                raise ParameterError(
                    f"stream {stream.name!r} certifies {atom.predicate!r}, which the domain "
                    f"uses negated; only a :predicate or a test stream with "
                    f"stream_info[{stream.name!r}] = StreamInfo(negate=True) may be used negated"
                )


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
