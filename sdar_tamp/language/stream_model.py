"""The typed model of a stream file: streams, stream functions and predicates, rules.

Immutable values built by :mod:`sdar_tamp.language.streams` (PDDLStream syntax) from the pieces
of :mod:`sdar_tamp.language.formula_model`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.formula_model import Atom, FunctionTerm
from sdar_tamp.language.leniency import Leniency


@dataclass(frozen=True)
class Stream:
    """A conditional generator: ``:stream`` (a *test* when it has no outputs)."""

    name: str
    inputs: tuple[str, ...]
    domain: tuple[Atom, ...]
    outputs: tuple[str, ...]
    certified: tuple[Atom, ...]
    fluents: tuple[str, ...] = ()
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def is_test(self) -> bool:
        return not self.outputs


@dataclass(frozen=True)
class StreamFunction:
    """``:function``: a non-negative numeric cost term computed by Python."""

    head: FunctionTerm
    domain: tuple[Atom, ...]
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def name(self) -> str:
        return self.head.name

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.head.args


@dataclass(frozen=True)
class StreamPredicate:
    """``:predicate``: an external boolean test, usable negated in the domain."""

    head: Atom
    domain: tuple[Atom, ...]
    location: SourceLocation | None = field(default=None, compare=False)

    @property
    def name(self) -> str:
        return self.head.predicate

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.head.args


@dataclass(frozen=True)
class Rule:
    """``:rule``: an always-true test used as an inference rule."""

    parameters: tuple[str, ...]
    domain: tuple[Atom, ...]
    certified: tuple[Atom, ...]
    location: SourceLocation | None = field(default=None, compare=False)


@dataclass(frozen=True)
class StreamFile:
    name: str
    streams: tuple[Stream, ...] = ()
    functions: tuple[StreamFunction, ...] = ()
    predicates: tuple[StreamPredicate, ...] = ()
    rules: tuple[Rule, ...] = ()
    source: str | None = field(default=None, compare=False)
    leniencies: tuple[Leniency, ...] = field(default=(), compare=False)
    """What was accepted although strict PDDL rejects it (see ``language.leniency``)."""

    def merged(self, other: StreamFile) -> StreamFile:
        return StreamFile(
            name=self.name,
            streams=self.streams + other.streams,
            functions=self.functions + other.functions,
            predicates=self.predicates + other.predicates,
            rules=self.rules + other.rules,
            source=self.source,
            leniencies=self.leniencies + other.leniencies,
        )
