"""Reading formulas and effects: :class:`FormulaReader` turns s-expressions into the typed
model's formulas, effects and numeric expressions, checking names, scopes and arities against
a :class:`Vocabulary` (the predicates, types, constants and functions formulas may mention)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from operator import attrgetter

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import (
    ArityError,
    PddlSyntaxError,
    UnboundVariableError,
    UndeclaredError,
    UnsupportedFeatureError,
)
from sdar_tamp.language.formula_model import (
    EQUALITY,
    TOTAL_COST,
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
    NumericExpr,
    Or,
    Parameter,
    When,
)
from sdar_tamp.language.grammar import expect_list, expect_symbol, parse_number, parse_typed_list
from sdar_tamp.language.sexpr import SExpr, SList, Symbol

# heads that make a list something else than an atom in a formula
_NOT_ATOMS = frozenset({EQUALITY, "and", "or", "not", "imply", "exists", "forall"})

_TEXT = attrgetter("text")
_NUMERIC_COMPARISONS = frozenset({"<", "<=", ">", ">="})

MAX_FORMULA_DEPTH = 100
"""Formulas and effects nested deeper than this are rejected with a located error (they are
read, and later used by the planners, recursively)."""


@dataclass
class Vocabulary:
    """What formulas may mention: predicate and function arities, types and constants."""

    predicates: dict[str, int]
    types: frozenset[str]
    constants: Mapping[str, str]
    functions: dict[str, int] = field(default_factory=dict)
    derived: frozenset[str] = frozenset()
    allow_new_functions: bool = False
    filename: str | None = None
    implicit_predicates: dict[str, SourceLocation] | None = None
    """When not None, an undeclared predicate is declared at its first use (noted here)."""
    open_arity_functions: set[str] = field(default_factory=set)
    """Functions declared with no arguments whose first use sets their arity (PDDLStream
    programs declare ``(:functions (Cost))`` and use ``(Cost ?a ?b)``)."""
    function_arity_uses: dict[str, tuple[int, SourceLocation]] = field(default_factory=dict)
    """The open-arity functions first used with arguments: their arity and that use."""


class FormulaReader:
    """Turns s-expressions into model formulas and effects, checking names and scopes."""

    def __init__(self, vocabulary: Vocabulary) -> None:
        self.vocabulary = vocabulary
        self._depth = 0
        self._free: dict[str, SourceLocation] | None = None

    def open_formula(
        self, node: SExpr, scope: Mapping[str, str]
    ) -> tuple[Formula, dict[str, SourceLocation]]:
        """A formula that may use variables bound nowhere, and those variables.

        Each free variable is returned with the location of its first use, in order of first
        use; the caller decides what they mean (Fast Downward reads them as existentially
        quantified over the whole formula).
        """
        outer = self._free
        self._free = {}
        try:
            return self.formula(node, scope), self._free
        finally:
            self._free = outer

    def _enter(self, node: SExpr, what: str) -> None:
        if self._depth >= MAX_FORMULA_DEPTH:
            raise PddlSyntaxError(
                f"{what} nested deeper than {MAX_FORMULA_DEPTH} levels", node.location
            )
        self._depth += 1

    # --- terms and atoms ----------------------------------------------------------------------

    def parameters(self, node: SExpr, what: str) -> tuple[Parameter, ...]:
        lst = expect_list(node, what)
        parsed = parse_typed_list(lst.items, what, self.vocabulary.types, variables=True)
        return tuple(Parameter(name, type_name) for name, type_name, _ in parsed)

    def term(self, node: SExpr, scope: Mapping[str, str]) -> str:
        token = expect_symbol(node, "a term (a variable or an object name)")
        text = token.text
        if text.startswith("?"):
            if text not in scope:
                if self._free is not None:
                    self._free.setdefault(text, token.location)
                    return text
                raise UnboundVariableError(f"variable {text} is not bound here", token.location)
        elif text not in self.vocabulary.constants:
            raise UndeclaredError(f"undeclared constant or object {text!r}", token.location)
        return text

    def atom(self, node: SList, scope: Mapping[str, str]) -> Atom:
        head = expect_symbol(node.items[0] if node.items else node, "a predicate name")
        name = head.text
        constants = self.vocabulary.constants
        # the common case (object names and bound variables) inline: init sections are large
        args = tuple(
            [
                arg.text
                if type(arg) is Symbol
                and (arg.text in scope if arg.text[0] == "?" else arg.text in constants)
                else self.term(arg, scope)  # the error, located
                for arg in node.items[1:]
            ]
        )
        if name == EQUALITY:
            expected = 2
        elif name in self.vocabulary.predicates:
            expected = self.vocabulary.predicates[name]
        elif name in self.vocabulary.types:
            expected = 1
        elif self.vocabulary.implicit_predicates is not None:
            expected = self.vocabulary.predicates[name] = len(args)
            self.vocabulary.implicit_predicates[name] = head.location
        else:
            raise UndeclaredError(f"undeclared predicate {name!r}", head.location)
        if len(args) != expected:
            raise ArityError(
                f"predicate {name!r} takes {expected} argument(s), got {len(args)}", node.location
            )
        return Atom(name, args)

    def plain_atoms(self, nodes: Sequence[SExpr], scope: Mapping[str, str]) -> list[Atom | None]:
        """Each node as an atom when it plainly is one, else None.

        Plainly: a list of symbols whose head is a declared predicate (not ``=`` nor a formula
        keyword) with as many arguments as its arity, each a known object or a variable bound
        in ``scope``. That is what large ``:init`` sections and goals are made of, and it is
        checked here in a few lookups per node; for a None the caller takes the general path,
        which gives the same atom or the located error.
        """
        arity = self.vocabulary.predicates.get
        known = self.vocabulary.constants.__contains__
        atoms: list[Atom | None] = []
        append = atoms.append
        for node in nodes:
            atom = None
            items = node.items if type(node) is SList else ()
            head = items[0] if items else None
            if type(head) is Symbol:
                try:
                    args = tuple(map(_TEXT, items[1:]))
                except AttributeError:  # a list among the arguments
                    args = None
                if (
                    args is not None
                    and arity(head.text) == len(args)
                    and head.text not in _NOT_ATOMS
                    and (all(map(known, args)) or self._bound(args, scope))
                ):
                    atom = Atom(head.text, args)
            append(atom)
        return atoms

    def _bound(self, names: Sequence[str], scope: Mapping[str, str]) -> bool:
        """Whether every name is an object or a variable bound in ``scope``."""
        constants = self.vocabulary.constants
        return all(name in scope if name[0] == "?" else name in constants for name in names)

    # --- formulas -----------------------------------------------------------------------------

    def formula(self, node: SExpr, scope: Mapping[str, str]) -> Formula:
        self._enter(node, "formula")
        try:
            return self._formula(node, scope)
        finally:
            self._depth -= 1

    def _formula(self, node: SExpr, scope: Mapping[str, str]) -> Formula:
        lst = expect_list(node, "a formula")
        if not lst.items:
            return And(())
        head = lst.items[0]
        keyword = head.text if isinstance(head, Symbol) else ""
        rest = lst.items[1:]
        if keyword == "and":
            if self._depth >= MAX_FORMULA_DEPTH:  # a part would be too deep: the error, located
                return And(tuple(self.formula(part, scope) for part in rest))
            atoms = self.plain_atoms(rest, scope)
            return And(
                tuple(
                    [
                        self.formula(part, scope) if atom is None else atom
                        for atom, part in zip(atoms, rest, strict=True)
                    ]
                )
            )
        if keyword == "or":
            return Or(tuple(self.formula(part, scope) for part in rest))
        if keyword == "not":
            self._arity(lst, 1, "'not' takes one formula")
            return Not(self.formula(rest[0], scope))
        if keyword == "imply":
            self._arity(lst, 2, "'imply' takes two formulas")
            return Imply(self.formula(rest[0], scope), self.formula(rest[1], scope))
        if keyword in ("exists", "forall"):
            self._arity(lst, 2, f"'{keyword}' takes a parameter list and a formula")
            params = self.parameters(rest[0], f"the parameters of '{keyword}'")
            inner = {**scope, **{p.name: p.type for p in params}}
            body = self.formula(rest[1], inner)
            return Exists(params, body) if keyword == "exists" else ForAll(params, body)
        if keyword in _NUMERIC_COMPARISONS or (
            keyword == EQUALITY and any(isinstance(item, SList) for item in rest)
        ):
            raise UnsupportedFeatureError(
                f"a numeric condition ('{keyword}') is supported only as a conjunct of an "
                "action's precondition or of a durative action's timed condition (not in a "
                "goal, a derived predicate, 'or', 'not', 'imply' or a quantifier)",
                lst.location,
            )
        return self.atom(lst, scope)

    def conjunction(self, node: SExpr, scope: Mapping[str, str], what: str) -> tuple[Atom, ...]:
        """A conjunction of positive atoms (stream domains and certified facts)."""
        formula = self.formula(node, scope)
        parts = formula.parts if isinstance(formula, And) else (formula,)
        atoms: list[Atom] = []
        for part in parts:
            if not isinstance(part, Atom):
                raise PddlSyntaxError(f"{what} must be a conjunction of atoms", node.location)
            atoms.append(part)
        return tuple(atoms)

    # --- effects ------------------------------------------------------------------------------

    def effect(self, node: SExpr, scope: Mapping[str, str]) -> Effect:
        self._enter(node, "effect")
        try:
            return self._effect(node, scope)
        finally:
            self._depth -= 1

    def _effect(self, node: SExpr, scope: Mapping[str, str]) -> Effect:
        lst = expect_list(node, "an effect")
        if not lst.items:
            return AndEffect(())
        head = lst.items[0]
        keyword = head.text if isinstance(head, Symbol) else ""
        rest = lst.items[1:]
        if keyword == "and":
            return AndEffect(tuple(self.effect(part, scope) for part in rest))
        if keyword == "not":
            self._arity(lst, 1, "'not' takes one atom")
            return Literal(self._effect_atom(rest[0], scope), negated=True)
        if keyword == "forall":
            self._arity(lst, 2, "'forall' takes a parameter list and an effect")
            params = self.parameters(rest[0], "the parameters of 'forall'")
            inner = {**scope, **{p.name: p.type for p in params}}
            return ForAllEffect(params, self.effect(rest[1], inner))
        if keyword == "when":
            self._arity(lst, 2, "'when' takes a condition and an effect")
            return When(self.formula(rest[0], scope), self.effect(rest[1], scope))
        if keyword == "increase":
            return self._increase(lst, scope)
        if keyword in ("decrease", "assign", "scale-up", "scale-down"):
            raise UnsupportedFeatureError(
                f"a numeric effect ('{keyword}') is supported only as a conjunct of an action's "
                "effect (not inside 'when' or 'forall')",
                lst.location,
            )
        return Literal(self._effect_atom(lst, scope))

    def _effect_atom(self, node: SExpr, scope: Mapping[str, str]) -> Atom:
        lst = expect_list(node, "an atom")
        atom = self.atom(lst, scope)
        if atom.predicate == EQUALITY or atom.predicate in self.vocabulary.derived:
            raise PddlSyntaxError(
                f"{atom.predicate!r} cannot appear in an effect (equality or derived predicate)",
                lst.location,
            )
        return atom

    def _increase(self, node: SList, scope: Mapping[str, str]) -> IncreaseCost:
        self._arity(node, 2, "'increase' takes '(total-cost)' and an amount")
        target = expect_list(node.items[1], "'(total-cost)'")
        if (
            len(target.items) != 1
            or expect_symbol(target.items[0], "total-cost").text != TOTAL_COST
        ):
            raise UnsupportedFeatureError(
                "a numeric effect ('increase') on a fluent other than 'total-cost' is supported "
                "only as a conjunct of an action's effect (not inside 'when' or 'forall')",
                target.location,
            )
        return IncreaseCost(self.numeric(node.items[2], scope))

    def numeric(self, node: SExpr, scope: Mapping[str, str]) -> NumericExpr:
        if isinstance(node, Symbol):
            value = parse_number(node, "a finite number or a function term")
            if value < 0:
                raise PddlSyntaxError(
                    f"action costs must be non-negative, got {value}", node.location
                )
            return value
        head = expect_symbol(node.items[0] if node.items else node, "a function name")
        args = tuple(self.term(arg, scope) for arg in node.items[1:])
        self.function_arity(head, len(args), node.location)
        return FunctionTerm(head.text, args)

    def function_arity(self, head: Symbol, arity: int, location: SourceLocation) -> None:
        functions = self.vocabulary.functions
        if head.text not in functions:
            if not self.vocabulary.allow_new_functions:
                raise UndeclaredError(f"undeclared function {head.text!r}", head.location)
            functions[head.text] = arity
        if head.text in self.vocabulary.open_arity_functions:
            self.vocabulary.open_arity_functions.discard(head.text)
            if arity != functions[head.text]:
                functions[head.text] = arity
                self.vocabulary.function_arity_uses[head.text] = (arity, location)
        if functions[head.text] != arity:
            raise ArityError(
                f"function {head.text!r} takes {functions[head.text]} argument(s), got {arity}",
                location,
            )

    @staticmethod
    def _arity(node: SList, count: int, message: str) -> None:
        if len(node.items) != count + 1:
            raise PddlSyntaxError(message, node.location)
