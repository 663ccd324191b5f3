"""Cost terms computed by ``:function`` streams may only be used where their value is known.

:func:`guard_costs` adds, for every ``(increase (total-cost) (f ?a ?b))`` of an action, the
precondition ``(@fn:f ?a ?b)``; the solver adds that fact wherever the value of ``f`` is known
(evaluated, given in ``init`` or optimistic), so the planner never grounds an action whose cost
is unknown.
"""

from __future__ import annotations

from dataclasses import replace

from sdar_tamp.language.domain_model import Domain, Predicate
from sdar_tamp.language.formula_model import (
    And,
    AndEffect,
    Atom,
    Effect,
    FunctionTerm,
    IncreaseCost,
    Parameter,
)
from solvers.stream_planning.engine import function_guard


def _cost_terms(effect: Effect) -> list[FunctionTerm]:
    if isinstance(effect, IncreaseCost) and isinstance(effect.amount, FunctionTerm):
        return [effect.amount]
    if isinstance(effect, AndEffect):
        return [term for part in effect.parts for term in _cost_terms(part)]
    return []


def guard_costs(domain: Domain) -> Domain:
    """``domain`` with a guard precondition for every top-level function cost term."""
    predicates = dict(domain.predicates)
    actions = []
    for action in domain.actions:
        terms = _cost_terms(action.effect)
        if not terms:
            actions.append(action)
            continue
        guards = tuple(Atom(function_guard(t.name), t.args) for t in terms)
        for term in terms:
            name = function_guard(term.name)
            predicates[name] = Predicate(
                name, tuple(Parameter(f"?x{i}") for i in range(len(term.args)))
            )
        actions.append(replace(action, precondition=And((action.precondition, *guards))))
    return replace(domain, predicates=predicates, actions=tuple(actions))
