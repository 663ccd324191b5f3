"""``PDDLProblem`` with PDDLStream's leniency about the stream map.

On top of :class:`sdar_tamp.language.problem.PDDLProblem` (which it is, so every solver takes
it), this class accepts what PDDLStream accepts:

- ``stream_map`` entries that no stream file declares are dropped with a logged note (a
  program often keeps samplers of an optional stream file in one map);
- ``stream_map=DEBUG`` (``"debug"``): every stream gives one stand-in output tuple per instance
  (:class:`DebugValue`), ``stream_map=SHARED_DEBUG`` (``"shared_debug"``): one stand-in per
  stream and output shared by all instances (:class:`SharedDebugValue`); debug functions cost
  0 and debug predicates are false, as in PDDLStream;
- a declared ``:function`` without a callable is accepted (PDDLStream does not look functions
  up with unit costs); calling it raises a :class:`StreamMapError` naming it;
- ``stream_map=None`` is an empty map.

A program's streams whose domain mentions a fluent fact are compiled as exogenous streams
(:mod:`sdar_tamp.compat.pddlstream.language.exogenous`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from sdar_tamp.compat.pddlstream.language.object import DebugValue, SharedDebugValue
from sdar_tamp.language.domain_model import Domain
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.errors import StreamMapError
from sdar_tamp.language.formula_model import TOTAL_COST
from sdar_tamp.language.problem import PDDLProblem as _CorePDDLProblem
from sdar_tamp.language.stream_model import StreamFile
from sdar_tamp.language.streams import parse_stream_file

LOG = logging.getLogger(__name__)
DEBUG = "debug"
SHARED_DEBUG = "shared_debug"
DEBUG_MODES = (DEBUG, SHARED_DEBUG)


def parse_stream_files(stream_pddl: Any, domain: Domain) -> StreamFile:
    """One :class:`StreamFile` from ``None``, one text, several texts or a parsed file."""
    if isinstance(stream_pddl, StreamFile):
        return stream_pddl
    if stream_pddl is None:
        return StreamFile("none")
    texts = [stream_pddl] if isinstance(stream_pddl, str) else list(stream_pddl)
    merged = StreamFile("none")
    for index, text in enumerate(texts):
        if isinstance(text, StreamFile):
            merged = merged.merged(text)
            continue
        name = "stream.pddl" if len(texts) == 1 else f"stream[{index}].pddl"
        merged = merged.merged(parse_stream_file(text, domain, name))
    return merged


def _debug_stream(name: str, outputs: Sequence[str], shared: bool) -> Callable[..., Any]:
    def gen_fn(*inputs: Any, **_fluents: Any) -> Iterator[list[tuple[Any, ...]]]:
        if shared:
            yield [tuple(SharedDebugValue(name, o) for o in outputs)]
        else:
            yield [tuple(DebugValue(name, inputs, o) for o in outputs)]

    return gen_fn


def _debug_map(streams: StreamFile, shared: bool) -> dict[str, Callable[..., Any]]:
    result: dict[str, Callable[..., Any]] = {
        s.name: _debug_stream(s.name, s.outputs, shared) for s in streams.streams
    }
    result.update({f.name: (lambda *_a: 0.0) for f in streams.functions})
    result.update({p.name: (lambda *_a: False) for p in streams.predicates})
    return result


def _missing_function(name: str) -> Callable[..., Any]:
    def fn(*_inputs: Any) -> Any:
        raise StreamMapError(f"stream_map has no callable for the function {name!r}")

    return fn


def adapt_stream_map(stream_map: Any, streams: StreamFile) -> dict[str, Callable[..., Any]]:
    """The map a core :class:`PDDLProblem` accepts, built from a PDDLStream ``stream_map``."""
    if isinstance(stream_map, str):
        if stream_map.lower() not in DEBUG_MODES:
            raise StreamMapError(
                f"stream_map must be a mapping, {DEBUG!r} or {SHARED_DEBUG!r}; got {stream_map!r}"
            )
        return _debug_map(streams, shared=stream_map.lower() == SHARED_DEBUG)
    if stream_map is not None and not isinstance(stream_map, Mapping):
        raise StreamMapError(
            f"stream_map must be a mapping from stream names to callables, got "
            f"{type(stream_map).__name__}"
        )
    declared = {s.name for s in streams.streams} | {p.name for p in streams.predicates}
    functions = {f.name for f in streams.functions}
    result: dict[str, Callable[..., Any]] = {}
    for name, fn in (stream_map or {}).items():
        key = str(name).lower()
        if key in declared or key in functions:
            result[key] = fn
        else:
            LOG.info("stream_map entry %r is not declared by any stream file; ignored", name)
    for name in sorted(functions - set(result)):
        LOG.info("stream_map has no callable for the function %r", name)
        result[name] = _missing_function(name)
    return result


def _numeric_function(fact: Any) -> str | None:
    """The function name of a numeric ``init`` fact ``('=', (function, ...), value)``."""
    if len(fact) == 3 and fact[0] == "=" and isinstance(fact[1], tuple | list) and fact[1]:
        return str(fact[1][0]).lower()
    return None


def _init_facts(init: Any, domain: Domain, streams: StreamFile) -> list[Any]:
    """``init`` without the numeric facts the solvers do not take: the ``total-cost`` counter
    (they keep their own) and values of functions no file declares (PDDLStream ignores them;
    a log line names them)."""
    declared = set(domain.functions) | {f.name for f in streams.functions}
    kept = []
    for fact in init:
        function = _numeric_function(fact)
        if function == TOTAL_COST:
            continue
        if function is not None and function not in declared:
            LOG.info("init fact %r: function %r is not declared; ignored", fact, function)
            continue
        kept.append(fact)
    return kept


@dataclass
class PDDLProblem(_CorePDDLProblem):
    """``PDDLProblem(domain_pddl, constant_map, stream_pddl, stream_map, init, goal)``."""

    def __post_init__(self) -> None:
        from sdar_tamp.compat.pddlstream.language.exogenous import (
            compile_exogenous,
            rename_predicates,
        )

        if self.constant_map is None:
            self.constant_map = {}
        given = (self.domain_pddl, self.stream_pddl)
        domain = (
            self.domain_pddl
            if isinstance(self.domain_pddl, Domain)
            else parse_domain(self.domain_pddl, "domain.pddl")
        )
        streams = parse_stream_files(self.stream_pddl, domain)
        self.init = _init_facts(self.init, domain, streams)
        stream_map = adapt_stream_map(self.stream_map, streams)
        domain, streams, renaming = compile_exogenous(domain, streams)
        self.domain_pddl, self.stream_pddl, self.stream_map = domain, streams, stream_map
        try:
            super().__post_init__()
        finally:
            self.domain_pddl, self.stream_pddl = given[0], given[1]
        if renaming:
            self.facts = replace(self.facts, goal=rename_predicates(self.facts.goal, renaming))
