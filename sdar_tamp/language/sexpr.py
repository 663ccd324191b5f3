"""S-expression reader with source positions, shared by the domain, problem and stream parsers.

The reader tokenises the whole text with one regular expression and builds lists with an explicit
stack, so nesting depth is not limited by Python's recursion limit. Nodes keep the character
offset of their first character; ``line:column`` is computed only when a location is asked for
(an error message, a declaration's place), by bisecting the line starts of the source.
"""

from __future__ import annotations

import gc
import re
from bisect import bisect_right
from collections.abc import Iterator
from contextlib import contextmanager
from itertools import accumulate
from typing import NamedTuple, TypeAlias

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import PddlSyntaxError

# A token: a comment (skipped), a parenthesis or a symbol. Only the six whitespace characters
# of the class, parentheses and ';' end a symbol.
# A symbol takes its first character, then runs to whitespace, a parenthesis, a comment or a
# '?': a '?' always starts a new token, as in Fast Downward and VAL ((at?x) reads as (at ?x)).
_SPLIT = re.compile(r"(;[^\n]*|[()]|[^ \t\r\n\f\v();][^ \t\r\n\f\v();?]*)")
_SYMBOL = re.compile(r"[^ \t\r\n\f\v();][^ \t\r\n\f\v();?]*")
_NEWLINE = re.compile(r"\n")
_GLUE_BREAKS = frozenset(" \t\r\n\f\v()")  # a '?' after one of these starts a token anyway


class SourceText:
    """One source text and its file name; turns character offsets into :class:`SourceLocation`.

    Lines end at ``\\n``; ``line`` and ``column`` count from 1, and a column counts characters
    (a tab is one column).
    """

    __slots__ = ("_line_starts", "filename", "glued", "text")

    def __init__(self, text: str, filename: str | None = None) -> None:
        self.filename = filename
        self.text = text
        self._line_starts: list[int] | None = None
        #: offsets of the '?' tokens the reader split off the symbol right before them, as in
        #: ``(aircraft?a)`` (filled by :func:`read_sexpr`)
        self.glued: list[int] = []

    def location(self, offset: int) -> SourceLocation:
        """The location of the character at ``offset`` (0-based) in the text."""
        starts = self._line_starts
        if starts is None:
            starts = [0]
            starts.extend(match.end() for match in _NEWLINE.finditer(self.text))
            self._line_starts = starts
        line = bisect_right(starts, offset)
        return SourceLocation(self.filename, line, offset - starts[line - 1] + 1)

    def __repr__(self) -> str:
        return f"SourceText({self.filename!r}, {len(self.text)} characters)"


class Symbol(NamedTuple):
    """One token; ``text`` is lower-cased (PDDL names are case-insensitive)."""

    text: str
    offset: int
    source: SourceText

    @property
    def location(self) -> SourceLocation:
        """Where the token starts."""
        return self.source.location(self.offset)

    def __str__(self) -> str:
        return self.text


class SList(NamedTuple):
    """A parenthesised list; its ``location`` is that of its opening parenthesis.

    ``len()`` counts the items. Nodes are named tuples: immutable and cheap to build.
    """

    items: tuple[SExpr, ...]
    offset: int
    source: SourceText

    @property
    def location(self) -> SourceLocation:
        """Where the opening parenthesis is."""
        return self.source.location(self.offset)

    def with_items(self, items: tuple[SExpr, ...]) -> SList:
        """A list at the same place with other ``items``."""
        return SList(items, self.offset, self.source)

    def __len__(self) -> int:
        return len(self.items)

    def __str__(self) -> str:
        # Iterative, so that printing a deeply nested list cannot exhaust the Python stack.
        parts: list[str] = []
        stack: list[SExpr | str] = [self]
        while stack:
            node = stack.pop()
            if isinstance(node, str):
                parts.append(node)
            elif isinstance(node, Symbol):
                parts.append(node.text)
            else:
                parts.append("(")
                stack.append(")")
                for index in range(len(node.items) - 1, -1, -1):
                    stack.append(node.items[index])
                    if index:
                        stack.append(" ")
        return "".join(parts)

    def excerpt(self, limit: int = 60) -> str:
        """The text of the list, cut to ``limit`` characters (for messages)."""
        text = str(self)
        return text if len(text) <= limit else text[: limit - 3] + "..."

    def __repr__(self) -> str:
        return f"SList({self.excerpt()} at {self.location})"


SExpr: TypeAlias = Symbol | SList


@contextmanager
def collector_paused() -> Iterator[None]:
    """Pause Python's cyclic garbage collector meanwhile (and restore it as it was).

    Parsing builds many objects and no reference cycles, so the collector can only waste time
    on them (a third of the reading time on large files); memory is freed as usual, by
    reference counting.
    """
    collecting = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if collecting:
            gc.enable()


def read_sexpr(text: str, filename: str | None = None) -> SList:
    """Read exactly one top-level list from ``text``.

    Raises:
        PddlSyntaxError: unbalanced parentheses, an empty source or text after the list.
    """
    source = SourceText(text, filename)
    with collector_paused():
        top, stack = _build(source)
    _check_top(top, source)
    if stack:
        if top:
            raise PddlSyntaxError(
                "unexpected text after the closing parenthesis", source.location(stack[0][0])
            )
        raise PddlSyntaxError(
            "unbalanced parentheses: '(' is never closed", source.location(stack[-1][0])
        )
    if not top:
        raise PddlSyntaxError(
            "expected a definition '(define ...)' but the source is empty",
            source.location(len(text)),
        )
    root = top[0]
    assert isinstance(root, SList)  # _check_top rejects a symbol
    return root


def _build(source: SourceText) -> tuple[list[SExpr], list[tuple[int, list[SExpr]]]]:
    """The top-level nodes of ``source`` and the lists still open at its end (offset, items)."""
    text = source.text
    # ASCII lower-casing maps each character to one character, so offsets stay valid.
    ascii_text = text.isascii()
    # parts alternates separators (whitespace, maybe empty) and tokens; the running sum of
    # the part lengths gives each token's offset.
    parts = _SPLIT.split(text.lower() if ascii_text else text)
    ends = list(accumulate(map(len, parts)))
    new = tuple.__new__
    top: list[SExpr] = []
    stack: list[tuple[int, list[SExpr]]] = []
    items = top  # the items of the innermost open list
    glued = source.glued
    # parts[0::2] are the separators, so ends[0::2] are where the tokens start
    for start, token in zip(ends[:-1:2], parts[1::2], strict=True):
        if token == "(":
            stack.append((start, items))
            items = []
        elif token == ")":
            if not stack:
                _check_top(top, source)
                raise PddlSyntaxError(
                    "unbalanced parentheses: ')' without a matching '('", source.location(start)
                )
            begin, parent = stack.pop()
            parent.append(new(SList, (tuple(items), begin, source)))
            items = parent
        elif token[0] != ";":
            # a '?' right after a symbol (no whitespace, no parenthesis, and a comment always
            # ends before a line break) was split off it
            if token[0] == "?" and start and text[start - 1] not in _GLUE_BREAKS:
                glued.append(start)
            if not ascii_text:
                token = token.lower()
            items.append(new(Symbol, (token, start, source)))
    return top, stack


def _check_top(top: list[SExpr], source: SourceText) -> None:
    """The first error among the top-level nodes read so far, in text order."""
    if top and isinstance(top[0], Symbol):
        match = _SYMBOL.match(source.text, top[0].offset)
        word = match.group() if match else top[0].text
        raise PddlSyntaxError(f"expected '(' but found {word!r}", top[0].location)
    if len(top) > 1:
        raise PddlSyntaxError("unexpected text after the closing parenthesis", top[1].location)
