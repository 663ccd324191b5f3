"""S-expression reader with source positions, shared by the domain, problem and stream parsers."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeAlias

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import PddlSyntaxError


@dataclass(frozen=True)
class Symbol:
    """One token; ``text`` is lower-cased (PDDL names are case-insensitive)."""

    text: str
    location: SourceLocation

    def __str__(self) -> str:
        return self.text


@dataclass(frozen=True)
class SList:
    """A parenthesised list; ``location`` is that of its opening parenthesis."""

    items: tuple[SExpr, ...]
    location: SourceLocation

    def __len__(self) -> int:
        return len(self.items)

    def __str__(self) -> str:
        return "(" + " ".join(str(item) for item in self.items) + ")"


SExpr: TypeAlias = Symbol | SList


def read_sexpr(text: str, filename: str | None = None) -> SList:
    """Read exactly one top-level list from ``text``.

    Raises:
        PddlSyntaxError: unbalanced parentheses, an empty source or text after the list.
    """
    stack: list[tuple[SourceLocation, list[SExpr]]] = []
    result: SList | None = None
    line, column = 1, 1
    index, length = 0, len(text)
    while index < length:
        char = text[index]
        here = SourceLocation(filename, line, column)
        if char == "\n":
            line, column = line + 1, 1
            index += 1
            continue
        if char in " \t\r\f\v":
            index, column = index + 1, column + 1
            continue
        if char == ";":
            while index < length and text[index] != "\n":
                index += 1
            continue
        if char == ")" and not stack:
            raise PddlSyntaxError("unbalanced parentheses: ')' without a matching '('", here)
        if result is not None:
            raise PddlSyntaxError("unexpected text after the closing parenthesis", here)
        if char == "(":
            stack.append((here, []))
            index, column = index + 1, column + 1
        elif char == ")":
            start, items = stack.pop()
            node = SList(tuple(items), start)
            if stack:
                stack[-1][1].append(node)
            else:
                result = node
            index, column = index + 1, column + 1
        else:
            # A '?' always starts a new token, as in Fast Downward and VAL: (at?x) is (at ?x).
            end = index + 1
            while end < length and text[end] not in " \t\r\n\f\v();?":
                end += 1
            if not stack:
                raise PddlSyntaxError(f"expected '(' but found {text[index:end]!r}", here)
            stack[-1][1].append(Symbol(text[index:end].lower(), here))
            column += end - index
            index = end
    if stack:
        raise PddlSyntaxError("unbalanced parentheses: '(' is never closed", stack[-1][0])
    if result is None:
        raise PddlSyntaxError(
            "expected a definition '(define ...)' but the source is empty",
            SourceLocation(filename, line, column),
        )
    return result
