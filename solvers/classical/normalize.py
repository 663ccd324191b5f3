"""Normalisation of a lifted task into conjunctive schemas.

Every precondition, effect condition, axiom body and the goal becomes a conjunction of literals:

* ``Imply`` is rewritten and negations are pushed down to atoms (negation normal form);
* ``ForAll`` is expanded over the (finite) objects of its parameter types when that gives at
  most :data:`FORALL_EXPANSION_LIMIT` copies of its body; a larger one becomes, as in Fast
  Downward, the negation of an auxiliary derived predicate ``(not (exists (..) (not body)))``
  (its relaxation drops the condition, so grounding does not join one literal per copy); the
  axiom's body also gets the enclosing conjunction's atoms over static predicates that mention
  its free variables (they hold wherever the condition is evaluated), which keeps its ground
  instances to the argument combinations the condition can be evaluated on;
* ``Or`` and ``Exists`` become auxiliary derived predicates (one axiom per disjunct, the
  existential variables as extra axiom parameters), so grounding only ever joins conjunctions;
* every typed parameter gets a *type literal* ``(type ?x)``; the type facts come from the object
  table (``object`` holds for every object), so a type name can also be used as a unary predicate.

Auxiliary predicates are named ``~aux<n>``, which is not a valid PDDL name, so they cannot clash.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

from sdar_tamp.language.domain_model import ActionSchema
from sdar_tamp.language.formula_model import (
    EQUALITY,
    OBJECT_TYPE,
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
    NumericExpr,
    Parameter,
    When,
)
from sdar_tamp.language.formula_model import And as AndF
from sdar_tamp.language.formula_model import Or as OrF
from sdar_tamp.language.traversal import iter_effect_literals
from solvers.classical.errors import GroundingError
from solvers.classical.problem import PlanningTask

#: a universally quantified condition over more parameter combinations than this is compiled
#: into a negated auxiliary axiom instead of being expanded into one copy per combination
FORALL_EXPANSION_LIMIT = 16


@dataclass(frozen=True)
class Lit:
    """A (possibly negated) atom of a normalised conjunction; ``=`` is equality."""

    predicate: str
    args: tuple[str, ...]
    positive: bool = True


@dataclass(frozen=True)
class NormEffect:
    """One add/delete literal, under universally quantified ``parameters`` and a ``condition``."""

    parameters: tuple[str, ...]
    condition: tuple[Lit, ...]
    literal: Lit


@dataclass(frozen=True)
class NormAction:
    name: str
    parameters: tuple[str, ...]
    precondition: tuple[Lit, ...]
    effects: tuple[NormEffect, ...]
    costs: tuple[NumericExpr, ...]


@dataclass(frozen=True)
class NormAxiom:
    predicate: str
    head: tuple[str, ...]
    body: tuple[Lit, ...]


@dataclass(frozen=True)
class NormTask:
    actions: tuple[NormAction, ...]
    axioms: tuple[NormAxiom, ...]
    goal: tuple[Lit, ...]
    derived: frozenset[str]
    fluent: frozenset[str]
    strata: Mapping[str, int]
    facts: frozenset[tuple[str, tuple[str, ...]]]  # initial relational facts incl. type facts


def nnf(formula: Formula, negate: bool = False) -> Formula:
    """Negation normal form without ``Imply``: ``Not`` only directly above atoms."""
    if isinstance(formula, Atom):
        return Not(formula) if negate else formula
    if isinstance(formula, Not):
        return nnf(formula.formula, not negate)
    if isinstance(formula, Imply):
        return nnf(OrF((Not(formula.antecedent), formula.consequent)), negate)
    if isinstance(formula, AndF | OrF):
        parts = tuple(nnf(part, negate) for part in formula.parts)
        conjunctive = isinstance(formula, AndF) != negate
        return AndF(parts) if conjunctive else OrF(parts)
    body = nnf(formula.body, negate)
    universal = isinstance(formula, ForAll) != negate
    return ForAll(formula.parameters, body) if universal else Exists(formula.parameters, body)


def free_variables(formula: Formula) -> frozenset[str]:
    if isinstance(formula, Atom):
        return frozenset(a for a in formula.args if a.startswith("?"))
    if isinstance(formula, Not):
        return free_variables(formula.formula)
    if isinstance(formula, Imply):
        return free_variables(formula.antecedent) | free_variables(formula.consequent)
    if isinstance(formula, AndF | OrF):
        return frozenset().union(*(free_variables(p) for p in formula.parts))
    return free_variables(formula.body) - {p.name for p in formula.parameters}


def _substitute(lit: Lit, mapping: Mapping[str, str]) -> Lit:
    return Lit(lit.predicate, tuple(mapping.get(a, a) for a in lit.args), lit.positive)


class _Normalizer:
    def __init__(self, task: PlanningTask) -> None:
        self.task = task
        self.hierarchy = task.domain.types
        by_type: dict[str, list[str]] = {}
        for obj, obj_type in task.objects.items():
            for ancestor in self.hierarchy.ancestors(obj_type):
                by_type.setdefault(ancestor, []).append(obj)
        by_type.setdefault(OBJECT_TYPE, [])
        self.objects_of_type = {t: tuple(sorted(objs)) for t, objs in by_type.items()}
        self.aux_axioms: list[NormAxiom] = []
        self.aux_names: list[str] = []
        domain = task.domain
        changed = {
            lit.atom.predicate for a in domain.actions for lit in iter_effect_literals(a.effect)
        }
        self.changing = changed | domain.derived_predicates | {EQUALITY}
        self.derived = domain.derived_predicates | {EQUALITY}
        # positive atoms of the conjunctions enclosing the formula being normalised (no
        # quantifier or disjunction in between), derived ones left out
        self.guards: list[Atom] = []

    def type_lit(self, parameter: Parameter) -> Lit:
        return Lit(parameter.type, (parameter.name,))

    def new_aux(self) -> str:
        name = f"~aux{len(self.aux_names)}"
        self.aux_names.append(name)
        return name

    def conjunction(self, formula: Formula, context: Mapping[str, str]) -> list[Lit]:
        """Literals equivalent to ``formula`` (in NNF) given auxiliary axioms."""
        if isinstance(formula, Atom):
            return [Lit(formula.predicate, formula.args)]
        if isinstance(formula, Not):
            negated = formula.formula
            if not isinstance(negated, Atom):  # pragma: no cover - nnf guarantees atoms here
                return self.conjunction(nnf(formula), context)
            return [Lit(negated.predicate, negated.args, positive=False)]
        if isinstance(formula, AndF):
            depth = len(self.guards)
            self.guards += [
                part
                for part in formula.parts
                if isinstance(part, Atom) and part.predicate not in self.derived
            ]
            try:
                return [lit for part in formula.parts for lit in self.conjunction(part, context)]
            finally:
                del self.guards[depth:]
        if isinstance(formula, OrF):
            if len(formula.parts) == 1:
                return self.conjunction(formula.parts[0], context)
            if any(isinstance(p, AndF) and not p.parts for p in formula.parts):
                return []  # a true disjunct
            # the atoms of the enclosing conjunction bind the disjunction's variables (its
            # auxiliary predicate is used there only, in the same state): without them, a
            # variable that no positive atom of a disjunct names would range over every object
            free = free_variables(formula)
            guards = [g for g in self.guards if free.intersection(g.args)]
            return [self.auxiliary(formula, (), formula.parts, context, guards)]
        if isinstance(formula, Exists):
            return [self.auxiliary(formula, formula.parameters, (formula.body,), context)]
        if isinstance(formula, Imply):
            return self.conjunction(nnf(formula), context)
        domains = [self.objects_of_type.get(p.type, ()) for p in formula.parameters]
        if math.prod(len(d) for d in domains) > FORALL_EXPANSION_LIMIT:
            # forall x: phi  ==  not (exists x: not phi)
            counter = nnf(formula.body, negate=True)
            exists = Exists(formula.parameters, counter)
            free = free_variables(exists)
            guards = [
                g
                for g in self.guards
                if free.intersection(g.args) and g.predicate not in self.changing
            ]
            lit = self.auxiliary(exists, formula.parameters, (counter,), context, guards)
            return [Lit(lit.predicate, lit.args, positive=False)]
        # ForAll over few objects: normalise the body once, then expand.
        inner = dict(context)
        inner.update({p.name: p.type for p in formula.parameters})
        body = self.conjunction(formula.body, inner)
        names = [p.name for p in formula.parameters]
        result: list[Lit] = []
        for values in itertools.product(*domains):
            mapping = dict(zip(names, values, strict=True))
            result.extend(_substitute(lit, mapping) for lit in body)
        return result

    def auxiliary(
        self,
        formula: Formula,
        bound: tuple[Parameter, ...],
        disjuncts: tuple[Formula, ...],
        context: Mapping[str, str],
        guards: list[Atom] | None = None,
    ) -> Lit:
        """A new derived predicate over the free variables of ``formula``, one axiom per
        disjunct; ``guards`` (static atoms, their other variables existential) are added to
        each axiom's body."""
        free = sorted(free_variables(formula))
        for var in free:
            if var not in context:
                raise GroundingError(f"variable {var} is not declared")
        name = self.new_aux()
        inner = dict(context)
        inner.update({p.name: p.type for p in bound})
        head_types = [Lit(context[v], (v,)) for v in free]
        bound_types = [self.type_lit(p) for p in bound]
        guard_lits = self._guard_lits(guards or [], {p.name for p in bound})
        outer = self.guards
        self.guards = []
        try:
            for disjunct in disjuncts:
                body = self.conjunction(disjunct, inner)
                lits = head_types + guard_lits + bound_types + body
                self.aux_axioms.append(NormAxiom(name, tuple(free), tuple(dict.fromkeys(lits))))
        finally:
            self.guards = outer
        return Lit(name, tuple(free))

    def _guard_lits(self, guards: list[Atom], bound: set[str]) -> list[Lit]:
        """``guards`` as literals; variables that the quantifier rebinds are renamed apart."""
        lits = []
        for index, atom in enumerate(guards):
            args = tuple(f"{a}~g{index}" if a in bound else a for a in atom.args)
            lits.append(Lit(atom.predicate, args))
        return lits

    def action(self, action: ActionSchema) -> NormAction:
        context = {p.name: p.type for p in action.parameters}
        pre = [self.type_lit(p) for p in action.parameters]
        pre += self.conjunction(nnf(action.precondition), context)
        effects: list[NormEffect] = []
        costs: list[NumericExpr] = []
        self.effect(action.effect, (), (), context, effects, costs, nested=False)
        return NormAction(
            action.name,
            tuple(p.name for p in action.parameters),
            tuple(dict.fromkeys(pre)),
            tuple(effects),
            tuple(costs),
        )

    def effect(
        self,
        effect: Effect,
        parameters: tuple[str, ...],
        condition: tuple[Lit, ...],
        context: Mapping[str, str],
        out: list[NormEffect],
        costs: list[NumericExpr],
        nested: bool,
    ) -> None:
        if isinstance(effect, Literal):
            lit = Lit(effect.atom.predicate, effect.atom.args, not effect.negated)
            out.append(NormEffect(parameters, condition, lit))
        elif isinstance(effect, AndEffect):
            for part in effect.parts:
                self.effect(part, parameters, condition, context, out, costs, nested)
        elif isinstance(effect, ForAllEffect):
            inner = dict(context)
            inner.update({p.name: p.type for p in effect.parameters})
            types = tuple(self.type_lit(p) for p in effect.parameters)
            names = parameters + tuple(p.name for p in effect.parameters)
            self.effect(effect.effect, names, condition + types, inner, out, costs, True)
        elif isinstance(effect, When):
            extra = tuple(self.conjunction(nnf(effect.condition), context))
            self.effect(effect.effect, parameters, condition + extra, context, out, costs, True)
        elif isinstance(effect, IncreaseCost):
            if nested:
                raise GroundingError("action costs inside conditional or universal effects")
            costs.append(effect.amount)

    def user_axiom(self, predicate: str, parameters: tuple[Parameter, ...], body: Formula) -> None:
        context = {p.name: p.type for p in parameters}
        extra = sorted(free_variables(body) - set(context))  # implicitly existential
        context.update(dict.fromkeys(extra, OBJECT_TYPE))
        lits = [self.type_lit(p) for p in parameters]
        lits += [Lit(OBJECT_TYPE, (v,)) for v in extra]
        lits += self.conjunction(nnf(body), context)
        head = tuple(p.name for p in parameters)
        self.aux_axioms.append(NormAxiom(predicate, head, tuple(dict.fromkeys(lits))))


def _strata(axioms: tuple[NormAxiom, ...], derived: frozenset[str]) -> dict[str, int]:
    strata = dict.fromkeys(derived, 0)
    for _ in range(len(derived) + 1):
        changed = False
        for axiom in axioms:
            for lit in axiom.body:
                if lit.predicate in derived:
                    need = strata[lit.predicate] + (0 if lit.positive else 1)
                    if strata[axiom.predicate] < need:
                        strata[axiom.predicate] = need
                        changed = True
        if not changed:
            return strata
    cyclic = sorted(p for p, s in strata.items() if s >= len(derived))
    raise GroundingError(f"derived predicates are not stratified (negation in a cycle): {cyclic}")


def normalize(task: PlanningTask) -> NormTask:
    """Rewrite ``task`` into conjunctive action, axiom and goal schemas."""
    normalizer = _Normalizer(task)
    for axiom in task.domain.axioms:
        normalizer.user_axiom(axiom.predicate, axiom.parameters, axiom.body)
    actions = tuple(normalizer.action(action) for action in task.domain.actions)
    goal = tuple(dict.fromkeys(normalizer.conjunction(nnf(task.goal), {})))
    axioms = tuple(normalizer.aux_axioms)
    derived = frozenset(normalizer.aux_names) | task.domain.derived_predicates
    fluent = frozenset(e.literal.predicate for a in actions for e in a.effects)
    bad = sorted(fluent & derived)
    if bad:
        raise GroundingError(f"derived predicates changed by an action effect: {bad}")
    facts = {
        (atom.predicate, atom.args)
        for atom in task.init
        if atom.predicate not in derived and atom.predicate != EQUALITY
    }
    for obj_type, objects in normalizer.objects_of_type.items():
        facts.update((obj_type, (obj,)) for obj in objects)
    return NormTask(
        actions=actions,
        axioms=axioms,
        goal=goal,
        derived=derived,
        fluent=fluent,
        strata=_strata(axioms, derived),
        facts=frozenset(facts),
    )
