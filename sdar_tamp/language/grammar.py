"""Shared grammar pieces of the domain, problem and stream-file readers: expected lists, symbols
and headers, ``:keyword value`` options, typed lists (with ``(either ...)`` types) and numbers.

Formulas and effects are read by :mod:`sdar_tamp.language.formula_reader`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import (
    DuplicateError,
    PddlSyntaxError,
    UndeclaredError,
    UnknownKeywordError,
    UnsupportedFeatureError,
)
from sdar_tamp.language.formula_model import OBJECT_TYPE
from sdar_tamp.language.sexpr import SExpr, SList, Symbol


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
