"""``pddlstream.language.function``: ``FunctionInfo`` / ``PredicateInfo`` with PDDLStream's
keywords, and ``add_opt_function``."""

from __future__ import annotations

from collections.abc import Callable, MutableMapping
from dataclasses import dataclass
from typing import Any

from sdar_tamp.compat.pddlstream.language.external import never_defer
from sdar_tamp.compat.pddlstream.language.object import UniqueOptValue
from sdar_tamp.language.options import FunctionInfo as _CoreFunctionInfo
from solvers.stream_planning.opt_values import OptimisticValue

__all__ = ["FunctionInfo", "PredicateInfo", "add_opt_function"]


def with_opt_values(opt_fn: Callable[..., Any]) -> Callable[..., Any]:
    """``opt_fn`` (or an ``opt_gen_fn``) called with PDDLStream's optimistic values
    (:class:`UniqueOptValue`) in place of the solver's placeholders that have no optimistic
    value, so ``type(x) in [UniqueOptValue, ...]`` checks work."""

    def wrapped(*args: Any) -> Any:
        converted = tuple(
            UniqueOptValue(a.stream, 0, a.name) if isinstance(a, OptimisticValue) else a
            for a in args
        )
        return opt_fn(*converted)

    wrapped.__wrapped__ = opt_fn  # type: ignore[attr-defined]
    return wrapped


@dataclass(frozen=True, init=False)
class FunctionInfo(_CoreFunctionInfo):
    """``FunctionInfo(opt_fn=None, eager=True, verbose=True, defer_fn=never_defer,
    p_success=None, overhead=None, effort=None)``; ``opt_fn`` gives the optimistic value of
    the function on inputs not sampled yet."""

    defer_fn: Callable[..., Any] | None = None

    _default_eager = True

    def __init__(
        self,
        opt_fn: Callable[..., Any] | None = None,
        eager: bool | None = None,
        verbose: bool = True,
        defer_fn: Callable[..., Any] | None = None,
        p_success: float | None = None,
        overhead: float | None = None,
        effort: float | None = None,
        eager_skeleton: bool = False,
        estimate: bool = False,
    ) -> None:
        if estimate:
            p_success = overhead = effort = None
        values = {
            "opt_fn": None if opt_fn is None else with_opt_values(opt_fn),
            "eager": self._default_eager if eager is None else bool(eager),
            "p_success": p_success,
            "overhead": overhead,
            "effort": effort,
            "verbose": bool(verbose),
            "defer_fn": None if defer_fn is never_defer else defer_fn,
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)


@dataclass(frozen=True, init=False)
class PredicateInfo(FunctionInfo):
    """``FunctionInfo`` for a ``:predicate`` (not eager by default)."""

    _default_eager = False


def add_opt_function(
    name: str,
    base_fn: Callable[..., float],
    stream_map: MutableMapping[str, Any],
    stream_info: MutableMapping[str, Any],
    constant: float = 0.0,
    coefficient: float = 1.0,
    **external_kwargs: Any,
) -> tuple[MutableMapping[str, Any], MutableMapping[str, Any]]:
    """Register ``name`` as ``constant + coefficient * base_fn(...)`` with the optimistic
    value ``constant``; returns the two maps (changed in place)."""
    stream_map[name] = lambda *args, **kwargs: constant + coefficient * base_fn(*args, **kwargs)
    stream_info[name] = FunctionInfo(opt_fn=lambda *args, **kwargs: constant, **external_kwargs)
    return stream_map, stream_info
