"""Streams bound to their Python callables, and their instances (one per input tuple).

A sampler is called with the Python values behind the object names; what it returns is checked
for shape, and its outputs get object names from the problem's :class:`ObjectTable`. A sampler
that raises stops the solve with a :class:`StreamError` naming the stream and its inputs; a test
or ``:predicate`` must answer with a bool (:func:`truth_value`). Calls go through the solve's
:class:`CallRunner` when one is given (deadline, optional worker thread).
"""

from __future__ import annotations

import copy
import itertools
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

from sdar_tamp.errors import SdarError
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.generators import (
    SINGLE_CALL,
    ListGenFn,
    TruthValueError,
    WildOutput,
    truth_value,
)
from sdar_tamp.language.objects import ObjectTable, keyed_by_identity
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.stream_model import Stream, StreamFunction, StreamPredicate
from sdar_tamp.language.substitution import ground_atom
from sdar_tamp.logs import get_logger
from solvers.stream_planning.calls import CallRunner, CallTimeout

LOG = get_logger(__name__)


class StreamError(SdarError):
    """A user sampler raised: names the stream and its inputs; the cause is chained."""


class StreamOutputError(StreamError):
    """A user sampler returned something of the wrong shape."""


@dataclass
class Counters:
    """Mutable per-external counters, frozen into ``StreamStatistics`` at the end."""

    calls: int = 0
    successes: int = 0
    outputs: int = 0
    time: float = 0.0


def _bind(atoms: tuple[Atom, ...], mapping: Mapping[str, str]) -> tuple[Atom, ...]:
    return tuple(ground_atom(a, mapping) for a in atoms)


@dataclass(frozen=True)
class DebugValue:
    """A stand-in output of ``stream_map='debug'``."""

    stream: str
    inputs: tuple[Any, ...]
    index: int
    call: int

    def __repr__(self) -> str:
        return f"${self.stream}{self.index}#{self.call}"


def _debug_gen_fn(stream: Stream) -> ListGenFn:
    def gen(*inputs: Any, **_kwargs: Any) -> Iterator[list[tuple[Any, ...]]]:
        for call in itertools.count():
            if stream.is_test:
                yield [()]
            else:
                yield [
                    tuple(
                        DebugValue(stream.name, inputs, i, call) for i in range(len(stream.outputs))
                    )
                ]

    return gen


@dataclass
class StreamExternal:
    """A ``:stream`` with its callable and options."""

    declaration: Stream
    gen_fn: ListGenFn
    info: StreamInfo
    counters: Counters = field(default_factory=Counters)

    @property
    def name(self) -> str:
        return self.declaration.name

    def certified(self, inputs: tuple[str, ...], outputs: tuple[str, ...]) -> tuple[Atom, ...]:
        decl = self.declaration
        mapping = dict(zip(decl.inputs, inputs, strict=True))
        mapping.update(zip(decl.outputs, outputs, strict=True))
        return _bind(decl.certified, mapping)

    def domain(self, inputs: tuple[str, ...]) -> tuple[Atom, ...]:
        return _bind(
            self.declaration.domain, dict(zip(self.declaration.inputs, inputs, strict=True))
        )


@dataclass
class StreamResult:
    """One output tuple of an instance with the facts it certifies."""

    instance: StreamInstance
    outputs: tuple[str, ...]
    certified: tuple[Atom, ...]
    call_index: int  # the instance's calls before this one


@dataclass
class StreamInstance:
    """A stream applied to real input objects (and, for fluent streams, a fluent state)."""

    external: StreamExternal
    inputs: tuple[str, ...]
    fluents: tuple[Atom, ...] = ()
    calls: int = 0
    exhausted: bool = False
    disabled: bool = False
    results: list[StreamResult] = field(default_factory=list)
    _iterator: Iterator[Any] | None = None

    def key(self) -> tuple[str, tuple[str, ...], tuple[Atom, ...]]:
        return (self.external.name, self.inputs, self.fluents)

    def describe(self, table: ObjectTable) -> str:
        values = ", ".join(repr(table.value(n)) for n in self.inputs)
        return f"stream {self.external.name!r} on inputs ({values})"

    def next(
        self, table: ObjectTable, runner: CallRunner | None = None
    ) -> tuple[list[StreamResult], list[Atom]]:
        """Call the sampler once; returns the new results and any wild facts.

        Raises:
            CallTimeout: (with ``runner``) the deadline passed before or during the call.
        """
        if self.exhausted:
            return [], []
        external = self.external
        values = tuple(table.value(n) for n in self.inputs)
        fluent_values = (
            [(a.predicate, *(table.value(n) for n in a.args)) for a in self.fluents]
            if self._iterator is None
            else []
        )

        def call() -> Any:
            if self._iterator is None:
                if external.declaration.fluents:
                    self._iterator = iter(external.gen_fn(*values, fluents=fluent_values))
                else:
                    self._iterator = iter(external.gen_fn(*values))
            return next(self._iterator)

        if runner is not None:
            runner.check()
        start = time.perf_counter()
        try:
            produced = call() if runner is None else runner.call(call, lambda: self.describe(table))
        except StopIteration:
            self.exhausted = True
            produced = []
        except TruthValueError as error:
            raise StreamOutputError(f"{self.describe(table)} is a test: {error}") from error
        except (SdarError, CallTimeout):
            raise
        except Exception as error:
            raise StreamError(
                f"{self.describe(table)} raised {type(error).__name__}: {error}"
            ) from error
        finally:
            external.counters.time += time.perf_counter() - start
            external.counters.calls += 1
        call_index = self.calls
        self.calls += 1
        if getattr(external.gen_fn, SINGLE_CALL, False):
            self.exhausted = True  # its one answer is in: no second call to find that out
        outputs, wild = self._check(produced, table)
        results = [
            StreamResult(self, names, external.certified(self.inputs, names), call_index)
            for names in outputs
        ]
        self.results.extend(results)
        if results or (wild and external.declaration.is_test):
            external.counters.successes += 1
        external.counters.outputs += len(results)
        return results, wild

    def _check(self, produced: Any, table: ObjectTable) -> tuple[list[tuple[str, ...]], list[Atom]]:
        decl = self.external.declaration
        wild: list[Atom] = []
        if isinstance(produced, WildOutput):
            wild = [
                Atom(str(f[0]).lower(), tuple(table.name(v) for v in f[1:])) for f in produced.facts
            ]
            produced = list(produced.values)
        if produced is None:
            produced = []
        if not isinstance(produced, list | tuple):
            raise StreamOutputError(
                f"{self.describe(table)} must produce a list of output tuples, got "
                f"{type(produced).__name__}: {produced!r}"
            )
        names: list[tuple[str, ...]] = []
        for output in produced:
            if not isinstance(output, tuple | list) or len(output) != len(decl.outputs):
                raise StreamOutputError(
                    f"{self.describe(table)} must produce tuples of {len(decl.outputs)} value(s) "
                    f"({' '.join(decl.outputs) or 'none: it is a test'}), got {output!r}"
                )
            names.append(tuple(self._name(value, table) for value in output))
        return names, wild

    def _name(self, value: Any, table: ObjectTable) -> str:
        """The object name of an output value. A generator that yields again an unhashable
        object it yielded before (a dict or array it changes between yields) gives a new value
        each time: the value as yielded now is copied and named anew, so every call can add
        a new object, as it would had the generator built a fresh one."""
        name = table.name(value)
        if not keyed_by_identity(value) or not any(name in r.outputs for r in self.results):
            return name
        try:
            snapshot = copy.deepcopy(value)
        except Exception:  # deepcopy is not available for every object
            LOG.debug("%s yielded an object again that cannot be copied", self.external.name)
            return name
        return table.name(snapshot)


@dataclass
class FunctionExternal:
    """A ``:function`` (numeric, non-negative) or ``:predicate`` (boolean) with its callable."""

    declaration: StreamFunction | StreamPredicate
    fn: Callable[..., Any]
    info: FunctionInfo | StreamInfo
    counters: Counters = field(default_factory=Counters)
    values: dict[tuple[str, ...], float | bool] = field(default_factory=dict)
    stream: str | None = None  # the test stream with ``negate=True`` this predicate stands for

    @property
    def name(self) -> str:
        return self.declaration.name

    @property
    def is_predicate(self) -> bool:
        return isinstance(self.declaration, StreamPredicate)

    def domain(self, inputs: tuple[str, ...]) -> tuple[Atom, ...]:
        return _bind(
            self.declaration.domain, dict(zip(self.declaration.inputs, inputs, strict=True))
        )

    def evaluate(
        self, inputs: tuple[str, ...], table: ObjectTable, runner: CallRunner | None = None
    ) -> float | bool:
        """The value on ``inputs`` (cached). Raises :class:`CallTimeout` as
        :meth:`StreamInstance.next` does."""
        if inputs in self.values:
            return self.values[inputs]
        values = tuple(table.value(n) for n in inputs)

        def describe() -> str:
            kind = "predicate" if self.is_predicate else "function"
            if self.stream is not None:
                kind = f"negated test stream {self.stream!r} for predicate"
            return f"{kind} {self.name!r} on inputs ({', '.join(repr(v) for v in values)})"

        if runner is not None:
            runner.check()
        start = time.perf_counter()
        try:
            raw = (
                self.fn(*values)
                if runner is None
                else runner.call(lambda: self.fn(*values), describe)
            )
        except CallTimeout:
            raise
        except TruthValueError as error:  # a negated test stream's test answered wrongly
            raise StreamOutputError(f"{describe()}: {error}") from error
        except Exception as error:
            raise StreamError(f"{describe()} raised {type(error).__name__}: {error}") from error
        finally:
            self.counters.time += time.perf_counter() - start
            self.counters.calls += 1
        result: float | bool
        if self.is_predicate:
            try:
                result = truth_value(raw)
            except TruthValueError as error:
                raise StreamOutputError(f"{describe()}: {error}") from error
        else:
            if isinstance(raw, bool) or not isinstance(raw, int | float):
                raise StreamOutputError(f"{describe()} must return a number, got {raw!r}")
            if raw < 0:
                raise StreamOutputError(f"{describe()} must return a non-negative cost, got {raw}")
            result = float(raw)
        self.counters.successes += 1
        self.counters.outputs += 1
        self.values[inputs] = result
        return result


def debug_gen_fn(stream: Stream) -> ListGenFn:
    """The sampler ``stream_map='debug'`` uses for ``stream``."""
    return _debug_gen_fn(stream)
