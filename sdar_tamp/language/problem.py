"""``PDDLProblem``: a domain, its stream files and samplers, and an init/goal over Python values.

``PDDLProblem(domain_pddl, constant_map, stream_pddl, stream_map, init, goal)`` has PDDLStream's
meaning: the domain and stream files are given as text (or parsed models), ``constant_map`` maps
the domain's constants to Python values, ``stream_map`` maps stream and function names
(case-insensitive) to callables, or is ``"debug"``, and ``init``/``goal`` are tuples whose
arguments are arbitrary Python values. Building the object validates all of it. The keyword
``solve_defaults`` (not in PDDLStream) lets whoever builds a problem attach the ``solve()``
options it was built for, so that every entry point solves it the same way.

As in PDDLStream, ``init`` and ``goal`` may use predicates that neither the domain nor the stream
files declare: each is declared by its first use (logged at info level and kept in
``PDDLProblem.leniencies``); using it later with another arity is an error.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from sdar_tamp.errors import SourceLocation
from sdar_tamp.language.cross_check import cross_check, has_streams
from sdar_tamp.language.domain_model import Domain, TypeHierarchy
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.errors import (
    ArityError,
    ProblemDefinitionError,
    StreamMapError,
    UndeclaredError,
)
from sdar_tamp.language.formula_model import (
    EQUALITY,
    OBJECT_TYPE,
    TOTAL_COST,
    And,
    Atom,
    Exists,
    ForAll,
    Formula,
    Imply,
    Not,
    Or,
    Parameter,
)
from sdar_tamp.language.leniency import IMPLICIT_PREDICATE, LOGGER, Leniency, LeniencyLog
from sdar_tamp.language.objects import ObjectTable
from sdar_tamp.language.stream_model import StreamFile
from sdar_tamp.language.streams import parse_stream_file

DEBUG = "debug"


def _where(what: str) -> SourceLocation:
    return SourceLocation(what, 0, 0)


@dataclass(frozen=True)
class GroundFacts:
    """``init`` and ``goal`` in object names, ready for a solver."""

    objects: Mapping[str, str]  # name -> most specific type
    init: frozenset[Atom]
    numeric: Mapping[tuple[str, tuple[str, ...]], float]
    goal: Formula


@dataclass
class PDDLProblem:
    """A planning problem over Python values (see module docstring)."""

    domain_pddl: str | Domain
    constant_map: Mapping[str, Any]
    stream_pddl: str | Sequence[str] | StreamFile | None
    stream_map: Mapping[str, Callable[..., Any]] | str | None
    init: Iterable[Sequence[Any]]
    goal: Any
    #: Keyword arguments of ``solve()`` this problem was configured with (for example by an
    #: application that builds it); an argument given to ``solve()`` itself wins.
    solve_defaults: Mapping[str, Any] = field(default_factory=dict, kw_only=True)
    domain: Domain = field(init=False)
    streams: StreamFile = field(init=False)
    objects: ObjectTable = field(init=False)
    facts: GroundFacts = field(init=False)
    leniencies: tuple[Leniency, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        self.domain = (
            self.domain_pddl
            if isinstance(self.domain_pddl, Domain)
            else parse_domain(self.domain_pddl, "domain.pddl")
        )
        self.streams = _parse_streams(self.stream_pddl, self.domain)
        constants = {str(k).lower(): v for k, v in self.constant_map.items()}
        missing = sorted(set(self.domain.constants) - set(constants))
        extra = sorted(set(constants) - set(self.domain.constants))
        if missing or extra:
            raise ProblemDefinitionError(
                "constant_map must map exactly the domain's constants"
                + (f"; missing: {missing}" if missing else "")
                + (f"; not constants of the domain: {extra}" if extra else ""),
                _where("constant_map"),
            )
        self.objects = ObjectTable(constants)
        self.stream_map = _check_stream_map(self.stream_map, self.streams)
        self.facts, self.leniencies = _ground(self)
        if has_streams(self.streams):
            found = cross_check(self.domain, self.streams, self.facts.init, self.facts.goal)
            for item in found:
                LOGGER.log(item.level, "%s", item)
            self.leniencies += found

    def __iter__(self) -> Iterator[Any]:
        """Unpacks as PDDLStream's tuple: domain, constants, streams, stream map, init, goal."""
        return iter(
            (
                self.domain_pddl,
                self.constant_map,
                self.stream_pddl,
                self.stream_map,
                self.init,
                self.goal,
            )
        )

    @property
    def stream_functions(self) -> Mapping[str, Callable[..., Any]]:
        """The stream map with lower-case names (empty for ``"debug"``)."""
        return self.stream_map if isinstance(self.stream_map, Mapping) else {}


def _parse_streams(
    stream_pddl: str | Sequence[str] | StreamFile | None, domain: Domain
) -> StreamFile:
    if isinstance(stream_pddl, StreamFile):
        return stream_pddl
    if stream_pddl is None:
        return StreamFile("none")
    texts = [stream_pddl] if isinstance(stream_pddl, str) else list(stream_pddl)
    result = StreamFile("none")
    for index, text in enumerate(texts):
        name = "stream.pddl" if len(texts) == 1 else f"stream[{index}].pddl"
        result = result.merged(parse_stream_file(text, domain, name))
    return result


def _check_stream_map(
    stream_map: Mapping[str, Callable[..., Any]] | str | None, streams: StreamFile
) -> Mapping[str, Callable[..., Any]] | str:
    declared = (
        {s.name for s in streams.streams}
        | {f.name for f in streams.functions}
        | {p.name for p in streams.predicates}
    )
    if isinstance(stream_map, str):
        if stream_map.lower() != DEBUG:
            raise StreamMapError(f"stream_map must be a mapping or 'debug', got {stream_map!r}")
        return DEBUG
    lowered: dict[str, Callable[..., Any]] = {}
    for name, fn in (stream_map or {}).items():
        if not callable(fn):
            raise StreamMapError(f"stream_map[{name!r}] must be callable, got {type(fn).__name__}")
        lowered[str(name).lower()] = fn
    missing = sorted(declared - set(lowered))
    extra = sorted(set(lowered) - declared)
    if missing:
        raise StreamMapError(f"stream_map has no callable for: {', '.join(missing)}")
    if extra:
        raise StreamMapError(
            f"stream_map names streams the stream files do not declare: {', '.join(extra)}"
            f" (declared: {', '.join(sorted(declared)) or 'none'})"
        )
    return lowered


class _Grounder:
    """Turns tuple facts and formulas over Python values into named atoms."""

    def __init__(self, problem: PDDLProblem) -> None:
        self.problem = problem
        domain = problem.domain
        self.arities = {p.name: p.arity for p in domain.predicates.values()}
        for atom in _stream_atoms(problem.streams):
            self.arities.setdefault(atom.predicate, len(atom.args))
        self.types = set(domain.types.types())
        self.functions = {f.name: len(f.parameters) for f in domain.functions.values()}
        self.log = LeniencyLog(strict=False)

    def term(self, value: Any, scope: frozenset[str], where: str) -> str:
        if isinstance(value, str) and value.startswith("?"):
            if value.lower() not in scope:
                raise ProblemDefinitionError(f"variable {value} is not bound", _where(where))
            return value.lower()
        return self.problem.objects.name(value)

    def atom(self, fact: Sequence[Any], scope: frozenset[str], where: str) -> Atom:
        if not fact or not isinstance(fact[0], str):
            raise ProblemDefinitionError(
                f"expected a fact ('predicate', arg, ...), got {fact!r}", _where(where)
            )
        name = fact[0].lower()
        args = tuple(self.term(arg, scope, where) for arg in fact[1:])
        if name == EQUALITY:
            expected = 2
        elif name in self.arities:
            expected = self.arities[name]
        elif name in self.types:
            expected = 1
        else:
            expected = self.arities[name] = len(args)
            self.log.add(
                IMPLICIT_PREDICATE,
                f"predicate {name!r} is declared neither in the domain nor in the stream files; "
                f"declared by this first use with {expected} argument(s)",
                _where(where),
            )
        if len(args) != expected:
            raise ArityError(
                f"predicate {name!r} takes {expected} argument(s), got {len(args)} in {fact!r}",
                _where(where),
            )
        return Atom(name, args)

    def formula(self, value: Any, scope: frozenset[str], where: str) -> Formula:
        if not isinstance(value, tuple | list) or not value:
            raise ProblemDefinitionError(f"expected a formula tuple, got {value!r}", _where(where))
        if isinstance(value[0], tuple | list):  # a list of facts is their conjunction
            return And(tuple(self.formula(p, scope, where) for p in value))
        head = value[0].lower() if isinstance(value[0], str) else value[0]
        rest = value[1:]
        if head == "and":
            return And(tuple(self.formula(p, scope, where) for p in rest))
        if head == "or":
            return Or(tuple(self.formula(p, scope, where) for p in rest))
        if head == "not":
            return Not(self.formula(rest[0], scope, where))
        if head == "imply":
            return Imply(self.formula(rest[0], scope, where), self.formula(rest[1], scope, where))
        if head in ("exists", "forall"):
            params = tuple(Parameter(str(p).lower(), OBJECT_TYPE) for p in rest[0])
            inner = scope | {p.name for p in params}
            body = self.formula(rest[1], inner, where)
            return Exists(params, body) if head == "exists" else ForAll(params, body)
        return self.atom(value, scope, where)


def _stream_atoms(streams: StreamFile) -> Iterable[Atom]:
    for stream in streams.streams:
        yield from stream.domain
        yield from stream.certified
    for rule in streams.rules:
        yield from rule.certified
    for predicate in streams.predicates:
        yield predicate.head


def _ground(problem: PDDLProblem) -> tuple[GroundFacts, tuple[Leniency, ...]]:
    grounder = _Grounder(problem)
    init: set[Atom] = set()
    numeric: dict[tuple[str, tuple[str, ...]], float] = {}
    for index, fact in enumerate(problem.init):
        where = f"init[{index}]"
        if (
            len(fact) == 3
            and isinstance(fact[0], str)
            and fact[0] == EQUALITY
            and isinstance(fact[1], tuple | list)
        ):
            head = fact[1]
            name = str(head[0]).lower()
            if name not in grounder.functions:
                raise UndeclaredError(f"undeclared function {name!r} in {fact!r}", _where(where))
            args = tuple(grounder.term(arg, frozenset(), where) for arg in head[1:])
            try:
                value = float(fact[2])
            except (TypeError, ValueError):
                value = math.nan
            if not math.isfinite(value):
                raise ProblemDefinitionError(
                    f"expected a finite number as the value of {head!r}, got {fact[2]!r}",
                    _where(where),
                )
            if name == TOTAL_COST and value < 0:
                raise ProblemDefinitionError(
                    f"expected a non-negative initial total-cost, got {fact[2]!r}", _where(where)
                )
            numeric[(name, args)] = value
            continue
        init.add(grounder.atom(fact, frozenset(), where))
    goal = grounder.formula(problem.goal, frozenset(), "goal")
    objects = _object_types(problem, init)
    init |= type_facts(objects, problem.domain.types)
    return GroundFacts(objects, frozenset(init), numeric, goal), grounder.log.finish()


def _object_types(problem: PDDLProblem, init: set[Atom]) -> dict[str, str]:
    """Each object's most specific type, from the domain's constants and init type facts."""
    declared = {
        name: problem.domain.constants.get(name, OBJECT_TYPE) for name in problem.objects.names()
    }
    try:
        return infer_object_types(declared, init, problem.domain.types)
    except ValueError as error:
        raise ProblemDefinitionError(str(error), _where("init")) from None


def infer_object_types(
    declared: Mapping[str, str], facts: Iterable[Atom], hierarchy: TypeHierarchy
) -> dict[str, str]:
    """Refine ``declared`` (name -> type) by unary type facts to the most specific type.

    Raises:
        ValueError: an object is given two unrelated types.
    """
    objects = dict(declared)
    for atom in facts:
        if atom.predicate in hierarchy.parents and len(atom.args) == 1:
            current = objects.get(atom.args[0], OBJECT_TYPE)
            new = atom.predicate
            if hierarchy.is_subtype(new, current):
                objects[atom.args[0]] = new
            elif not hierarchy.is_subtype(current, new):
                raise ValueError(
                    f"object {atom.args[0]!r} is given both type {current!r} and the unrelated "
                    f"type {new!r}"
                )
    return objects


def type_facts(objects: Mapping[str, str], hierarchy: TypeHierarchy) -> frozenset[Atom]:
    """Unary type atoms for every object and every ancestor type except ``object``."""
    return frozenset(
        Atom(type_name, (name,))
        for name, own in objects.items()
        for type_name in hierarchy.ancestors(own)
        if type_name != OBJECT_TYPE
    )
