"""A lifted state that applies a domain's actions one at a time (SDAR executes, not searches).

Facts are atoms over object names: ``static`` ones (initial facts and stream certificates) and
``fluents`` (the predicates some action changes). Conditions and effects mean what
:mod:`sdar_tamp.language.evaluator` and :mod:`sdar_tamp.language.state_changes` say; this class
keeps the facts, indexed by predicate, and changes them in place.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Collection, Iterable, Iterator, Mapping, Sequence

from sdar_tamp.errors import ActionError
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.evaluator import Evaluator
from sdar_tamp.language.formula_model import OBJECT_TYPE, Atom, Formula, FunctionTerm
from sdar_tamp.language.state_changes import effect_changes
from sdar_tamp.language.substitution import bind
from sdar_tamp.language.traversal import iter_effect_literals

Binding = Mapping[str, str]

__all__ = ["ActionError", "Binding", "LiftedState", "fluent_predicates"]


def fluent_predicates(domain: Domain) -> frozenset[str]:
    """Predicates some action adds or deletes."""
    return frozenset(
        literal.atom.predicate
        for action in domain.actions
        for literal in iter_effect_literals(action.effect)
    )


class LiftedState:
    """Static facts, the current fluents, and action application with costs.

    ``objects_of_type`` lists the objects of a type (quantifiers range over them); ``cost``
    gives a ground cost term's value.
    """

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
        self._by_predicate: dict[str, set[tuple[str, ...]]] = defaultdict(set)
        for atom in (*static, *fluents):
            self._by_predicate[atom.predicate].add(atom.args)
        self._of_type = objects_of_type
        self._cost = cost
        self._evaluator: Evaluator | None = None
        self.version = 0
        """Counts the actions applied: the fluents change only with it."""

    # -- facts (the Facts and Objects of language.state_index) ---------------------------------
    def __contains__(self, atom: object) -> bool:
        return isinstance(atom, Atom) and atom.args in self._by_predicate.get(atom.predicate, ())

    def args_of(self, predicate: str) -> Collection[tuple[str, ...]]:
        return self._by_predicate.get(predicate, ())

    def objects_of(self, type_name: str) -> Sequence[str]:
        return self._of_type(type_name)

    def has_type(self, name: str, type_name: str) -> bool:
        return (
            type_name == OBJECT_TYPE
            or (name,) in self._by_predicate.get(type_name, ())
            or name in self._of_type(type_name)
        )

    def add_static(self, atoms: Iterable[Atom]) -> None:
        for atom in atoms:
            if atom.predicate in self.fluent_names:
                raise ValueError(f"{atom} is a fluent; streams may not certify it")
            self._by_predicate[atom.predicate].add(atom.args)
            self._evaluator = None

    def has(self, predicate: str, *args: str) -> bool:
        return args in self._by_predicate.get(predicate, ())

    def atoms(self, predicate: str) -> Iterator[tuple[str, ...]]:
        yield from sorted(self._by_predicate.get(predicate, ()))

    def fluents(self) -> frozenset[Atom]:
        return frozenset(
            Atom(p, args) for p in self.fluent_names for args in self._by_predicate.get(p, ())
        )

    # -- evaluation ----------------------------------------------------------------------------
    def evaluator(self) -> Evaluator:
        """The evaluator of the current facts (a new one after every change)."""
        if self._evaluator is None:
            self._evaluator = Evaluator(self.domain, self, self)
        return self._evaluator

    def holds(self, formula: Formula, binding: Binding) -> bool:
        return self.evaluator().holds(formula, binding)

    # -- actions -------------------------------------------------------------------------------
    def applicable(self, name: str, args: Sequence[str]) -> bool:
        action = self.domain.action(name)
        return self.holds(action.precondition, bind(action, args))

    def apply(self, name: str, args: Sequence[str]) -> float:
        """Apply the action; returns its cost. Raises :class:`ActionError` if not applicable."""
        action = self.domain.action(name)
        binding = bind(action, args)
        evaluator = self.evaluator()
        if not evaluator.holds(action.precondition, binding):
            raise ActionError(f"({name} {' '.join(args)}): precondition does not hold")
        changes = effect_changes(evaluator, action.effect, binding, self._cost)
        for atom in changes.deletes:
            self._by_predicate[atom.predicate].discard(atom.args)
        for atom in changes.adds:
            self._by_predicate[atom.predicate].add(atom.args)
        self._evaluator = None
        self.version += 1
        return changes.cost
