"""Constructs the parsers accept although strict PDDL rejects them, and the warnings about them.

Real PDDL files and PDDLStream programs rely on what Fast Downward, VAL and PDDLStream accept, so
the parsers accept it too, note each case as a :class:`Leniency` (kept on the parsed model and
logged), and reject it only with ``strict=True`` (:class:`StrictModeError`). The kinds:

``glued-variable``
    ``(aircraft?a)`` reads as ``(aircraft ?a)``: a ``?`` always starts a new token.
``repeated-variable``
    ``(in ?obj ?obj)`` in a predicate declaration (the names there are placeholders).
``implicit-predicate``
    a predicate used in ``:init``, a goal or a stream's ``:domain`` but never declared; it is
    declared with the arity of its first use (a later use with another arity is still an error).
``duplicate-predicate``
    a predicate declared twice with the same arity (the first declaration is kept).
``duplicate-type``
    a type declared twice in ``:types``, with the same parent or once under ``object`` (IPC's
    storage domain: ``area - object`` and ``area - surface``); the more specific parent is kept
    (two different parents other than ``object`` are still an error).
``undeclared-parent-type``
    ``(:types a - b)`` where ``b`` is never declared: ``b`` becomes a subtype of ``object``.
``free-variable``
    a variable in an action precondition or a derived predicate's body that is neither a
    parameter nor quantified: read as existentially quantified over that formula, as Fast
    Downward's translator does.
``init-type``
    an initial fact whose argument's type is not the declared parameter type.
``function-arity``
    a function declared with no arguments (``(:functions (Cost))``) and used with some
    (``(Cost ?a ?b)``), as PDDLStream programs do: the first use gives its arity, which a
    stream file's ``(:function (Cost ?a ?b) ...)`` must then match.

``unused-certified``, ``unachievable-predicate``, ``untyped-output``
    a stream file checked against its domain (:mod:`sdar_tamp.language.cross_check`): a
    certified predicate nothing reads, a predicate the domain reads that nothing makes true,
    an action parameter of a declared type read where only a stream's (untyped) output can be.

``undeclared-parent-type``, ``init-type``, ``function-arity``, ``unachievable-predicate`` and
``untyped-output`` are more likely mistakes than dialect, so they are logged as warnings; the
others at info level (``unused-certified`` too: PDDLStream programs often certify type-like
facts such as ``(Grasp ?o ?g)`` that nothing reads; ``sdar check`` still prints it as a
warning).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from dataclasses import dataclass

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.errors import PddlError
from sdar_tamp.language.sexpr import SList

LOGGER = logging.getLogger("sdar_tamp.language")

GLUED_VARIABLE = "glued-variable"
REPEATED_VARIABLE = "repeated-variable"
IMPLICIT_PREDICATE = "implicit-predicate"
DUPLICATE_PREDICATE = "duplicate-predicate"
DUPLICATE_TYPE = "duplicate-type"
UNDECLARED_PARENT_TYPE = "undeclared-parent-type"
INIT_TYPE = "init-type"
FREE_VARIABLE = "free-variable"
FUNCTION_ARITY = "function-arity"
UNUSED_CERTIFIED = "unused-certified"
UNACHIEVABLE_PREDICATE = "unachievable-predicate"
UNTYPED_OUTPUT = "untyped-output"

KINDS = (
    GLUED_VARIABLE,
    REPEATED_VARIABLE,
    IMPLICIT_PREDICATE,
    DUPLICATE_PREDICATE,
    DUPLICATE_TYPE,
    UNDECLARED_PARENT_TYPE,
    INIT_TYPE,
    FREE_VARIABLE,
    FUNCTION_ARITY,
    UNUSED_CERTIFIED,
    UNACHIEVABLE_PREDICATE,
    UNTYPED_OUTPUT,
)
_WARNING_KINDS = frozenset(
    {UNDECLARED_PARENT_TYPE, INIT_TYPE, FUNCTION_ARITY, UNACHIEVABLE_PREDICATE, UNTYPED_OUTPUT}
)


@dataclass(frozen=True)
class Leniency:
    """One accepted construct that strict PDDL rejects (``kind`` is one of :data:`KINDS`)."""

    kind: str
    message: str
    location: SourceLocation | None = None

    @property
    def level(self) -> int:
        """The logging level it is reported at (warning for likely mistakes, else info)."""
        return logging.WARNING if self.kind in _WARNING_KINDS else logging.INFO

    def __str__(self) -> str:
        where = f"{self.location}: " if self.location is not None else ""
        return f"{where}{self.message} [{self.kind}]"


class StrictModeError(PddlError):
    """Raised by a parser called with ``strict=True`` when the source needs any leniency.

    ``leniencies`` lists every one of them, in source order; the message has one per line.
    """

    def __init__(self, leniencies: Iterable[Leniency]) -> None:
        self.leniencies = tuple(leniencies)
        lines = "\n".join(f"  {item}" for item in self.leniencies)
        first = self.leniencies[0].location if self.leniencies else None
        super().__init__(
            f"strict mode: {len(self.leniencies)} construct(s) that strict PDDL rejects:\n{lines}",
            first,
        )


class LeniencyLog:
    """Collects the leniencies of one parse; logs them (lenient mode) or raises (strict mode)."""

    def __init__(self, strict: bool) -> None:
        self.strict = strict
        self._items: list[Leniency] = []

    def add(self, kind: str, message: str, location: SourceLocation | None) -> None:
        self._items.append(Leniency(kind, message, location))

    def finish(self) -> tuple[Leniency, ...]:
        """The leniencies in source order, each logged once.

        Raises:
            StrictModeError: in strict mode, when there is any.
        """
        items = tuple(sorted(self._items, key=_order))
        if self.strict and items:
            raise StrictModeError(items)
        for item in items:
            LOGGER.log(item.level, "%s", item)
        return items


def note_glued_variables(root: SList, log: LeniencyLog) -> None:
    """Note every variable written right after the previous token, as in ``(aircraft?a)``.

    The reader splits such tokens and keeps their offsets (``SourceText.glued``).
    """
    source = root.source
    for offset in source.glued:
        end = offset + 1
        while end < len(source.text) and source.text[end] not in " \t\r\n\f\v();?":
            end += 1
        before = offset
        while before > 0 and source.text[before - 1] not in " \t\r\n\f\v();":
            before -= 1
            if source.text[before] == "?":
                break  # the token before is a variable itself: (?x?y)
        log.add(
            GLUED_VARIABLE,
            f"{source.text[offset:end].lower()!r} is glued to the token before it "
            f"({source.text[before:offset].lower()!r}); read as two tokens",
            source.location(offset),
        )


def _order(item: Leniency) -> tuple[int, int]:
    location = item.location
    return (location.line, location.column) if location is not None else (0, 0)
