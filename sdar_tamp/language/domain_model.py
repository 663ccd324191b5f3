"""The typed model of a PDDL domain and problem: declarations, schemas and their containers.

Immutable values built by :mod:`sdar_tamp.language.domain_reader` and
:mod:`sdar_tamp.language.problem_reader` from the pieces of
:mod:`sdar_tamp.language.formula_model` (names stored lower-case).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.durative import DurativeActionSchema
from sdar_tamp.language.formula_model import (
    OBJECT_TYPE,
    TOTAL_COST,
    Atom,
    Effect,
    Formula,
    Parameter,
)
from sdar_tamp.language.leniency import Leniency
from sdar_tamp.language.numeric import Comparison, NumericEffect


@dataclass(frozen=True)
class Predicate:
    name: str
    parameters: tuple[Parameter, ...] = ()

    @property
    def arity(self) -> int:
        return len(self.parameters)


@dataclass(frozen=True)
class Function:
    name: str
    parameters: tuple[Parameter, ...] = ()


@dataclass(frozen=True)
class ActionSchema:
    """A domain's ``(:action ...)``: the lifted schema (a plan step is
    :class:`solvers.solution.Action`)."""

    name: str
    parameters: tuple[Parameter, ...]
    precondition: Formula
    effect: Effect
    location: SourceLocation | None = field(default=None, compare=False)
    numeric_conditions: tuple[Comparison, ...] = ()
    """Numeric conditions, conjuncts of the precondition (:mod:`sdar_tamp.language.numeric`)."""
    numeric_effects: tuple[NumericEffect, ...] = ()
    """Numeric effects (and ``(increase (total-cost) ...)`` by an expression), conjuncts of
    the effect."""


@dataclass(frozen=True)
class Axiom:
    """A derived predicate: ``(:derived (predicate ?params) body)``."""

    predicate: str
    parameters: tuple[Parameter, ...]
    body: Formula
    location: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class TypeHierarchy:
    """Types and their parents; ``object`` is the root and has no parent."""

    parents: Mapping[str, str] = field(default_factory=dict)

    def ancestors(self, type_name: str) -> tuple[str, ...]:
        """``type_name`` followed by its ancestors up to ``object`` (inclusive)."""
        chain = [type_name]
        while chain[-1] != OBJECT_TYPE:
            chain.append(self.parents.get(chain[-1], OBJECT_TYPE))
        return tuple(chain)

    def is_subtype(self, child: str, parent: str) -> bool:
        return parent in self.ancestors(child)

    def types(self) -> tuple[str, ...]:
        return (OBJECT_TYPE, *sorted(self.parents))


@dataclass(frozen=True)
class Domain:
    name: str
    requirements: frozenset[str]
    types: TypeHierarchy
    constants: Mapping[str, str]  # name -> type
    predicates: Mapping[str, Predicate]
    functions: Mapping[str, Function]
    actions: tuple[ActionSchema, ...]
    axioms: tuple[Axiom, ...]
    durative_actions: tuple[DurativeActionSchema, ...] = ()
    """The ``(:durative-action ...)`` as written; ``actions`` holds each one compiled into an
    instantaneous action of the same name (:mod:`sdar_tamp.language.sequential`)."""
    source: str | None = field(default=None, compare=False)
    leniencies: tuple[Leniency, ...] = field(default=(), compare=False)
    """What was accepted although strict PDDL rejects it (see ``language.leniency``)."""

    @property
    def derived_predicates(self) -> frozenset[str]:
        return frozenset(axiom.predicate for axiom in self.axioms)

    @property
    def numeric_fluents(self) -> frozenset[str]:
        """The functions that some action's numeric effect changes (``total-cost`` aside)."""
        return frozenset(
            effect.target.name
            for action in self.actions
            for effect in action.numeric_effects
            if effect.target.name != TOTAL_COST
        )

    @property
    def numeric(self) -> bool:
        """True when an action has a numeric condition or effect (other than an action cost
        given as a number or one function term)."""
        return any(a.numeric_conditions or a.numeric_effects for a in self.actions)

    @property
    def temporal(self) -> bool:
        """True when the domain has durative actions (its plans are timed)."""
        return bool(self.durative_actions)

    def durative_action(self, name: str) -> DurativeActionSchema | None:
        """The durative action called ``name``, or None (an instantaneous action, or none)."""
        for action in self.durative_actions:
            if action.name == name.lower():
                return action
        return None

    def action(self, name: str) -> ActionSchema:
        for action in self.actions:
            if action.name == name.lower():
                return action
        raise KeyError(name)


@dataclass(frozen=True)
class Problem:
    name: str
    domain_name: str
    objects: Mapping[str, str]  # name -> type
    init: tuple[Atom, ...]
    numeric_init: Mapping[tuple[str, tuple[str, ...]], float]
    goal: Formula
    minimize_cost: bool = False
    source: str | None = field(default=None, compare=False)
    leniencies: tuple[Leniency, ...] = field(default=(), compare=False)
    """What was accepted although strict PDDL rejects it (see ``language.leniency``)."""
