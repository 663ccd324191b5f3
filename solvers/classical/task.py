"""The ground task: integer facts, ground operators and ground axioms.

Facts are numbered ``0 .. len(facts)-1``; only *fluent* facts (changed by some action) and
*derived* facts (heads of axioms) get numbers. Static facts were used up by grounding.
A state is a set of fact ids; the search packs it into a Python ``int`` bitset.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass
from functools import cached_property

from sdar_tamp.language.formula_model import Atom
from solvers.classical.problem import GroundAction, PlanningTask


@dataclass(frozen=True)
class ConditionalEffect:
    """``adds``/``deletes`` happen if ``condition`` holds and ``negative_condition`` does not."""

    condition: tuple[int, ...]
    negative_condition: tuple[int, ...]
    adds: tuple[int, ...]
    deletes: tuple[int, ...]


@dataclass(frozen=True)
class GroundOperator:
    """An applicable-if-reachable instance of an action schema."""

    name: str
    args: tuple[str, ...]
    precondition: tuple[int, ...]
    negative_precondition: tuple[int, ...]
    adds: tuple[int, ...]
    deletes: tuple[int, ...]
    conditional: tuple[ConditionalEffect, ...]
    cost: float

    @property
    def action(self) -> GroundAction:
        return GroundAction(self.name, self.args)


@dataclass(frozen=True)
class GroundAxiom:
    """``head`` holds when all of ``body`` holds and none of ``negative_body``."""

    head: int
    body: tuple[int, ...]
    negative_body: tuple[int, ...]
    stratum: int


@dataclass(frozen=True)
class GroundTask:
    """A grounded task. ``goal_reachable`` is False when relaxed reachability misses the goal."""

    facts: tuple[Atom, ...]
    derived: frozenset[int]
    init: frozenset[int]  # non-derived facts of the initial state
    goal: tuple[int, ...]
    negative_goal: tuple[int, ...]
    goal_reachable: bool
    operators: tuple[GroundOperator, ...]
    axioms: tuple[GroundAxiom, ...]
    #: the reachable facts of each static predicate (what :attr:`static_facts` lists)
    static_relations: Mapping[str, Collection[tuple[str, ...]]]
    source: PlanningTask

    @cached_property
    def static_facts(self) -> frozenset[Atom]:
        """The facts of static predicates (true in every state; built on first use)."""
        return frozenset(
            Atom(predicate, args)
            for predicate, relation in self.static_relations.items()
            for args in relation
        )

    def fact_id(self, atom: Atom) -> int:
        """The number of a fluent or derived fact (``ValueError`` if static or unreachable)."""
        return self.facts.index(atom)
