"""``pddlstream.language.optimizer``: the output value of PDDLStream's optimizer streams.

Optimizer stream files (``:optimizer``) are not supported; ``OptimizerOutput`` is here so that
programs that define optimizer procedures next to ordinary streams import unchanged, and it
turns into a :class:`WildOutput` when such a procedure is used as a list stream."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from sdar_tamp.compat.pddlstream.language.stream import WildOutput

__all__ = ["OptimizerOutput"]


class OptimizerOutput:
    """``assignments`` (output tuples), extra ``facts`` and ``infeasible`` fact sets."""

    def __init__(
        self,
        assignments: Iterable[Sequence[Any]] = (),
        facts: Iterable[Sequence[Any]] = (),
        infeasible: Iterable[Iterable[Any]] = (),
    ) -> None:
        self.assignments = list(assignments)
        self.facts = list(facts)
        self.infeasible = [frozenset(group) for group in infeasible]

    def to_wild(self) -> WildOutput:
        return WildOutput(self.assignments, self.facts)

    def __bool__(self) -> bool:
        return bool(self.assignments)

    def __repr__(self) -> str:
        return f"OptimizerOutput(assignments={self.assignments!r}, facts={self.facts!r})"
