"""A lifted state that applies a domain's actions one at a time (SDAR executes, not searches).

Facts are atoms over object names: ``static`` ones (initial facts and stream certificates) and
``fluents`` (the predicates some action changes). Preconditions are evaluated on the lifted
formulas; a derived atom is evaluated on demand from its axiom's body. An existential
quantifier is solved by matching a positive atom of its body against the facts (so it costs
a scan of one predicate's atoms, not a product over typed objects); only when its body has no
such atom does it range over the objects of the parameter's type.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence

from sdar_tamp.language.model import (
    EQUALITY,
    And,
    AndEffect,
    Atom,
    Domain,
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
    iter_effect_literals,
)

Binding = Mapping[str, str]


class ActionError(Exception):
    """An action applied where its precondition does not hold (a solver bug, not user error)."""


def fluent_predicates(domain: Domain) -> frozenset[str]:
    """Predicates some action adds or deletes."""
    return frozenset(
        literal.atom.predicate
        for action in domain.actions
        for literal in iter_effect_literals(action.effect)
    )


class LiftedState:
    """Static facts, the current fluents, and action application with costs."""

    def __init__(
        self,
        domain: Domain,
        static: Iterable[Atom],
        fluents: Iterable[Atom],
        objects_of_type: Callable[[str], Sequence[str]],
        cost: Callable[[FunctionTerm], float],
    ) -> None:
        self.domain = domain
        self.fluent_names = fluent_predicates(domain)
        self.axioms = {a.predicate: a for a in domain.axioms}
        self._by_predicate: dict[str, set[tuple[str, ...]]] = defaultdict(set)
        for atom in (*static, *fluents):
            self._by_predicate[atom.predicate].add(atom.args)
        self._of_type = objects_of_type
        self._cost = cost

    # -- facts ---------------------------------------------------------------------------------
    def add_static(self, atoms: Iterable[Atom]) -> None:
        for atom in atoms:
            if atom.predicate in self.fluent_names:
                raise ValueError(f"{atom} is a fluent; streams may not certify it")
            self._by_predicate[atom.predicate].add(atom.args)

    def has(self, predicate: str, *args: str) -> bool:
        return args in self._by_predicate.get(predicate, ())

    def atoms(self, predicate: str) -> Iterator[tuple[str, ...]]:
        yield from sorted(self._by_predicate.get(predicate, ()))

    def fluents(self) -> frozenset[Atom]:
        return frozenset(
            Atom(p, args) for p in self.fluent_names for args in self._by_predicate.get(p, ())
        )

    # -- evaluation ----------------------------------------------------------------------------
    def holds(self, formula: Formula, binding: Binding) -> bool:
        if isinstance(formula, Atom):
            args = tuple(binding.get(a, a) for a in formula.args)
            if formula.predicate == EQUALITY:
                return len(set(args)) <= 1
            axiom = self.axioms.get(formula.predicate)
            if axiom is not None:
                inner = {p.name: a for p, a in zip(axiom.parameters, args, strict=True)}
                return self.holds(axiom.body, inner)
            return args in self._by_predicate.get(formula.predicate, ())
        if isinstance(formula, Not):
            return not self.holds(formula.formula, binding)
        if isinstance(formula, And):
            return all(self.holds(p, binding) for p in formula.parts)
        if isinstance(formula, Or):
            return any(self.holds(p, binding) for p in formula.parts)
        if isinstance(formula, Imply):
            return not self.holds(formula.antecedent, binding) or self.holds(
                formula.consequent, binding
            )
        if isinstance(formula, Exists):
            return any(
                self.holds(formula.body, b)
                for b in self._candidates(formula.parameters, formula.body, binding)
            )
        assert isinstance(formula, ForAll)
        return all(self.holds(formula.body, b) for b in self._typed(formula.parameters, binding))

    def _candidates(
        self, parameters: tuple[Parameter, ...], body: Formula, binding: Binding
    ) -> Iterator[dict[str, str]]:
        names = {p.name for p in parameters}
        parts = body.parts if isinstance(body, And) else (body,)
        anchors = [
            p
            for p in parts
            if isinstance(p, Atom)
            and p.predicate != EQUALITY
            and p.predicate not in self.axioms
            and names <= set(p.args)
        ]
        if not anchors:
            yield from self._typed(parameters, binding)
            return
        anchor = min(anchors, key=lambda a: len(self._by_predicate.get(a.predicate, ())))
        for args in sorted(self._by_predicate.get(anchor.predicate, ())):
            b = dict(binding)
            if all(_unify(t, v, b, names) for t, v in zip(anchor.args, args, strict=True)):
                yield b

    def _typed(self, parameters: tuple[Parameter, ...], binding: Binding) -> list[dict[str, str]]:
        result = [dict(binding)]
        for p in parameters:
            result = [{**b, p.name: o} for b in result for o in self._of_type(p.type)]
        return result

    # -- actions -------------------------------------------------------------------------------
    def applicable(self, name: str, args: Sequence[str]) -> bool:
        action = self.domain.action(name)
        binding = {p.name: a for p, a in zip(action.parameters, args, strict=True)}
        return self.holds(action.precondition, binding)

    def apply(self, name: str, args: Sequence[str]) -> float:
        """Apply the action; returns its cost. Raises :class:`ActionError` if not applicable."""
        action = self.domain.action(name)
        if len(args) != len(action.parameters):
            raise ActionError(f"({name} {' '.join(args)}): wrong number of arguments")
        binding = {p.name: a for p, a in zip(action.parameters, args, strict=True)}
        if not self.holds(action.precondition, binding):
            raise ActionError(f"({name} {' '.join(args)}): precondition does not hold")
        adds: list[Atom] = []
        deletes: list[Atom] = []
        cost = self._effects(action.effect, binding, adds, deletes)
        for atom in deletes:
            self._by_predicate[atom.predicate].discard(atom.args)
        for atom in adds:
            self._by_predicate[atom.predicate].add(atom.args)
        return cost

    def _effects(
        self, effect: Effect, binding: Binding, adds: list[Atom], deletes: list[Atom]
    ) -> float:
        if isinstance(effect, Literal):
            atom = Atom(effect.atom.predicate, tuple(binding.get(a, a) for a in effect.atom.args))
            (deletes if effect.negated else adds).append(atom)
            return 0.0
        if isinstance(effect, AndEffect):
            return sum(self._effects(p, binding, adds, deletes) for p in effect.parts)
        if isinstance(effect, ForAllEffect):
            return sum(
                self._effects(effect.effect, b, adds, deletes)
                for b in self._typed(effect.parameters, binding)
            )
        if isinstance(effect, When):
            if self.holds(effect.condition, binding):
                return self._effects(effect.effect, binding, adds, deletes)
            return 0.0
        assert isinstance(effect, IncreaseCost)
        amount = effect.amount
        if isinstance(amount, FunctionTerm):
            return self._cost(
                FunctionTerm(amount.name, tuple(binding.get(a, a) for a in amount.args))
            )
        return float(amount)


def _unify(term: str, value: str, binding: dict[str, str], variables: set[str]) -> bool:
    if term in variables:
        if term in binding:
            return binding[term] == value
        binding[term] = value
        return True
    return binding.get(term, term) == value
