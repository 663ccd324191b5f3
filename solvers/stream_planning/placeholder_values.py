"""Placeholders and the optimistic values behind them, for one solve's optimistic worlds
(:class:`PlaceholderValues`, kept by :class:`~.optimistic.OptimisticBuilder`).

A placeholder's name is made once per key (an instance and output position, or a stream and
output position when shared) and kept across builds. A callable ``StreamInfo(opt_gen_fn=...)``
gives each of an instance's optimistic output tuples a set of placeholders standing for the
values it produced; ``FunctionInfo.opt_fn`` gives the optimistic value of a function on
placeholders or of a deferred one (default 1), called with the values of real inputs, the value
behind a placeholder that has one, an :class:`~.opt_values.OptimisticValue` for the others.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from solvers.stream_planning.engine import Engine
from solvers.stream_planning.externals import FunctionExternal, StreamExternal
from solvers.stream_planning.opt_results import PLACEHOLDER, is_placeholder
from solvers.stream_planning.opt_values import OptimisticValue, first_batch


class PlaceholderValues:
    """The placeholders of one engine's optimistic worlds and the values behind them."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self._names: dict[tuple[object, ...], str] = {}
        self.producers: dict[str, str] = {}  # placeholder -> the stream that makes it
        # placeholder -> the value a callable opt_gen_fn gave it
        self.values: dict[str, object] = {}
        # (stream, inputs) -> the output tuples of its callable opt_gen_fn
        self._generated: dict[tuple[str, tuple[str, ...]], list[tuple[object, ...]]] = {}
        # the optimistic values of deferred function terms (asked for by the search)
        self._optimistic: dict[tuple[str, tuple[str, ...]], float] = {}

    def placeholder(self, key: tuple[object, ...]) -> str:
        """The placeholder of ``key`` (its first element: the stream that makes it)."""
        name = self._names.get(key)
        if name is None:
            name = f"{PLACEHOLDER}{len(self._names)}"
            self._names[key] = name
            self.producers[name] = str(key[0])
        return name

    def of(self, inputs: tuple[str, ...]) -> tuple[object, ...]:
        """What user code sees for ``inputs``: real values, or what stands for placeholders."""
        return tuple(
            (self.values[n] if n in self.values else OptimisticValue(n, self.producers.get(n, "?")))
            if is_placeholder(n)
            else self.engine.table.value(n)
            for n in inputs
        )  # fmt: skip

    def generated(
        self, external: StreamExternal, inputs: tuple[str, ...], generator: Callable[..., Any]
    ) -> list[tuple[str, ...]]:
        """The placeholders of each output tuple of ``generator`` on ``inputs`` (called once).

        Raises:
            StreamError: ``generator`` raised.
            StreamOutputError: it produced something other than a list of output tuples.
        """
        name = external.name
        key = (name, inputs)
        batch = self._generated.get(key)
        if batch is None:
            batch = self._generated[key] = first_batch(external, self.of(inputs), generator)
        result = []
        for index, values in enumerate(batch):
            outputs = tuple(
                self.placeholder((name, inputs, "opt", index, i)) for i in range(len(values))
            )
            for placeholder, value in zip(outputs, values, strict=True):
                self.values[placeholder] = value
            result.append(outputs)
        return result

    def function_value(self, function: FunctionExternal, inputs: tuple[str, ...]) -> float:
        """The optimistic value of ``function`` on ``inputs`` (its ``opt_fn``, default 1)."""
        opt_fn = getattr(function.info, "opt_fn", None)
        return float(opt_fn(*self.of(inputs))) if opt_fn is not None else 1.0

    def deferred(self, name: str, inputs: tuple[str, ...]) -> float:
        """The optimistic value of deferred function ``name`` on ``inputs`` (kept)."""
        key = (name, inputs)
        found = self._optimistic.get(key)
        if found is None:
            found = self._optimistic[key] = self.function_value(self.engine.functions[name], inputs)
        return found
