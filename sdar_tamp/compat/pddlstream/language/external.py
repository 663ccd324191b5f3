"""``pddlstream.language.external``: the debug stream-map modes and the defer functions.

In PDDLStream a defer function is consulted only for the stream results a plan needs at or
after the step that follows its first action named in ``solve(replan_actions=...)``; those are
left unevaluated in the returned plan, for the program to re-plan at that action. Without
replan actions nothing is deferred there. ``solve`` here drops the functions in that case (the
same result) and notes in the log that it evaluates the whole plan when replan actions are
given (:func:`sdar_tamp.compat.pddlstream.algorithms.meta.solve`); the predicates still answer
as documented when a program calls them itself."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from sdar_tamp.compat.pddlstream.language.problem import DEBUG, DEBUG_MODES, SHARED_DEBUG

__all__ = [
    "DEBUG",
    "DEBUG_MODES",
    "SHARED_DEBUG",
    "defer_shared",
    "defer_unique",
    "get_defer_all_unbound",
    "get_defer_any_unbound",
    "never_defer",
]


def never_defer(*_args: Any, **_kwargs: Any) -> bool:
    """Never postpone (PDDLStream's default)."""
    return False


def defer_shared(*_args: Any, **_kwargs: Any) -> bool:
    """Always postpone."""
    return True


def defer_unique(result: Any, *_args: Any, **_kwargs: Any) -> bool:
    """Postpone when the result's inputs are all known (``result.is_refined()``)."""
    refined = getattr(result, "is_refined", None)
    return bool(refined()) if callable(refined) else True


def _known(value: Any, bound: Any) -> bool:
    return not getattr(value, "is_optimistic", False) or value in bound


def get_defer_any_unbound(unique: bool = False) -> Callable[..., bool]:
    """A defer function: postpone when any input is not bound yet."""

    def defer_any_unbound(result: Any, bound_objects: Any = (), *_a: Any, **_k: Any) -> bool:
        if unique and not defer_unique(result):
            return False
        inputs = getattr(result, "input_objects", ())
        return not all(_known(value, bound_objects) for value in inputs)

    return defer_any_unbound


def get_defer_all_unbound(inputs: str = "", unique: bool = False) -> Callable[..., bool]:
    """A defer function: postpone when none of ``inputs`` (names, space separated) is bound."""
    names = tuple(inputs.split())

    def defer_all_unbound(result: Any, bound_objects: Any = (), *_a: Any, **_k: Any) -> bool:
        if unique and not defer_unique(result):
            return False
        mapping = getattr(result, "mapping", {})
        values = [mapping[n] for n in names if n in mapping]
        return not any(_known(value, bound_objects) for value in values)

    return defer_all_unbound
