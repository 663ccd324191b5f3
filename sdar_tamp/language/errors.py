"""Errors raised while reading domain, problem and stream files (all carry ``file:line:col``)."""

from __future__ import annotations

from sdar_tamp.errors import LocatedError, SdarError


class PddlError(LocatedError):
    """Base class of every error about a PDDL or stream source."""


class PddlSyntaxError(PddlError):
    """Unbalanced parentheses, a missing token, or a token that is not what the grammar expects."""


class UnknownKeywordError(PddlError):
    """A section or option keyword (``:foo``) that this language does not have."""


class UndeclaredError(PddlError):
    """A predicate, type, constant, object or function that was never declared."""


class ArityError(PddlError):
    """A predicate or function used with the wrong number of arguments."""


class UnboundVariableError(PddlError):
    """A variable used outside the parameters or quantifiers that bind it."""


class DuplicateError(PddlError):
    """A name declared twice where names must be unique (parameters, objects, actions...)."""


class StreamDefinitionError(PddlError):
    """A stream that breaks the stream well-formedness rules."""


class UnsupportedFeatureError(PddlError):
    """A construct that is recognised but not supported (for example ``:optimizer``)."""


class ProblemDefinitionError(PddlError):
    """A bad ``PDDLProblem``: a constant map that misses or adds constants, a bad init fact..."""


class StreamMapError(SdarError):
    """A ``stream_map`` that lacks a stream's callable or names a stream that does not exist."""
