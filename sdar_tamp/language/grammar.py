"""Shared grammar pieces: typed lists, formulas and effects, with scope and arity checks."""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from operator import attrgetter

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import (
    ArityError,
    DuplicateError,
    PddlSyntaxError,
    UnboundVariableError,
    UndeclaredError,
    UnknownKeywordError,
    UnsupportedFeatureError,
)
from sdar_tamp.language.model import (
    EQUALITY,
    OBJECT_TYPE,
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
from sdar_tamp.language.sexpr import SExpr, SList, Symbol

# heads that make a list something else than an atom in a formula
_NOT_ATOMS = frozenset({EQUALITY, "and", "or", "not", "imply", "exists", "forall"})

_TEXT = attrgetter("text")

MAX_FORMULA_DEPTH = 100
"""Formulas and effects nested deeper than this are rejected with a located error (they are
read, and later used by the planners, recursively)."""


def expect_list(node: SExpr, what: str) -> SList:
    if not isinstance(node, SList):
        raise PddlSyntaxError(f"expected {what} in parentheses, found {node.text!r}", node.location)
    return node


def expect_symbol(node: SExpr, what: str) -> Symbol:
    if not isinstance(node, Symbol):
        raise PddlSyntaxError(f"expected {what}, found a list {node.excerpt()}", node.location)
    return node


def expect_head(node: SExpr, keyword: str, what: str) -> SList:
    """``node`` must be a list starting with ``keyword``."""
    lst = expect_list(node, what)
    if not lst.items or not isinstance(lst.items[0], Symbol) or lst.items[0].text != keyword:
        raise PddlSyntaxError(f"expected {what} starting with '{keyword}'", lst.location)
    return lst


def parse_options(
    section: SList, allowed: tuple[str, ...], what: str, start: int
) -> dict[str, SExpr]:
    """The ``:keyword value`` pairs of ``section`` from item ``start`` on (an action's or a
    stream's options), each keyword one of ``allowed`` and given once."""
    items = section.items[start:]
    if len(items) % 2:
        raise PddlSyntaxError(f"{what}: expected ':keyword value' pairs", section.location)
    options: dict[str, SExpr] = {}
    for key_node, value in zip(items[::2], items[1::2], strict=True):
        key = expect_symbol(key_node, "a keyword")
        if key.text not in allowed:
            raise UnknownKeywordError(
                f"unknown keyword {key.text!r} in {what}; expected one of {', '.join(allowed)}",
                key.location,
            )
        if key.text in options:
            raise DuplicateError(f"{key.text} is given twice in {what}", key.location)
        options[key.text] = value
    return options


def parse_name_header(node: SExpr, keyword: str) -> str:
    """``(domain NAME)``, ``(problem NAME)`` or ``(stream NAME)``."""
    header = expect_head(node, keyword, f"a header '({keyword} NAME)'")
    if len(header.items) != 2:
        raise PddlSyntaxError(f"expected '({keyword} NAME)'", header.location)
    return expect_symbol(header.items[1], f"the {keyword} name").text


def parse_typed_list(
    items: Sequence[SExpr],
    what: str,
    types: frozenset[str] | None,
    variables: bool,
    repeats: list[tuple[str, SourceLocation]] | None = None,
    either: Callable[[tuple[str, ...]], str] | None = None,
) -> list[tuple[str, str, Symbol]]:
    """Parse ``a b - t c`` into ``[(a, t), (b, t), (c, object)]``, each with its name's token
    (``token.location`` says where it is: worked out only when asked for).

    ``types`` None means the caller does not check types (type declarations themselves).
    ``variables`` requires every name to start with ``?``; otherwise none may. A name that
    appears twice is an error, unless ``repeats`` is given: then it is kept and noted there.
    ``either`` maps the member types of ``(either t1 t2 ...)`` to the type to use for them;
    without it such a type is an error.
    """
    result: list[tuple[str, str, Symbol]] = []
    pending: list[Symbol] = []
    index = 0
    count = len(items)
    while index < count:
        token = items[index]
        if not isinstance(token, Symbol):
            token = expect_symbol(token, what)  # the error, located
        if token.text == "-":
            if index + 1 >= count:
                raise PddlSyntaxError(f"expected a type name after '-' in {what}", token.location)
            type_node = items[index + 1]
            if not pending:
                raise PddlSyntaxError(f"expected a name before '-' in {what}", token.location)
            if isinstance(type_node, SList):
                type_name = _either_type(type_node, what, types, either)
            else:
                check_type(type_node, types)
                type_name = type_node.text
            result.extend((name.text, type_name, name) for name in pending)
            pending = []
            index += 2
            continue
        if variables != (token.text[0] == "?"):
            expected = "a variable starting with '?'" if variables else "a name (no '?')"
            raise PddlSyntaxError(
                f"expected {expected} in {what}, found {token.text!r}", token.location
            )
        pending.append(token)
        index += 1
    result.extend((name.text, OBJECT_TYPE, name) for name in pending)
    if len({name for name, _, _ in result}) == len(result):
        return result  # no name appears twice
    seen: set[str] = set()
    for name, _, token in result:
        if name in seen:
            if repeats is None:
                raise DuplicateError(f"{name!r} appears twice in {what}", token.location)
            repeats.append((name, token.location))
        seen.add(name)
    return result


_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def parse_number(token: Symbol, what: str) -> float:
    """A finite decimal number such as ``3``, ``-0.5`` or ``1e3`` (no ``nan``, ``inf``, ``1_0``).

    Raises:
        PddlSyntaxError: not a number, or one too large for a float (``1e309``).
    """
    if not _NUMBER.fullmatch(token.text):
        raise PddlSyntaxError(f"expected {what}, found {token.text!r}", token.location)
    value = float(token.text)
    if not math.isfinite(value):
        raise PddlSyntaxError(
            f"expected {what}, found {token.text!r}, which is too large for a finite value",
            token.location,
        )
    return value


def _either_type(
    node: SList,
    what: str,
    types: frozenset[str] | None,
    either: Callable[[tuple[str, ...]], str] | None,
) -> str:
    """The type standing for ``(either t1 t2 ...)`` in ``what`` (see :func:`parse_typed_list`)."""
    head = node.items[0] if node.items else None
    if not (isinstance(head, Symbol) and head.text == "either") or len(node.items) < 2:
        raise PddlSyntaxError(
            f"expected a type name or '(either TYPE ...)' in {what}", node.location
        )
    if either is None:
        raise UnsupportedFeatureError(
            f"'(either ...)' types are supported in predicate and function declarations, not "
            f"in {what}: declare a common supertype",
            node.location,
        )
    members = []
    for item in node.items[1:]:
        member = expect_symbol(item, "a type name in '(either ...)'")
        check_type(member, types)
        members.append(member.text)
    return either(tuple(members))


def check_type(node: Symbol, types: frozenset[str] | None) -> None:
    if types is not None and node.text not in types:
        raise UndeclaredError(
            f"undeclared type {node.text!r} (declared: {sorted(types)})", node.location
        )


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
                f"numeric effect '{keyword}' is not supported; only '(increase (total-cost) N)' is",
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
                "only '(increase (total-cost) ...)' is supported", target.location
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
        if functions[head.text] != arity:
            raise ArityError(
                f"function {head.text!r} takes {functions[head.text]} argument(s), got {arity}",
                location,
            )

    @staticmethod
    def _arity(node: SList, count: int, message: str) -> None:
        if len(node.items) != count + 1:
            raise PddlSyntaxError(message, node.location)
