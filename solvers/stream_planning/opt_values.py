"""What user code sees of the optimistic world: :class:`OptimisticValue` stands for an output
not sampled yet (passed to ``FunctionInfo.opt_fn`` and callable ``opt_gen_fn``), and
:func:`first_batch` calls a callable ``StreamInfo(opt_gen_fn=...)`` for the optimistic output
values of one stream instance."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from sdar_tamp.language.generators import WildOutput
from solvers.stream_planning.externals import StreamError, StreamExternal, StreamOutputError


@dataclass(frozen=True)
class OptimisticValue:
    """What ``FunctionInfo.opt_fn`` receives for an input not sampled yet: the placeholder's
    name and the stream that will produce it."""

    name: str
    stream: str

    def __repr__(self) -> str:
        return f"{self.name}({self.stream})"


def first_batch(
    external: StreamExternal, values: Sequence[object], generator: Callable[..., Any]
) -> list[tuple[object, ...]]:
    """The output tuples of the first batch ``generator`` yields on the input ``values`` of an
    instance of ``external`` (none when it yields nothing or None).

    Raises:
        StreamError: ``generator`` raised.
        StreamOutputError: it produced something other than a list of output tuples.
    """
    what = f"the opt_gen_fn of stream {external.name!r} on inputs {values!r}"
    try:
        produced: Any = next(iter(generator(*values)), [])
    except Exception as error:
        raise StreamError(f"{what} raised {type(error).__name__}: {error}") from error
    if isinstance(produced, WildOutput):
        produced = list(produced.values)
    if produced is None:
        return []
    arity = len(external.declaration.outputs)
    if not isinstance(produced, list | tuple) or not all(
        isinstance(output, list | tuple) and len(output) == arity for output in produced
    ):
        raise StreamOutputError(
            f"{what} must produce a list of tuples of {arity} value(s), got {produced!r}"
        )
    return [tuple(output) for output in produced]
