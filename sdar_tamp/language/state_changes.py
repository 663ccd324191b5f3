"""What an action's effect does to a state (:func:`effect_changes`, :class:`Changes`).

The effect is evaluated in the state before the action: conditional effects whose condition
holds there (decided by :class:`~sdar_tamp.language.evaluator.Evaluator`), universal effects
over the objects of their types, deletes applied before adds (:meth:`Changes.apply`, so an atom
both added and deleted stays true), and ``(increase (total-cost) ...)`` summed through a
``cost_of`` callback.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from sdar_tamp.errors import EvaluationError
from sdar_tamp.language.evaluator import EMPTY, Evaluator, Support
from sdar_tamp.language.formula_model import (
    AndEffect,
    Atom,
    Effect,
    ForAllEffect,
    FunctionTerm,
    Literal,
    When,
    is_variable,
)
from sdar_tamp.language.substitution import Binding, ground_args, ground_atom

CostOf = Callable[[FunctionTerm], float]


@dataclass(frozen=True)
class Changes:
    """What one action does to a state: ``adds``, ``deletes``, its ``cost``, and (with an
    explaining evaluator) the facts its effect conditions relied on (``support``)."""

    adds: frozenset[Atom] = frozenset()
    deletes: frozenset[Atom] = frozenset()
    cost: float = 0.0
    support: Support = EMPTY

    def apply(self, state: frozenset[Atom]) -> frozenset[Atom]:
        """The next state: deletes first, then adds (an atom both added and deleted holds)."""
        return (state - self.deletes) | self.adds


def effect_changes(
    evaluator: Evaluator, effect: Effect, binding: Binding, cost_of: CostOf | None = None
) -> Changes:
    """The changes ``effect`` makes, evaluated in ``evaluator``'s state (the one before the
    action). ``cost_of`` gives a ground cost term's value; without it costs count 0.

    Raises:
        EvaluationError: an effect atom or cost term has a variable that nothing binds.
    """
    adds: set[Atom] = set()
    deletes: set[Atom] = set()
    support: set[Atom] = set()
    cost = 0.0

    def visit(node: Effect, inner: Binding) -> None:
        nonlocal cost
        if isinstance(node, Literal):
            atom = ground_atom(node.atom, inner)
            if any(is_variable(a) for a in atom.args):
                raise EvaluationError(f"unbound variable in the effect {atom}")
            (deletes if node.negated else adds).add(atom)
        elif isinstance(node, AndEffect):
            for part in node.parts:
                visit(part, inner)
        elif isinstance(node, ForAllEffect):
            for extended in evaluator.every(node.parameters, inner):
                visit(node.effect, extended)
        elif isinstance(node, When):
            found = evaluator.support(node.condition, inner)
            if found is not None:
                support.update(found)
                visit(node.effect, inner)
        else:
            amount = node.amount
            if isinstance(amount, FunctionTerm):
                term = FunctionTerm(amount.name, ground_args(amount.args, inner))
                if any(is_variable(a) for a in term.args):
                    raise EvaluationError(f"unbound variable in the cost term {term}")
                if cost_of is not None:
                    cost += cost_of(term)
            elif cost_of is not None:
                cost += amount

    visit(effect, binding)
    return Changes(frozenset(adds), frozenset(deletes), cost, frozenset(support))
