"""The numeric part of the sequential compilation of a durative action
(:mod:`sdar_tamp.language.sequential`): its conditions and effects on numeric fluents said in
terms of the state before it.

``?duration`` is the duration evaluated at the start. An over-all or at-end condition, and the
value an at-end effect computes, read the fluents after the start effects: each term a start
effect changes is replaced by the start effect's new value (the term as written: two terms that
differ only in their variables are assumed distinct). Every effect becomes an ``assign`` of the
value after the action, the end effect's where both change the same term.
"""

from __future__ import annotations

from collections.abc import Callable

from sdar_tamp.language.durative import END, OVER_ALL, START, DurativeActionSchema
from sdar_tamp.language.formula_model import TOTAL_COST, FunctionTerm
from sdar_tamp.language.numeric import (
    DURATION_TERM,
    Comparison,
    Expression,
    NumericEffect,
    substitute_terms,
)


def numeric_parts(
    action: DurativeActionSchema,
) -> tuple[tuple[Comparison, ...], tuple[NumericEffect, ...]]:
    """The numeric conditions and effects of the compiled action (in the state before it)."""
    duration = action.duration

    def at_start(term: FunctionTerm) -> Expression:
        return duration if term == DURATION_TERM else term

    starts: dict[FunctionTerm, Expression] = {}
    costs: list[NumericEffect] = []
    for effect in action.numeric_effects.get(START, ()):
        if effect.target.name == TOTAL_COST:
            costs.append(_cost(effect, at_start))
        else:
            starts[effect.target] = substitute_terms(effect.as_assignment(), at_start)

    def after_start(term: FunctionTerm) -> Expression:
        return duration if term == DURATION_TERM else starts.get(term, term)

    conditions = [_mapped(c, at_start) for c in action.numeric_conditions.get(START, ())]
    for tag in (OVER_ALL, END):
        conditions.extend(_mapped(c, after_start) for c in action.numeric_conditions.get(tag, ()))
    finals: dict[FunctionTerm, tuple[Expression, NumericEffect]] = {
        target: (value, _effect_of(action, START, target)) for target, value in starts.items()
    }
    for effect in action.numeric_effects.get(END, ()):
        if effect.target.name == TOTAL_COST:
            costs.append(_cost(effect, after_start))
            continue
        value = substitute_terms(effect.as_assignment(), after_start)
        finals[effect.target] = (value, effect)
    effects = tuple(
        NumericEffect("assign", target, value, effect.location)
        for target, (value, effect) in finals.items()
    )
    return tuple(conditions), effects + tuple(costs)


_Replace = Callable[[FunctionTerm], Expression]


def _cost(effect: NumericEffect, replace: _Replace) -> NumericEffect:
    """An ``(increase (total-cost) amount)`` with its amount in the state before the action."""
    return NumericEffect(
        effect.operator, effect.target, substitute_terms(effect.value, replace), effect.location
    )


def _mapped(condition: Comparison, replace: _Replace) -> Comparison:
    return Comparison(
        condition.operator,
        substitute_terms(condition.left, replace),
        substitute_terms(condition.right, replace),
        condition.location,
    )


def _effect_of(action: DurativeActionSchema, tag: str, target: FunctionTerm) -> NumericEffect:
    return next(e for e in action.numeric_effects.get(tag, ()) if e.target == target)
