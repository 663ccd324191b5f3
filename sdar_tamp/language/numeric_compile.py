"""Numeric fluents compiled away for their reachable values: :func:`compile_numeric`.

A classical planner over sets of atoms plans over a domain with numeric fluents
(:mod:`sdar_tamp.language.numeric`) once each ground fluent's value is an atom. The values a
fluent can take are found first: from its initial value, every numeric action is applied, for
every binding of the parameters its numeric parts mention and every combination of known
values of the fluents it reads, whenever its numeric conditions hold (its other conditions
are ignored here: the set found may be larger than the reachable one, never smaller), until no
new value appears. A fluent with more than ``max_values`` values (an unbounded counter) is
refused with a located :class:`~sdar_tamp.language.errors.UnsupportedFeatureError`.

Then each numeric action gets one extra parameter per fluent term it reads (its value before)
and one per term it changes (its value after); its precondition requires
``(#=f args ?old)`` for each term read and one static fact ``(#num-a ...)`` that lists the
valid combinations (numeric conditions true, new values defined); its effect replaces
``(#=f args ?old)`` by ``(#=f args ?new)``, and an action cost that depends on the values
becomes a cost term ``(#cost-a ...)`` whose values are listed. Values are rounded to 9
decimals. :meth:`NumericCompilation.original_args` gives a plan step's arguments back without
the extra parameters.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from sdar_tamp.language.domain_model import ActionSchema, Domain, Predicate
from sdar_tamp.language.errors import UnsupportedFeatureError
from sdar_tamp.language.formula_model import (
    TOTAL_COST,
    And,
    AndEffect,
    Atom,
    Effect,
    ForAllEffect,
    FunctionTerm,
    IncreaseCost,
    Literal,
    Parameter,
    When,
)
from sdar_tamp.language.numeric import (
    Comparison,
    Expression,
    evaluate,
    function_terms,
    holds,
)

MAX_VALUES = 1000
"""The most values one ground numeric fluent may take."""
MAX_BINDINGS = 200_000
"""The most parameter bindings times value combinations of one numeric action."""

NumericInit = Mapping[tuple[str, tuple[str, ...]], float]
_Key = tuple[str, tuple[str, ...]]


@dataclass(frozen=True)
class NumericCompilation:
    """A domain and problem without numeric fluents that plan as the original ones do."""

    domain: Domain
    objects: Mapping[str, str]
    init: frozenset[Atom]
    numeric_init: Mapping[tuple[str, tuple[str, ...]], float]
    arities: Mapping[str, int]
    """Each action's number of parameters before the compilation."""

    def original_args(self, name: str, args: tuple[str, ...]) -> tuple[str, ...]:
        """A step's arguments without the parameters the compilation added."""
        return args[: self.arities.get(name, len(args))]


def value_object(value: float) -> str:
    """The object that stands for a numeric value."""
    return f"#n{value!r}"


@dataclass(frozen=True)
class _Shape:
    """One numeric action, lifted: the parameters its numeric parts mention, the fluent terms
    it reads and those it changes (indices into ``reads``), and its parts."""

    action: ActionSchema
    parameters: tuple[Parameter, ...]
    reads: tuple[FunctionTerm, ...]
    writes: tuple[int, ...]
    conditions: tuple[Comparison, ...]
    values: tuple[Expression, ...]  # the new value of each written term
    costs: tuple[Expression, ...]  # amounts added to total-cost
    effect: Effect  # the propositional effect


def compile_numeric(
    domain: Domain,
    objects: Mapping[str, str],
    init: frozenset[Atom],
    numeric_init: NumericInit,
    *,
    max_values: int = MAX_VALUES,
) -> NumericCompilation:
    """``domain`` and its problem (``objects``, ``init``, ``numeric_init``) compiled into a
    domain without numeric conditions and effects (see the module's description).

    Raises:
        UnsupportedFeatureError: a fluent takes more than ``max_values`` values, an action has
            too many bindings (:data:`MAX_BINDINGS`), an action cost reads a numeric fluent
            inside ``when`` or ``forall``, or a cost is negative.
    """
    fluents = domain.numeric_fluents
    shapes = [_shape(action, fluents) for action in domain.actions]
    values: dict[_Key, set[float]] = {
        key: {_round(value)} for key, value in numeric_init.items() if key[0] in fluents
    }
    statics = numeric_init  # read for the functions no action changes
    changed = True
    while changed:
        changed = False
        for shape in shapes:
            if shape is None:
                continue
            for _binding, reads, new, _cost in _rows(shape, domain, objects, values, statics):
                for key, value in zip((reads[i][0] for i in shape.writes), new, strict=True):
                    known = values.setdefault(key, set())
                    if value not in known:
                        known.add(value)
                        changed = True
                        if len(known) > max_values:
                            raise UnsupportedFeatureError(
                                f"numeric fluent ({' '.join((key[0], *key[1]))}) takes more "
                                f"than {max_values} values; only numeric fluents with finitely "
                                "many reachable values are supported",
                                shape.action.location,
                            )
    return _rewrite(domain, objects, init, numeric_init, shapes, values, statics)


def _shape(action: ActionSchema, fluents: frozenset[str]) -> _Shape | None:
    effect, fluent_costs = _split_costs(action, action.effect, fluents)
    if not (action.numeric_conditions or action.numeric_effects or fluent_costs):
        return None
    writes = [e for e in action.numeric_effects if e.target.name != TOTAL_COST]
    costs = [e.value for e in action.numeric_effects if e.target.name == TOTAL_COST]
    costs.extend(fluent_costs)
    exprs: list[Expression] = [e.target for e in writes] + [e.as_assignment() for e in writes]
    for condition in action.numeric_conditions:
        exprs.extend((condition.left, condition.right))
    exprs.extend(costs)
    terms = [t for expr in exprs for t in function_terms(expr)]
    reads = tuple(dict.fromkeys(t for t in terms if t.name in fluents))
    mentioned = {a for t in terms for a in t.args}
    targets = [e.target for e in writes]
    for i, target in enumerate(targets):
        if target in targets[:i]:
            raise UnsupportedFeatureError(
                f"action {action.name!r} changes {target.name} twice", writes[i].location
            )
    return _Shape(
        action,
        tuple(p for p in action.parameters if p.name in mentioned),
        reads,
        tuple(reads.index(t) for t in targets),
        action.numeric_conditions,
        tuple(e.as_assignment() for e in writes),
        tuple(costs),
        effect,
    )


def _split_costs(
    action: ActionSchema, effect: Effect, fluents: frozenset[str]
) -> tuple[Effect, list[Expression]]:
    """``effect`` without the ``(increase (total-cost) (f ...))`` of a numeric fluent ``f``,
    and those terms."""
    if isinstance(effect, IncreaseCost):
        amount = effect.amount
        if isinstance(amount, FunctionTerm) and amount.name in fluents:
            return AndEffect(()), [amount]
        return effect, []
    if isinstance(effect, AndEffect):
        parts: list[Effect] = []
        found: list[Expression] = []
        for part in effect.parts:
            kept, terms = _split_costs(action, part, fluents)
            parts.append(kept)
            found.extend(terms)
        return (AndEffect(tuple(parts)), found) if found else (effect, [])
    if isinstance(effect, When | ForAllEffect):
        inner = effect.effect
        if _split_costs(action, inner, fluents)[1]:
            raise UnsupportedFeatureError(
                f"action {action.name!r}: a cost that reads a numeric fluent is supported only "
                "as a conjunct of the effect (not inside 'when' or 'forall')",
                action.location,
            )
    return effect, []


_Row = tuple[tuple[str, ...], list[tuple[_Key, float]], tuple[float, ...], float]


def _rows(
    shape: _Shape,
    domain: Domain,
    objects: Mapping[str, str],
    values: Mapping[_Key, set[float]],
    statics: Mapping[_Key, float],
) -> Iterator[_Row]:
    """Each binding of the shape's parameters and values of the terms it reads for which its
    numeric conditions hold and its new values and cost are defined: ``(binding, [(term,
    value) per read term], new values, cost)``."""
    domains = [
        sorted(o for o, t in objects.items() if domain.types.is_subtype(t, p.type))
        for p in shape.parameters
    ]
    names = [p.name for p in shape.parameters]
    count = 0
    for binding in itertools.product(*domains):
        mapping = dict(zip(names, binding, strict=True))
        keys = [(t.name, tuple(mapping.get(a, a) for a in t.args)) for t in shape.reads]
        distinct = list(dict.fromkeys(keys))
        choices = [sorted(values.get(key, ())) for key in distinct]
        for combination in itertools.product(*choices):
            count += 1
            if count > MAX_BINDINGS:
                raise UnsupportedFeatureError(
                    f"action {shape.action.name!r}: more than {MAX_BINDINGS} combinations of "
                    "parameters and numeric values",
                    shape.action.location,
                )
            state = dict(zip(distinct, combination, strict=True))

            def lookup(term: FunctionTerm) -> float | None:
                key = (term.name, tuple(mapping.get(a, a) for a in term.args))  # noqa: B023
                return state.get(key, statics.get(key))  # noqa: B023

            if not all(holds(c, lookup) for c in shape.conditions):
                continue
            new = [evaluate(v, lookup) for v in shape.values]
            costs = [evaluate(c, lookup) for c in shape.costs]
            if any(v is None for v in new) or any(c is None for c in costs):
                continue
            cost = sum(c for c in costs if c is not None)
            if cost < 0:
                raise UnsupportedFeatureError(
                    f"action {shape.action.name!r} costs {cost} for {binding}; action costs "
                    "must be non-negative",
                    shape.action.location,
                )
            written = [_round(v) for v in new if v is not None]
            targets = [keys[i] for i in shape.writes]
            if len(set(targets)) < len(targets):  # two terms, one fluent: one value
                seen: dict[_Key, float] = {}
                if any(seen.setdefault(k, v) != v for k, v in zip(targets, written, strict=True)):
                    continue
            yield binding, [(k, state[k]) for k in keys], tuple(written), cost


def _rewrite(
    domain: Domain,
    objects: Mapping[str, str],
    init: frozenset[Atom],
    numeric_init: NumericInit,
    shapes: list[_Shape | None],
    values: Mapping[_Key, set[float]],
    statics: Mapping[_Key, float],
) -> NumericCompilation:
    predicates = dict(domain.predicates)
    new_objects = dict(objects)
    facts = set(init)
    costs = copy.copy(numeric_init)  # keeps a mapping's own lookups (optimistic values)
    extra: dict[_Key, float] = {}
    for key, known in values.items():
        name = f"#={key[0]}"
        predicates.setdefault(name, Predicate(name, _params(len(key[1]) + 1)))
        for value in known:
            new_objects[value_object(value)] = "object"
        if key in numeric_init:
            facts.add(Atom(name, (*key[1], value_object(_round(numeric_init[key])))))
    actions: list[ActionSchema] = []
    for action, shape in zip(domain.actions, shapes, strict=True):
        if shape is None:
            actions.append(action)
            continue
        relation = f"#num-{action.name}"
        cost_name = f"#cost-{action.name}"
        olds = tuple(f"?#old{i}" for i in range(len(shape.reads)))
        news = tuple(f"?#new{j}" for j in range(len(shape.writes)))
        names = tuple(p.name for p in shape.parameters)
        predicates[relation] = Predicate(relation, _params(len(names) + len(olds) + len(news)))
        for binding, reads, new, cost in _rows(shape, domain, objects, values, statics):
            read_objects = tuple(value_object(v) for _, v in reads)
            new_objects.update(dict.fromkeys(map(value_object, new), "object"))
            facts.add(Atom(relation, (*binding, *read_objects, *map(value_object, new))))
            if shape.costs:
                extra[(cost_name, (*binding, *read_objects))] = cost
        holds_now = tuple(
            Atom(f"#={t.name}", (*t.args, old)) for t, old in zip(shape.reads, olds, strict=True)
        )
        changes: list[Effect] = []
        for j, i in enumerate(shape.writes):
            term = shape.reads[i]
            changes.append(Literal(Atom(f"#={term.name}", (*term.args, olds[i])), negated=True))
            changes.append(Literal(Atom(f"#={term.name}", (*term.args, news[j]))))
        if shape.costs:
            changes.append(IncreaseCost(FunctionTerm(cost_name, (*names, *olds))))
        parameters = action.parameters + tuple(Parameter(v) for v in olds + news)
        precondition = And((action.precondition, *holds_now, Atom(relation, names + olds + news)))
        effect = AndEffect((shape.effect, *changes))
        actions.append(ActionSchema(action.name, parameters, precondition, effect, action.location))
    compiled = dataclasses.replace(
        domain, predicates=predicates, actions=tuple(actions), durative_actions=()
    )
    if extra:
        if not isinstance(costs, dict):
            costs = dict(costs)
        costs.update(extra)
    return NumericCompilation(
        compiled,
        new_objects,
        frozenset(facts),
        costs,
        {a.name: len(a.parameters) for a in domain.actions},
    )


def _params(count: int) -> tuple[Parameter, ...]:
    return tuple(Parameter(f"?x{i}") for i in range(count))


def _round(value: float) -> float:
    return round(value, 9) + 0.0
