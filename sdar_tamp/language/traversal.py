"""Walking and rewriting the typed model's formulas and effects.

Iterating over the atoms of a formula or the leaves of an effect, mapping atoms and effect
conditions, and substituting values for free variables (the values are in
:mod:`sdar_tamp.language.formula_model`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping

from sdar_tamp.language.formula_model import (
    And,
    AndEffect,
    Atom,
    Effect,
    Exists,
    ForAll,
    ForAllEffect,
    Formula,
    Imply,
    IncreaseCost,
    Literal,
    Not,
    Or,
    When,
)


def iter_atoms(formula: Formula) -> Iterator[Atom]:
    """Every atom in ``formula`` (quantified variables left as they are)."""
    stack: list[Formula] = [formula]
    while stack:
        node = stack.pop()
        if isinstance(node, Atom):
            yield node
        elif isinstance(node, Not):
            stack.append(node.formula)
        elif isinstance(node, And | Or):
            stack.extend(node.parts)
        elif isinstance(node, Imply):
            stack.extend((node.antecedent, node.consequent))
        else:
            stack.append(node.body)


def iter_effects(effect: Effect) -> Iterator[Literal | IncreaseCost]:
    """Every leaf of ``effect`` (literals and cost increases), in order, including those
    inside conditional and universal effects."""
    stack: list[Effect] = [effect]
    while stack:
        node = stack.pop()
        if isinstance(node, Literal | IncreaseCost):
            yield node
        elif isinstance(node, AndEffect):
            stack.extend(reversed(node.parts))
        else:
            stack.append(node.effect)


def iter_effect_literals(effect: Effect) -> Iterator[Literal]:
    """Every add/delete literal inside ``effect``, including conditional and universal ones."""
    return (e for e in iter_effects(effect) if isinstance(e, Literal))


def map_atoms(
    formula: Formula, fn: Callable[[Atom, bool], Formula], positive: bool = True
) -> Formula:
    """``formula`` with every atom replaced by ``fn(atom, positive)``; ``positive`` says
    whether the atom is used positively (under an even number of negations, an implication's
    antecedent counting as one). Quantifiers are kept as they are."""
    if isinstance(formula, Atom):
        return fn(formula, positive)
    if isinstance(formula, Not):
        return Not(map_atoms(formula.formula, fn, not positive))
    if isinstance(formula, And):
        return And(tuple(map_atoms(p, fn, positive) for p in formula.parts))
    if isinstance(formula, Or):
        return Or(tuple(map_atoms(p, fn, positive) for p in formula.parts))
    if isinstance(formula, Imply):
        return Imply(
            map_atoms(formula.antecedent, fn, not positive),
            map_atoms(formula.consequent, fn, positive),
        )
    body = map_atoms(formula.body, fn, positive)
    if isinstance(formula, Exists):
        return Exists(formula.parameters, body)
    return ForAll(formula.parameters, body)


def map_conditions(effect: Effect, fn: Callable[[Formula], Formula]) -> Effect:
    """``effect`` with the condition of every conditional effect replaced by ``fn(condition)``."""
    if isinstance(effect, AndEffect):
        return AndEffect(tuple(map_conditions(p, fn) for p in effect.parts))
    if isinstance(effect, ForAllEffect):
        return ForAllEffect(effect.parameters, map_conditions(effect.effect, fn))
    if isinstance(effect, When):
        return When(fn(effect.condition), map_conditions(effect.effect, fn))
    return effect


def substitute(formula: Formula, mapping: Mapping[str, str]) -> Formula:
    """Replace free variables of ``formula`` by ``mapping``; bound variables are shadowed."""
    if isinstance(formula, Atom):
        return Atom(formula.predicate, tuple(mapping.get(a, a) for a in formula.args))
    if isinstance(formula, Not):
        return Not(substitute(formula.formula, mapping))
    if isinstance(formula, And):
        return And(tuple(substitute(p, mapping) for p in formula.parts))
    if isinstance(formula, Or):
        return Or(tuple(substitute(p, mapping) for p in formula.parts))
    if isinstance(formula, Imply):
        return Imply(
            substitute(formula.antecedent, mapping), substitute(formula.consequent, mapping)
        )
    inner = {k: v for k, v in mapping.items() if k not in {p.name for p in formula.parameters}}
    body = substitute(formula.body, inner)
    return (
        Exists(formula.parameters, body)
        if isinstance(formula, Exists)
        else ForAll(formula.parameters, body)
    )
