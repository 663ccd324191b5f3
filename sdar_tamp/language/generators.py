"""Adapters from plain Python samplers to the one form every stream is called in.

A stream is called as ``list_gen_fn(*inputs)`` (plus ``fluents=`` for a fluent stream, which
the adapters pass on to the sampler) and returns an iterator; each ``next`` gives a
list of output tuples (possibly empty: no output this call) or a :class:`WildOutput`. The
adapters below wrap the usual shapes of samplers into that form (PDDLStream's names):

- ``from_gen_fn(g)``: ``g(*inputs)`` yields one output tuple (or None) per call;
- ``from_list_gen_fn(g)``: ``g(*inputs)`` yields lists of output tuples;
- ``from_sampler(s)``: ``s(*inputs)`` returns one output tuple (or None), called forever;
- ``from_fn(f)``: ``f(*inputs)`` returns one tuple or None, called once;
- ``from_list_fn(f)``: ``f(*inputs)`` returns a list of tuples, called once;
- ``from_test(t)``: ``t(*inputs)`` returns a bool, called once (no outputs); see
  :func:`truth_value` for what counts as one;
- ``from_constant(c)``: always the tuple ``c``, once; ``fn_from_constant(c)``: a function
  (for ``:function``/``:predicate``) that always returns ``c``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from sdar_tamp.errors import SdarError

Outputs = list[tuple[Any, ...]]
ListGenFn = Callable[..., Iterator["Outputs | WildOutput"]]


@dataclass(frozen=True)
class WildOutput:
    """Outputs plus extra certified facts the stream did not declare (PDDLStream's wild streams)."""

    values: Sequence[tuple[Any, ...]] = ()
    facts: Sequence[tuple[Any, ...]] = field(default_factory=tuple)


def _as_tuple(output: Any) -> Any:
    """A list becomes a tuple; anything else is passed on as it is, so that the solver's shape
    check can name what the sampler really returned."""
    return tuple(output) if isinstance(output, list | tuple) else output


def _one(output: Any) -> Outputs:
    return [] if output is None else [_as_tuple(output)]


def from_list_gen_fn(list_gen_fn: Callable[..., Iterable[Any]]) -> ListGenFn:
    def stream(*inputs: Any, **kwargs: Any) -> Iterator[Outputs | WildOutput]:
        for outputs in list_gen_fn(*inputs, **kwargs):
            if isinstance(outputs, WildOutput):
                yield outputs
            else:
                yield [_as_tuple(output) for output in (outputs or [])]

    return stream


def from_gen_fn(gen_fn: Callable[..., Iterable[Any]]) -> ListGenFn:
    def stream(*inputs: Any, **kwargs: Any) -> Iterator[Outputs | WildOutput]:
        for output in gen_fn(*inputs, **kwargs):
            yield output if isinstance(output, WildOutput) else _one(output)

    return stream


def from_sampler(sampler: Callable[..., Any], max_attempts: int | None = None) -> ListGenFn:
    def stream(*inputs: Any, **kwargs: Any) -> Iterator[Outputs | WildOutput]:
        attempt = 0
        while max_attempts is None or attempt < max_attempts:
            attempt += 1
            yield _one(sampler(*inputs, **kwargs))

    return stream


#: Attribute of an adapter whose iterator gives exactly one answer (``from_fn``, ``from_test``,
#: ...): the solver knows the instance is exhausted after one call, as PDDLStream does.
SINGLE_CALL = "single_call"


def _once(stream: ListGenFn) -> ListGenFn:
    setattr(stream, SINGLE_CALL, True)
    return stream


def from_list_fn(list_fn: Callable[..., Any]) -> ListGenFn:
    def stream(*inputs: Any, **kwargs: Any) -> Iterator[Outputs | WildOutput]:
        outputs = list_fn(*inputs, **kwargs)
        yield (
            outputs if isinstance(outputs, WildOutput) else [_as_tuple(o) for o in (outputs or [])]
        )

    return _once(stream)


def from_fn(fn: Callable[..., Any]) -> ListGenFn:
    def stream(*inputs: Any, **kwargs: Any) -> Iterator[Outputs | WildOutput]:
        output = fn(*inputs, **kwargs)
        yield output if isinstance(output, WildOutput) else _one(output)

    return _once(stream)


class TruthValueError(SdarError, TypeError):
    """A test returned something other than a truth value (the solver names the stream)."""

    def __init__(self, value: Any) -> None:
        super().__init__(
            "a test must return a bool (True/False or numpy.bool_; None counts as False), got "
            f"{type(value).__name__}: {value!r}"
        )
        self.value = value


def truth_value(value: Any) -> bool:
    """A test's answer: ``bool`` or ``numpy.bool_``; ``None`` counts as False (a PDDLStream
    test that falls off its end). Anything else (``"no"``, ``1``, a list) raises
    :class:`TruthValueError` rather than being judged by its truthiness."""
    if value is None:
        return False
    kind = type(value)
    if kind is bool or (kind.__module__ == "numpy" and kind.__name__ in ("bool", "bool_")):
        return bool(value)
    raise TruthValueError(value)


def from_test(test: Callable[..., Any]) -> ListGenFn:
    def stream(*inputs: Any, **kwargs: Any) -> Iterator[Outputs | WildOutput]:
        yield [()] if truth_value(test(*inputs, **kwargs)) else []

    return _once(stream)


def from_constant(constant: Sequence[Any]) -> ListGenFn:
    return from_fn(lambda *_inputs: tuple(constant))


def fn_from_constant(constant: Any) -> Callable[..., Any]:
    return lambda *_inputs: constant


def negate_test(test: Callable[..., Any]) -> Callable[..., bool]:
    return lambda *inputs: not truth_value(test(*inputs))
