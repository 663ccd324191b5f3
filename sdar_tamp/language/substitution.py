"""Binding variables to objects: grounding atoms and arguments, an action's parameter binding,
and the free variables of a formula."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from sdar_tamp.errors import ActionError
from sdar_tamp.language.domain_model import ActionSchema
from sdar_tamp.language.formula_model import (
    And,
    Atom,
    Formula,
    Imply,
    Not,
    Or,
    Parameter,
    Term,
    is_variable,
)

Binding = Mapping[str, str]


def ground_args(args: Iterable[Term], binding: Binding) -> tuple[str, ...]:
    """``args`` with every bound variable replaced by its value."""
    return tuple(binding.get(a, a) for a in args)


def ground_atom(atom: Atom, binding: Binding) -> Atom:
    """``atom`` with every bound variable replaced by its value."""
    return Atom(atom.predicate, ground_args(atom.args, binding))


def bind(action: ActionSchema, args: Sequence[str]) -> dict[str, str]:
    """The binding of ``action``'s parameters to ``args``.

    Raises:
        ActionError: ``args`` has not one value per parameter.
    """
    if len(args) != len(action.parameters):
        raise ActionError(
            f"({' '.join((action.name, *args))}): wrong number of arguments "
            f"(expected {len(action.parameters)}, got {len(args)})"
        )
    return {p.name: a for p, a in zip(action.parameters, args, strict=True)}


def free_parameters(formula: Formula, bound: Iterable[str]) -> tuple[Parameter, ...]:
    """The variables of ``formula`` that neither ``bound`` nor a quantifier binds, in order of
    first use (typed ``object``)."""
    seen: dict[str, None] = {}

    def visit(node: Formula, scope: frozenset[str]) -> None:
        if isinstance(node, Atom):
            for arg in node.args:
                if is_variable(arg) and arg not in scope:
                    seen.setdefault(arg)
        elif isinstance(node, Not):
            visit(node.formula, scope)
        elif isinstance(node, And | Or):
            for part in node.parts:
                visit(part, scope)
        elif isinstance(node, Imply):
            visit(node.antecedent, scope)
            visit(node.consequent, scope)
        else:
            visit(node.body, scope | {p.name for p in node.parameters})

    visit(formula, frozenset(bound))
    return tuple(Parameter(name) for name in seen)
