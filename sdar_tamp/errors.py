"""The project's exception hierarchy: one base class, specific subclasses.

A problem in a file carries its :class:`SourceLocation` (file, line, column) so that the
message reads ``domain.pddl:12:5: expected ...``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SourceLocation:
    """A position in a text source. ``line`` and ``column`` count from 1."""

    file: str | None
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file or '<string>'}:{self.line}:{self.column}"


class SdarError(Exception):
    """Base class of every error this project raises on purpose."""


class LocatedError(SdarError):
    """An error tied to a place in a source file."""

    def __init__(self, message: str, location: SourceLocation | None = None) -> None:
        self.message = message
        self.location = location
        super().__init__(f"{location}: {message}" if location is not None else message)


class ParameterError(SdarError, ValueError):
    """A bad argument value: names the parameter and what was expected."""


class ActionError(SdarError):
    """An action applied with the wrong arguments or where its precondition does not hold (in a
    solver, a bug rather than a user error)."""


class EvaluationError(SdarError):
    """A formula that cannot be evaluated, such as an atom with a variable nothing binds."""
