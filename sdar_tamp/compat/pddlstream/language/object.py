"""``pddlstream.language.object``: the stand-in values of debug stream maps and of optimistic
(not yet sampled) outputs, as a program's samplers and ``opt_fn`` functions may see them."""

from __future__ import annotations

import itertools
from typing import Any, NamedTuple

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__ = [
    "DebugValue",
    "SharedDebugValue",
    "SharedOptValue",
    "UniqueOptValue",
]


class UniqueOptValue(NamedTuple):
    """An optimistic output of one stream instance (``opt_fn`` receives these)."""

    instance: Any
    sequence_index: int
    output: str

    @property
    def parameter(self) -> str:
        return self.output


class SharedOptValue(NamedTuple):
    """An optimistic output shared by the instances of one stream."""

    stream: str
    inputs: tuple[Any, ...]
    input_objects: tuple[Any, ...]
    output: str

    @property
    def values(self) -> tuple[Any, ...]:
        return tuple(self.input_objects)


class DebugValue:
    """An output of ``stream_map=DEBUG``: one per stream instance and output parameter."""

    _counter = itertools.count()

    def __init__(self, stream: str, input_values: tuple[Any, ...], output_parameter: str) -> None:
        self.stream = stream
        self.input_values = tuple(input_values)
        self.output_parameter = output_parameter
        self.index = next(self._counter)

    def __repr__(self) -> str:
        return f"@{self.output_parameter.lstrip('?')}{self.index}"


class SharedDebugValue(NamedTuple):
    """An output of ``stream_map=SHARED_DEBUG``: one per stream and output parameter."""

    stream: str
    output_parameter: str

    def __repr__(self) -> str:
        return f"&{self.output_parameter.lstrip('?')}"


__getattr__ = not_provided(
    __name__,
    "PDDLStream's Object/OptimisticObject registries (objects here are the values themselves)",
)
