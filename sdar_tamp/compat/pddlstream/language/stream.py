"""``pddlstream.language.stream``: ``StreamInfo`` with PDDLStream's keywords, ``PartialInputs``,
``WildOutput`` and the debug modes."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from sdar_tamp.compat.pddlstream.language.external import never_defer
from sdar_tamp.compat.pddlstream.language.function import with_opt_values
from sdar_tamp.compat.pddlstream.language.generator import universe_test
from sdar_tamp.compat.pddlstream.language.problem import DEBUG, DEBUG_MODES, SHARED_DEBUG
from sdar_tamp.language.generators import WildOutput as _CoreWildOutput
from sdar_tamp.language.options import StreamInfo as _CoreStreamInfo

__all__ = [
    "DEBUG",
    "DEBUG_MODES",
    "SHARED_DEBUG",
    "PartialInputs",
    "StreamInfo",
    "WildOutput",
]

LOG = logging.getLogger(__name__)


class PartialInputs:
    """PDDLStream's optimistic-output generator spec: ``unique=True`` gives each stream
    instance its own placeholders, ``unique=False`` shares them between instances."""

    def __init__(
        self, inputs: str = "", unique: bool = False, test: Callable[..., Any] = universe_test
    ) -> None:
        self.inputs = tuple(inputs.split())
        self.unique = unique
        self.test = test

    def __repr__(self) -> str:
        return f"PartialInputs(inputs={' '.join(self.inputs)!r}, unique={self.unique})"


def _opt_gen_fn(value: Any) -> Callable[..., Any] | str | None:
    if value is None:
        return "shared"  # PDDLStream's default, PartialInputs(): shared until a plan uses it
    if isinstance(value, str):
        return value
    if callable(value):
        return with_opt_values(value)
    if isinstance(value, PartialInputs):
        if value.inputs:
            LOG.info("PartialInputs(inputs=%r): placeholders are shared per stream", value.inputs)
        return "unique" if value.unique else "shared"
    raise TypeError("StreamInfo opt_gen_fn must be a PartialInputs, a callable or None")


@dataclass(frozen=True, init=False)
class StreamInfo(_CoreStreamInfo):
    """``StreamInfo(opt_gen_fn=None, negate=False, simultaneous=False, verbose=True,
    eager=False, eager_skeleton=False, defer_fn=never_defer, p_success=None, overhead=None,
    effort=None, estimate=False)``.

    ``p_success=0`` with no ``effort`` makes the stream's effort infinite: as in PDDLStream
    it is never assumed optimistically, only its real (eager) results count, unless
    ``solve(effort_weight=...)`` is given (then its results cost ``overhead`` / 1e-9 efforts).
    ``estimate=True`` clears ``p_success``, ``overhead`` and ``effort``; the default defer
    function is stored as None. ``eager_skeleton`` is accepted and has no effect.
    """

    eager_skeleton: bool = False

    def __init__(
        self,
        opt_gen_fn: Any = None,
        negate: bool = False,
        simultaneous: bool = False,
        verbose: bool = True,
        eager: bool = False,
        eager_skeleton: bool = False,
        defer_fn: Callable[..., Any] | None = None,
        p_success: float | None = None,
        overhead: float | None = None,
        effort: float | None = None,
        estimate: bool = False,
    ) -> None:
        if estimate:
            p_success = overhead = effort = None
        values = {
            "eager": bool(eager),
            "p_success": p_success,
            "overhead": overhead,
            "effort": effort,
            "opt_gen_fn": _opt_gen_fn(opt_gen_fn),
            "negate": bool(negate),
            "simultaneous": bool(simultaneous),
            "verbose": bool(verbose),
            "defer_fn": None if defer_fn is never_defer else defer_fn,
            "eager_skeleton": bool(eager_skeleton),
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)
        self.__post_init__()


@dataclass(frozen=True, init=False)
class WildOutput(_CoreWildOutput):
    """``WildOutput(values=[], facts=[], actions=[], enumerated=False, replan=False)``: output
    tuples plus facts the stream did not declare. Unpacks as ``values, facts``."""

    enumerated: bool = False
    replan: bool = False

    def __init__(
        self,
        values: Sequence[Sequence[Any]] = (),
        facts: Sequence[Sequence[Any]] = (),
        actions: Sequence[Any] = (),
        enumerated: bool = False,
        replan: bool = False,
    ) -> None:
        if actions:
            raise NotImplementedError("WildOutput(actions=...) is not supported")
        object.__setattr__(self, "values", tuple(tuple(v) for v in values))
        object.__setattr__(self, "facts", tuple(tuple(f) for f in facts))
        object.__setattr__(self, "enumerated", bool(enumerated))
        object.__setattr__(self, "replan", bool(replan))

    def __iter__(self) -> Any:
        return iter((list(self.values), list(self.facts)))
