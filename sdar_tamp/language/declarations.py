"""Reading a domain's declarations: the type hierarchy (``:types``), predicate and function
declarations (``(name ?a - t ?b)``, with ``(either ...)`` argument types read as their most
specific common supertype), and the leniencies they may need (duplicate and undeclared parent
types, repeated variables)."""

from __future__ import annotations

import itertools
from collections.abc import Mapping

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.domain_model import Function, Predicate, TypeHierarchy
from sdar_tamp.language.errors import DuplicateError, PddlSyntaxError
from sdar_tamp.language.formula_model import OBJECT_TYPE, Parameter
from sdar_tamp.language.formula_reader import FormulaReader
from sdar_tamp.language.grammar import expect_list, expect_symbol, parse_typed_list
from sdar_tamp.language.leniency import (
    DUPLICATE_TYPE,
    REPEATED_VARIABLE,
    UNDECLARED_PARENT_TYPE,
    LeniencyLog,
)
from sdar_tamp.language.sexpr import SExpr, Symbol


def declare_types(body: tuple[SExpr, ...], parents: dict[str, str], log: LeniencyLog) -> None:
    """Add the types of a ``(:types ...)`` section to ``parents`` (type -> parent type); an
    undeclared supertype becomes a subtype of ``object``."""
    repeats: list[tuple[str, SourceLocation]] = []
    declared = parse_typed_list(body, "the types", None, variables=False, repeats=repeats)
    for child, parent, token in declared:
        if child == OBJECT_TYPE:
            continue
        earlier = parents.get(child)
        if earlier is not None and OBJECT_TYPE not in (earlier, parent) and earlier != parent:
            raise DuplicateError(
                f"type {child!r} is declared twice, as a subtype of {earlier!r} and of {parent!r}",
                token.location,
            )
        if earlier is not None:
            kept = earlier if parent == OBJECT_TYPE else parent
            log.add(
                DUPLICATE_TYPE,
                f"type {child!r} is declared twice; kept as a subtype of {kept!r}",
                token.location,
            )
            parent = kept
        parents[child] = parent
    noted: set[str] = set()
    for dash, node in itertools.pairwise(body):
        if (
            isinstance(dash, Symbol)
            and dash.text == "-"
            and isinstance(node, Symbol)
            and node.text not in parents
            and node.text != OBJECT_TYPE
            and node.text not in noted
        ):
            noted.add(node.text)
            log.add(
                UNDECLARED_PARENT_TYPE,
                f"parent type {node.text!r} is not declared in :types; it is taken to be a "
                "subtype of 'object'",
                node.location,
            )
    for child, parent in list(parents.items()):
        seen = {child}
        while parent != OBJECT_TYPE:
            if parent not in parents:
                parents[parent] = OBJECT_TYPE  # an undeclared supertype is implicitly an object
                break
            if parent in seen:
                raise PddlSyntaxError(
                    f"type {child!r} is its own ancestor", body[0].location if body else None
                )
            seen.add(parent)
            parent = parents[parent]


def common_supertype(members: tuple[str, ...], parents: Mapping[str, str]) -> str:
    """The most specific type that every one of ``members`` is a subtype of (given the
    ``parents`` of the declared types)."""
    chains = [TypeHierarchy(parents).ancestors(member) for member in members]
    return next(t for t in chains[0] if all(t in chain for chain in chains[1:]))


def declaration(
    node: SExpr,
    reader: FormulaReader,
    what: str,
    log: LeniencyLog | None = None,
    parents: Mapping[str, str] | None = None,
) -> Predicate:
    """``(name ?a - t ?b)``; with ``log``, a repeated variable name is noted, not an error.
    With ``parents`` (predicate and function declarations, whose types only describe the
    arguments), ``?a - (either t1 t2)`` is read as the most specific common supertype of its
    members."""
    lst = expect_list(node, what)
    head = expect_symbol(lst.items[0] if lst.items else lst, "a name")
    repeats: list[tuple[str, SourceLocation]] = []
    params = parse_typed_list(
        lst.items[1:],
        f"the parameters of {head.text!r}",
        reader.vocabulary.types,
        variables=True,
        repeats=repeats if log is not None else None,
        either=None if parents is None else (lambda members: common_supertype(members, parents)),
    )
    if log is not None:
        for variable, location in repeats:
            log.add(
                REPEATED_VARIABLE,
                f"variable {variable} appears twice in the declaration of {head.text!r}",
                location,
            )
    return Predicate(head.text, tuple(Parameter(n, t) for n, t, _ in params))


def declare_functions(
    body: tuple[SExpr, ...],
    reader: FormulaReader,
    functions: dict[str, Function],
    parents: Mapping[str, str],
) -> None:
    """Declare the functions of a ``(:functions ...)`` section in ``functions`` and in
    ``reader``'s vocabulary (``- number`` types are skipped)."""
    index = 0
    while index < len(body):
        node = body[index]
        if isinstance(node, Symbol) and node.text == "-":
            index += 2  # "- number": the only function type
            continue
        declared = declaration(node, reader, "a function declaration", parents=parents)
        functions[declared.name] = Function(declared.name, declared.parameters)
        reader.vocabulary.functions[declared.name] = declared.arity
        index += 1
