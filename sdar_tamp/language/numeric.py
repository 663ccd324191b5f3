"""Numeric fluents (PDDL 2.1 level 2): expressions, conditions, effects, and their reading.

An action may compare numeric expressions in its precondition (``(>= (fuel ?r) 1)``, as a
conjunct of the precondition) and change numeric fluents in its effect (``(decrease (fuel ?r)
(distance ?a ?b))``, ``assign``, ``increase``, ``scale-up``, ``scale-down``, as a conjunct of
the effect). Expressions are numbers, function terms and ``+ - * /`` over them; in a durative
action ``?duration`` too (:data:`DURATION_TERM`). Outside these places (inside ``or``, ``not``,
a quantifier, a ``when`` or a ``forall`` effect, a derived predicate, a goal) a numeric
condition or effect is refused with a located
:class:`~sdar_tamp.language.errors.UnsupportedFeatureError`.

The classical planner plans over them by compiling them away for the reachable values
(:mod:`sdar_tamp.language.numeric_compile`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol, TypeAlias

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import PddlSyntaxError, UnsupportedFeatureError
from sdar_tamp.language.formula_model import EQUALITY, TOTAL_COST, FunctionTerm, Term
from sdar_tamp.language.grammar import expect_list, expect_symbol, parse_number
from sdar_tamp.language.sexpr import SExpr, SList, Symbol

COMPARISONS = frozenset({"<", "<=", ">", ">=", EQUALITY})
ARITHMETIC = frozenset({"+", "-", "*", "/"})
NUMERIC_EFFECTS = frozenset({"assign", "increase", "decrease", "scale-up", "scale-down"})
DURATION = "?duration"
DURATION_TERM = FunctionTerm(DURATION)
"""``?duration`` in an expression of a durative action (the duration, fixed at its start)."""


@dataclass(frozen=True)
class Arithmetic:
    """``(op a b ...)`` for ``op`` in ``+ - * /``; ``(- a)`` is the negation."""

    operator: str
    operands: tuple[Expression, ...]


Expression: TypeAlias = float | FunctionTerm | Arithmetic


@dataclass(frozen=True)
class Comparison:
    """A numeric condition ``(op left right)`` for ``op`` in ``< <= > >= =``."""

    operator: str
    left: Expression
    right: Expression
    location: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class NumericEffect:
    """``(operator target value)``: ``assign``, ``increase``, ``decrease``, ``scale-up`` or
    ``scale-down`` of the fluent ``target``."""

    operator: str
    target: FunctionTerm
    value: Expression
    location: SourceLocation | None = field(default=None, compare=False)

    def as_assignment(self) -> Expression:
        """The target's new value as an expression of the values before the effect."""
        op = {"increase": "+", "decrease": "-", "scale-up": "*", "scale-down": "/"}
        if self.operator == "assign":
            return self.value
        return Arithmetic(op[self.operator], (self.target, self.value))


Lookup: TypeAlias = Callable[[FunctionTerm], float | None]
"""The value of a ground function term, or None when it has none (undefined)."""


def evaluate(expression: Expression, lookup: Lookup) -> float | None:
    """The value of a ground ``expression``; None when a term is undefined or a division is by
    zero (the action is then not applicable, as in PDDL 2.1)."""
    if isinstance(expression, float | int):
        return float(expression)
    if isinstance(expression, FunctionTerm):
        return lookup(expression)
    values: list[float] = []
    for operand in expression.operands:
        value = evaluate(operand, lookup)
        if value is None:
            return None
        values.append(value)
    op = expression.operator
    if op == "-" and len(values) == 1:
        return -values[0]
    result = values[0]
    for value in values[1:]:
        if op == "+":
            result += value
        elif op == "-":
            result -= value
        elif op == "*":
            result *= value
        elif value == 0:
            return None
        else:
            result /= value
    return result if math.isfinite(result) else None


def holds(condition: Comparison, lookup: Lookup) -> bool:
    """Whether a ground ``condition`` holds (False when a side is undefined)."""
    left, right = evaluate(condition.left, lookup), evaluate(condition.right, lookup)
    if left is None or right is None:
        return False
    op = condition.operator
    if op == "<":
        return left < right
    if op == "<=":
        return left <= right
    if op == ">":
        return left > right
    if op == ">=":
        return left >= right
    return math.isclose(left, right, rel_tol=1e-9, abs_tol=1e-12)


def function_terms(expression: Expression) -> list[FunctionTerm]:
    """The function terms of ``expression`` (``?duration`` included), left to right."""
    if isinstance(expression, FunctionTerm):
        return [expression]
    if isinstance(expression, Arithmetic):
        return [t for operand in expression.operands for t in function_terms(operand)]
    return []


def numeric_terms(action: _HasNumericParts) -> list[FunctionTerm]:
    """The function terms ``action``'s numeric conditions and effects read (targets and
    ``?duration`` aside), in order, each once."""
    exprs: list[Expression] = []
    for condition in action.numeric_conditions:
        exprs.extend((condition.left, condition.right))
    exprs.extend(effect.value for effect in action.numeric_effects)
    terms = (t for e in exprs for t in function_terms(e) if t != DURATION_TERM)
    return list(dict.fromkeys(terms))


class _HasNumericParts(Protocol):
    @property
    def numeric_conditions(self) -> tuple[Comparison, ...]: ...

    @property
    def numeric_effects(self) -> tuple[NumericEffect, ...]: ...


def substitute_terms(
    expression: Expression, replace: Callable[[FunctionTerm], Expression]
) -> Expression:
    """``expression`` with each function term ``t`` replaced by ``replace(t)``."""
    if isinstance(expression, FunctionTerm):
        return replace(expression)
    if isinstance(expression, Arithmetic):
        return Arithmetic(
            expression.operator,
            tuple(substitute_terms(o, replace) for o in expression.operands),
        )
    return expression


def rename_args(expression: Expression, binding: Mapping[Term, Term]) -> Expression:
    """``expression`` with the arguments of its function terms renamed by ``binding``."""
    return substitute_terms(
        expression, lambda t: FunctionTerm(t.name, tuple(binding.get(a, a) for a in t.args))
    )


def is_comparison(node: SExpr) -> bool:
    """Whether ``node`` reads as a numeric condition: ``(< ...)``... or an ``=`` with a list
    argument (``(= (fuel ?r) 0)``; ``(= ?a ?b)`` is equality of objects)."""
    if not isinstance(node, SList) or not node.items:
        return False
    head = node.items[0]
    if not isinstance(head, Symbol) or head.text not in COMPARISONS:
        return False
    if head.text == EQUALITY:
        return any(isinstance(item, SList) for item in node.items[1:])
    return True


def is_numeric_effect(node: SExpr) -> bool:
    """Whether ``node`` is ``(assign ...)``, ``(increase ...)``... on a fluent other than
    ``total-cost``, or an ``(increase (total-cost) ...)`` whose amount is an arithmetic
    expression (a plain number or function term stays an ordinary action cost)."""
    if not isinstance(node, SList) or len(node.items) != 3:
        return False
    head, target, amount = node.items
    if not isinstance(head, Symbol) or head.text not in NUMERIC_EFFECTS:
        return False
    if not (isinstance(target, SList) and target.items and isinstance(target.items[0], Symbol)):
        return True  # malformed: the reader reports it
    if target.items[0].text != TOTAL_COST or head.text != "increase":
        return True
    if isinstance(amount, Symbol):
        return amount.text == DURATION
    head_of_amount = amount.items[0] if amount.items else None
    return isinstance(head_of_amount, Symbol) and head_of_amount.text in ARITHMETIC


class NumericReader:
    """Reads numeric expressions, conditions and effects; ``function(head, args, location)``
    checks a function term (declared, arity) and returns its name."""

    def __init__(
        self,
        term: Callable[[SExpr, Mapping[str, str]], Term],
        function: Callable[[Symbol, int, SourceLocation], None],
        *,
        duration: bool = False,
    ) -> None:
        self._term = term
        self._function = function
        self._duration = duration

    def expression(self, node: SExpr, scope: Mapping[str, str]) -> Expression:
        if isinstance(node, Symbol):
            if node.text == DURATION:
                if not self._duration:
                    raise PddlSyntaxError(
                        "'?duration' is only defined in a durative action", node.location
                    )
                return DURATION_TERM
            if node.text.startswith("?"):
                raise UnsupportedFeatureError(
                    f"variable {node.text} is an object, not a number; numeric expressions are "
                    "numbers, function terms and + - * / over them",
                    node.location,
                )
            return parse_number(node, "a number, a function term or an arithmetic expression")
        head = expect_symbol(node.items[0] if node.items else node, "a function name")
        if head.text in ARITHMETIC:
            operands = tuple(self.expression(item, scope) for item in node.items[1:])
            if not operands or (len(operands) == 1 and head.text != "-"):
                raise PddlSyntaxError(
                    f"'{head.text}' takes two or more operands ('-' one or more)", node.location
                )
            return Arithmetic(head.text, operands)
        return self.function_term(node, scope)

    def function_term(self, node: SList, scope: Mapping[str, str]) -> FunctionTerm:
        head = expect_symbol(node.items[0] if node.items else node, "a function name")
        if head.text in COMPARISONS or head.text in NUMERIC_EFFECTS:
            raise PddlSyntaxError(
                f"expected a function term, got '({head.text} ...)'", node.location
            )
        args = tuple(self._term(arg, scope) for arg in node.items[1:])
        self._function(head, len(args), node.location)
        return FunctionTerm(head.text, args)

    def comparison(self, node: SExpr, scope: Mapping[str, str]) -> Comparison:
        lst = expect_list(node, "a numeric condition")
        if len(lst.items) != 3:
            raise PddlSyntaxError(
                "a numeric condition takes two expressions, '(op left right)'", lst.location
            )
        op = expect_symbol(lst.items[0], "a comparison").text
        left = self.expression(lst.items[1], scope)
        right = self.expression(lst.items[2], scope)
        return Comparison(op, left, right, lst.location)

    def effect(self, node: SExpr, scope: Mapping[str, str]) -> NumericEffect:
        lst = expect_list(node, "a numeric effect")
        op = expect_symbol(lst.items[0] if lst.items else lst, "a numeric effect").text
        if len(lst.items) != 3:
            raise PddlSyntaxError(f"'{op}' takes a function term and an expression", lst.location)
        target = expect_list(lst.items[1], f"the function term that '{op}' changes")
        head = target.items[0] if target.items else None
        if isinstance(head, Symbol) and head.text == TOTAL_COST and op != "increase":
            raise UnsupportedFeatureError(
                f"'{op}' of 'total-cost': action costs may only be increased", lst.location
            )
        return NumericEffect(
            op, self.function_term(target, scope), self.expression(lst.items[2], scope),
            lst.location,
        )  # fmt: skip


def split_conjuncts(
    node: SExpr | None, numeric: Callable[[SExpr], bool]
) -> tuple[SExpr | None, list[SExpr]]:
    """``node`` without its top-level conjuncts for which ``numeric`` holds (nested ``and``
    flattened), and those conjuncts. None stays None."""
    if node is None:
        return None, []
    if numeric(node):
        return SList((), node.offset, node.source), [node]
    if not (isinstance(node, SList) and node.items):
        return node, []
    head = node.items[0]
    if not (isinstance(head, Symbol) and head.text == "and"):
        return node, []
    kept: list[SExpr] = [head]
    found: list[SExpr] = []
    for item in node.items[1:]:
        rest, parts = split_conjuncts(item, numeric)
        found.extend(parts)
        if parts and isinstance(rest, SList) and not rest.items:
            continue
        kept.append(rest if rest is not None else item)
    if not found:
        return node, []
    return SList(tuple(kept), node.offset, node.source), found
