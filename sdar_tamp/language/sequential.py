"""The sequential compilation of durative actions: :func:`compile_durative` turns a
:class:`~sdar_tamp.language.durative.DurativeActionSchema` into one instantaneous
:class:`~sdar_tamp.language.domain_model.ActionSchema` whose cost is its duration.

Run alone, a durative action goes through two states: ``s0`` before it, where its at-start
condition must hold; ``s1`` after its at-start effects, where its over-all and at-end
conditions must hold and its at-end effects are evaluated; and ``s2`` after them. The compiled
action says the same in ``s0`` terms: its precondition is the at-start condition and the
over-all and at-end conditions *regressed* through the at-start effects (an atom holds in
``s1`` when a start effect adds it, or when it held and no start effect deletes it; equality
decides which lifted effect touches which atom), and its effect is the end effects (their
conditions regressed likewise) after the start effects (a start add that an end effect deletes
is dropped). A derived predicate whose definition depends on what the start effects change is
regressed through its definition, unfolded; a recursive one cannot be and is refused.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass

from sdar_tamp.language.domain_model import ActionSchema, Axiom
from sdar_tamp.language.durative import DurativeActionSchema
from sdar_tamp.language.errors import UnsupportedFeatureError
from sdar_tamp.language.formula_model import (
    EQUALITY,
    FALSE,
    OBJECT_TYPE,
    TOTAL_COST,
    TRUE,
    And,
    AndEffect,
    Atom,
    Effect,
    Exists,
    ForAll,
    ForAllEffect,
    Formula,
    FunctionTerm,
    Imply,
    IncreaseCost,
    Literal,
    Not,
    Or,
    Parameter,
    When,
)
from sdar_tamp.language.numeric import DURATION_TERM, NumericEffect
from sdar_tamp.language.sequential_numeric import numeric_parts
from sdar_tamp.language.traversal import iter_atoms, substitute


@dataclass(frozen=True)
class _Touch:
    """One literal of an effect, with what must hold for it to apply: ``condition`` (in the
    state the effect is evaluated in) for some values of ``parameters`` (its ``forall``)."""

    atom: Atom
    negated: bool
    parameters: tuple[Parameter, ...]
    condition: Formula


def compile_durative(action: DurativeActionSchema, axioms: tuple[Axiom, ...]) -> ActionSchema:
    """The instantaneous action that does what ``action`` does when run alone.

    Raises:
        UnsupportedFeatureError: an over-all or at-end condition (or an at-end effect's
            condition) uses a recursive derived predicate that the start effects affect.
    """
    fresh = _Fresh()
    start = list(_touches(action.start_effect, TRUE, (), fresh))
    regress = _Regression(start, axioms, fresh, action)
    precondition = _and(action.at_start, regress(action.over_all), regress(action.at_end))
    end_effect = _map_effect_conditions(action.end_effect, regress)
    end = list(_touches(end_effect, TRUE, (), fresh))
    kept_start = _drop_overridden(action.start_effect, end)
    conditions, numeric_effects = numeric_parts(action)
    duration = action.duration
    parts: tuple[Effect, ...] = (kept_start, end_effect)
    if isinstance(duration, float | int) or (
        isinstance(duration, FunctionTerm) and duration != DURATION_TERM
    ):
        parts += (IncreaseCost(duration),)
    else:  # an expression: a numeric cost (sdar_tamp.language.numeric_compile)
        total = NumericEffect("increase", FunctionTerm(TOTAL_COST), duration, action.location)
        numeric_effects += (total,)
    return ActionSchema(
        action.name,
        action.parameters,
        precondition,
        AndEffect(parts),
        action.location,
        conditions,
        numeric_effects,
    )


class _Fresh:
    """Fresh variable names (never written by a user: they contain ``#``)."""

    def __init__(self) -> None:
        self._count = itertools.count()

    def rename(self, parameters: tuple[Parameter, ...]) -> dict[str, str]:
        return {p.name: f"?#{next(self._count)}-{p.name[1:]}" for p in parameters}


def _touches(
    effect: Effect, condition: Formula, parameters: tuple[Parameter, ...], fresh: _Fresh
) -> Iterator[_Touch]:
    if isinstance(effect, Literal):
        yield _Touch(effect.atom, effect.negated, parameters, condition)
    elif isinstance(effect, AndEffect):
        for part in effect.parts:
            yield from _touches(part, condition, parameters, fresh)
    elif isinstance(effect, ForAllEffect):
        names = fresh.rename(effect.parameters)
        renamed = tuple(Parameter(names[p.name], p.type) for p in effect.parameters)
        inner = _substitute_effect(effect.effect, names)
        yield from _touches(inner, substitute(condition, names), parameters + renamed, fresh)
    elif isinstance(effect, When):
        yield from _touches(effect.effect, _and(condition, effect.condition), parameters, fresh)


def _matches(atom: Atom, touches: list[_Touch], negated: bool) -> Formula:
    """When one of ``touches`` (adds, or deletes when ``negated``) applies to ``atom``."""
    cases: list[Formula] = []
    for touch in touches:
        if touch.negated != negated or touch.atom.predicate != atom.predicate:
            continue
        if len(touch.atom.args) != len(atom.args):
            continue
        equal = tuple(
            Atom(EQUALITY, (a, b)) for a, b in zip(atom.args, touch.atom.args, strict=True)
        )
        case = _and(touch.condition, *(e for e in equal if e.args[0] != e.args[1]))
        cases.append(Exists(touch.parameters, case) if touch.parameters else case)
    return _or(*cases)


class _Regression:
    """A formula on ``s1`` rewritten as one on ``s0`` (before the start effects)."""

    def __init__(
        self,
        start: list[_Touch],
        axioms: tuple[Axiom, ...],
        fresh: _Fresh,
        action: DurativeActionSchema,
    ) -> None:
        self.start = start
        self.fresh = fresh
        self.action = action
        self.definitions: dict[str, list[Axiom]] = {}
        for axiom in axioms:
            self.definitions.setdefault(axiom.predicate, []).append(axiom)
        changed = {t.atom.predicate for t in start}
        self.affected = _affected(self.definitions, changed)

    def __call__(self, formula: Formula) -> Formula:
        return self._regress(formula, ())

    def _regress(self, formula: Formula, unfolding: tuple[str, ...]) -> Formula:
        if isinstance(formula, Atom):
            return self._atom(formula, unfolding)
        if isinstance(formula, Not):
            return Not(self._regress(formula.formula, unfolding))
        if isinstance(formula, And):
            return And(tuple(self._regress(p, unfolding) for p in formula.parts))
        if isinstance(formula, Or):
            return Or(tuple(self._regress(p, unfolding) for p in formula.parts))
        if isinstance(formula, Exists | ForAll):
            body = self._regress(formula.body, unfolding)
            return type(formula)(formula.parameters, body)
        return Imply(
            self._regress(formula.antecedent, unfolding),
            self._regress(formula.consequent, unfolding),
        )

    def _atom(self, atom: Atom, unfolding: tuple[str, ...]) -> Formula:
        if atom.predicate == EQUALITY:
            return atom
        if atom.predicate in self.definitions:
            if atom.predicate not in self.affected:
                return atom
            if atom.predicate in unfolding:
                raise UnsupportedFeatureError(
                    f"durative action {self.action.name!r}: derived predicate "
                    f"{atom.predicate!r} is recursive and depends on what the action's start "
                    "effects change, so its over-all or at-end conditions cannot be checked "
                    "after them in a sequential plan",
                    self.action.location,
                )
            bodies = [self._unfold(axiom, atom) for axiom in self.definitions[atom.predicate]]
            return self._regress(_or(*bodies), (*unfolding, atom.predicate))
        added = _matches(atom, self.start, negated=False)
        deleted = _matches(atom, self.start, negated=True)
        return _or(added, _and(atom, Not(deleted)) if deleted != FALSE else atom)

    def _unfold(self, axiom: Axiom, atom: Atom) -> Formula:
        bound = self.fresh.rename(tuple(_bound_parameters(axiom.body)))
        body = _rename_bound(axiom.body, bound)
        mapping: dict[str, str] = {}
        typed: list[Parameter] = []
        equal: list[Formula] = []
        for parameter, arg in zip(axiom.parameters, atom.args, strict=True):
            if parameter.type == OBJECT_TYPE:
                mapping[parameter.name] = arg
            else:  # the argument must be of the parameter's type: bind a typed copy
                (name,) = self.fresh.rename((parameter,)).values()
                typed.append(Parameter(name, parameter.type))
                equal.append(Atom(EQUALITY, (name, arg)))
                mapping[parameter.name] = name
        unfolded = substitute(body, mapping)
        return Exists(tuple(typed), _and(*equal, unfolded)) if typed else unfolded


def _affected(definitions: Mapping[str, list[Axiom]], changed: set[str]) -> set[str]:
    """The derived predicates whose definitions depend (transitively) on ``changed``."""
    affected: set[str] = set()
    grew = True
    while grew:
        grew = False
        for name, axioms in definitions.items():
            if name in affected:
                continue
            used = {a.predicate for axiom in axioms for a in iter_atoms(axiom.body)}
            if used & (changed | affected):
                affected.add(name)
                grew = True
    return affected


def _bound_parameters(formula: Formula) -> Iterator[Parameter]:
    if isinstance(formula, Not):
        yield from _bound_parameters(formula.formula)
    elif isinstance(formula, And | Or):
        for part in formula.parts:
            yield from _bound_parameters(part)
    elif isinstance(formula, Exists | ForAll):
        yield from formula.parameters
        yield from _bound_parameters(formula.body)
    elif isinstance(formula, Imply):
        yield from _bound_parameters(formula.antecedent)
        yield from _bound_parameters(formula.consequent)


def _rename_bound(formula: Formula, names: Mapping[str, str]) -> Formula:
    """``formula`` with its quantified variables renamed by ``names`` (all of them distinct,
    so that substituting the free ones afterwards captures nothing)."""
    if isinstance(formula, Atom):
        return formula
    if isinstance(formula, Not):
        return Not(_rename_bound(formula.formula, names))
    if isinstance(formula, And | Or):
        return type(formula)(tuple(_rename_bound(p, names) for p in formula.parts))
    if isinstance(formula, Exists | ForAll):
        own = {p.name: names[p.name] for p in formula.parameters}
        params = tuple(Parameter(own[p.name], p.type) for p in formula.parameters)
        return type(formula)(params, substitute(_rename_bound(formula.body, names), own))
    return Imply(_rename_bound(formula.antecedent, names), _rename_bound(formula.consequent, names))


def _substitute_effect(effect: Effect, mapping: Mapping[str, str]) -> Effect:
    if isinstance(effect, Literal):
        atom = Atom(effect.atom.predicate, tuple(mapping.get(a, a) for a in effect.atom.args))
        return Literal(atom, effect.negated)
    if isinstance(effect, AndEffect):
        return AndEffect(tuple(_substitute_effect(p, mapping) for p in effect.parts))
    if isinstance(effect, ForAllEffect):
        inner = {k: v for k, v in mapping.items() if k not in {p.name for p in effect.parameters}}
        return ForAllEffect(effect.parameters, _substitute_effect(effect.effect, inner))
    if isinstance(effect, When):
        return When(
            substitute(effect.condition, mapping), _substitute_effect(effect.effect, mapping)
        )
    return effect


def _map_effect_conditions(effect: Effect, fn: Callable[[Formula], Formula]) -> Effect:
    if isinstance(effect, AndEffect):
        return AndEffect(tuple(_map_effect_conditions(p, fn) for p in effect.parts))
    if isinstance(effect, ForAllEffect):
        return ForAllEffect(effect.parameters, _map_effect_conditions(effect.effect, fn))
    if isinstance(effect, When):
        return When(fn(effect.condition), _map_effect_conditions(effect.effect, fn))
    return effect


def _drop_overridden(effect: Effect, end: list[_Touch]) -> Effect:
    """The start ``effect`` with each add made conditional on no end effect deleting it."""
    if isinstance(effect, Literal):
        if effect.negated:
            return effect
        deleted = _matches(effect.atom, end, negated=True)
        if deleted == TRUE:
            return AndEffect(())
        return effect if deleted == FALSE else When(Not(deleted), effect)
    if isinstance(effect, AndEffect):
        return AndEffect(tuple(_drop_overridden(p, end) for p in effect.parts))
    if isinstance(effect, ForAllEffect):
        return ForAllEffect(effect.parameters, _drop_overridden(effect.effect, end))
    if isinstance(effect, When):
        return When(effect.condition, _drop_overridden(effect.effect, end))
    return effect


def _and(*parts: Formula) -> Formula:
    kept = tuple(p for p in parts if p != TRUE)
    if any(p == FALSE for p in kept):
        return FALSE
    return kept[0] if len(kept) == 1 else And(kept)


def _or(*parts: Formula) -> Formula:
    kept = tuple(p for p in parts if p != FALSE)
    if any(p == TRUE for p in kept):
        return TRUE
    return kept[0] if len(kept) == 1 else Or(kept)
