"""Per-stream options and plan constraints (PDDLStream's ``StreamInfo``, ``FunctionInfo``,
``PlanConstraints``). Options that a solver does not implement yet are accepted and reported
with a logged warning by that solver, never ignored silently (see :func:`unsupported_options`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import Any, Final


class _Wild:
    """The type of ``WILD``: a skeleton argument that matches anything (compare with ``is``)."""

    def __repr__(self) -> str:
        return "WILD"


WILD: Final = _Wild()


@dataclass(frozen=True)
class StreamInfo:
    """How a solver should treat one stream.

    Attributes:
        eager: call each new instance once as soon as its inputs exist (before planning), as
            an incremental stream would; at most 10,000 eager calls per solve.
        p_success: prior probability that one call succeeds, in [0, 1]. 0 (with no
            ``effort``): the stream's effort is infinite. Without ``effort_weight`` the
            optimistic algorithms never assume its outputs, only its real results count
            (``eager`` calls it on real inputs), as PDDLStream prunes such streams; with
            ``effort_weight`` it is assumed, each optimistic result costing ``overhead`` / 1e-9
            efforts (1 with ``unit_efforts``).
        overhead: expected cost of one call [s], >= 0.
        effort: fixed effort used in place of the one derived from p_success and overhead.
        opt_gen_fn: placeholder outputs: ``"unique"`` (default, one per instance) or
            ``"shared"`` (one per stream), or a callable called like the sampler on the
            instance's (optimistic) input values whose first batch of output tuples gives the
            optimistic outputs and their values (see ``solvers.stream_planning.optimistic``).
        negate: for a test stream certifying one fact over its inputs: the domain may use
            that fact negated; ``(not (fact ...))`` holds where the test returns False. Such
            a test is evaluated when a candidate plan uses it (or at once with ``eager``).
        simultaneous: evaluate all instances of this stream together.
        verbose: log each call.
        defer_fn: decides whether the stream is evaluated only after a plan is found.
    """

    eager: bool = False
    p_success: float | None = None
    overhead: float | None = None
    effort: float | None = None
    opt_gen_fn: Callable[..., Any] | str | None = None
    negate: bool = False
    simultaneous: bool = False
    verbose: bool = True
    defer_fn: Callable[..., Any] | None = None

    def __post_init__(self) -> None:
        if self.p_success is not None and not 0.0 <= self.p_success <= 1.0:
            raise ValueError(f"StreamInfo.p_success must be in [0, 1], got {self.p_success}")
        if isinstance(self.opt_gen_fn, str) and self.opt_gen_fn not in ("shared", "unique"):
            raise ValueError(
                f"StreamInfo.opt_gen_fn must be 'shared', 'unique' or a callable, "
                f"got {self.opt_gen_fn!r}"
            )
        if self.overhead is not None and self.overhead < 0:
            raise ValueError(f"StreamInfo.overhead must be >= 0, got {self.overhead}")


@dataclass(frozen=True)
class FunctionInfo:
    """How a solver should treat one ``:function`` or ``:predicate``.

    Attributes:
        opt_fn: its optimistic value on inputs not evaluated yet (called with the inputs'
            values; default 1 for a function, true for a predicate).
        eager: evaluate each instance as soon as its inputs exist; by default the optimistic
            algorithms evaluate only the instances a candidate plan uses.
    """

    opt_fn: Callable[..., Any] | None = None
    eager: bool = False
    p_success: float | None = None
    overhead: float | None = None
    effort: float | None = None
    verbose: bool = True


@dataclass(frozen=True)
class PlanConstraints:
    """Restricts plans to ``skeletons`` (action name + arguments, ``WILD`` matches anything)."""

    skeletons: Sequence[Sequence[tuple[str, Sequence[Any]]]] | None = None
    exact: bool = True
    max_cost: float = math.inf


def unsupported_options(info: StreamInfo | FunctionInfo, supported: set[str]) -> list[str]:
    """Names of options set to a non-default value that are not in ``supported``."""
    defaults = type(info)()
    return [
        f.name
        for f in fields(info)
        if f.name not in supported and getattr(info, f.name) != getattr(defaults, f.name)
    ]


def never_assumed(info: StreamInfo) -> bool:
    """A stream whose effort is infinite (``p_success=0`` and no ``effort``): never assumed
    optimistically when efforts do not weigh on plans (see ``StreamInfo.p_success``)."""
    return info.p_success == 0 and info.effort is None
