"""The typed model's building blocks: terms, parameters, formulas, numeric expressions, effects.

Everything here is an immutable value. Names (predicates, actions, objects, types) are stored
lower-case, since PDDL names are case-insensitive. A *term* is a plain string: a variable when it
starts with ``?``, otherwise an object (constant) name. Objects that stand for arbitrary
Python values are given string names by :mod:`sdar_tamp.language.problem`, so solvers only
ever see strings.

Formulas::

    Atom("on", ("?x", "b1"))            # (on ?x b1); the predicate "=" is equality
    Not(Atom(...)), And((...)), Or((...)), Imply(a, b)
    Exists((Parameter("?x", "block"),), body), ForAll(...)

``And(())`` is true and ``Or(())`` is false. The declarations and containers built from them are
in :mod:`sdar_tamp.language.domain_model` and :mod:`sdar_tamp.language.stream_model`; walking
and rewriting them is :mod:`sdar_tamp.language.traversal`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeAlias

OBJECT_TYPE = "object"
EQUALITY = "="
TOTAL_COST = "total-cost"

Term: TypeAlias = str


def is_variable(term: Term) -> bool:
    """True for a variable term (``?x``)."""
    return term.startswith("?")


@dataclass(frozen=True)
class Parameter:
    """A typed variable, e.g. ``?b - block``."""

    name: str
    type: str = OBJECT_TYPE


@dataclass(frozen=True)
class Atom:
    """``(predicate arg1 ... argn)``; ``predicate == "="`` is equality."""

    predicate: str
    args: tuple[Term, ...] = ()

    def __str__(self) -> str:
        return f"({' '.join((self.predicate, *self.args))})"


@dataclass(frozen=True)
class Not:
    formula: Formula


@dataclass(frozen=True)
class And:
    parts: tuple[Formula, ...]


@dataclass(frozen=True)
class Or:
    parts: tuple[Formula, ...]


@dataclass(frozen=True)
class Imply:
    antecedent: Formula
    consequent: Formula


@dataclass(frozen=True)
class Exists:
    parameters: tuple[Parameter, ...]
    body: Formula


@dataclass(frozen=True)
class ForAll:
    parameters: tuple[Parameter, ...]
    body: Formula


Formula: TypeAlias = Atom | Not | And | Or | Imply | Exists | ForAll

TRUE: Formula = And(())
FALSE: Formula = Or(())


# --- numeric expressions (action costs) -------------------------------------------------------


@dataclass(frozen=True)
class FunctionTerm:
    """A numeric function applied to terms, e.g. ``(distance ?a ?b)``."""

    name: str
    args: tuple[Term, ...] = ()


NumericExpr: TypeAlias = float | FunctionTerm


# --- effects ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Literal:
    """An add (``negated=False``) or delete (``negated=True``) effect on one atom."""

    atom: Atom
    negated: bool = False


@dataclass(frozen=True)
class AndEffect:
    parts: tuple[Effect, ...]


@dataclass(frozen=True)
class ForAllEffect:
    parameters: tuple[Parameter, ...]
    effect: Effect


@dataclass(frozen=True)
class When:
    """A conditional effect: ``effect`` happens when ``condition`` holds before the action."""

    condition: Formula
    effect: Effect


@dataclass(frozen=True)
class IncreaseCost:
    """``(increase (total-cost) amount)``."""

    amount: NumericExpr


Effect: TypeAlias = Literal | AndEffect | ForAllEffect | When | IncreaseCost
