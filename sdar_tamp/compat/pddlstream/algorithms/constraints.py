"""``pddlstream.algorithms.constraints``: ``PlanConstraints`` and ``WILD``.

PDDLStream spells the wildcard ``'*'``; here ``WILD`` is the core sentinel and a ``'*'``
argument in a skeleton is read as ``WILD`` too, so both spellings work.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from sdar_tamp.language.options import WILD
from sdar_tamp.language.options import PlanConstraints as _CorePlanConstraints

__all__ = ["WILD", "PlanConstraints"]
WILD_STRING = "*"


def _skeleton(skeleton: Any) -> tuple[tuple[str, tuple[Any, ...]], ...]:
    steps = getattr(skeleton, "actions", skeleton)  # PDDLStream's OrderedSkeleton
    return tuple(
        (name, tuple(WILD if isinstance(a, str) and a == WILD_STRING else a for a in args))
        for name, args in steps
    )


@dataclass(frozen=True, init=False)
class PlanConstraints(_CorePlanConstraints):
    """``PlanConstraints(skeletons=None, groups={}, exact=True, hint=False, max_cost=INF)``.

    ``groups`` and ``hint`` are accepted and have no effect."""

    groups: Mapping[str, Sequence[Any]] | None = None
    hint: bool = False

    def __init__(
        self,
        skeletons: Sequence[Any] | None = None,
        groups: Mapping[str, Sequence[Any]] | None = None,
        exact: bool = True,
        hint: bool = False,
        max_cost: float = math.inf,
    ) -> None:
        converted = None if skeletons is None else tuple(_skeleton(s) for s in skeletons)
        object.__setattr__(self, "skeletons", converted)
        object.__setattr__(self, "exact", bool(exact))
        object.__setattr__(self, "max_cost", max_cost)
        object.__setattr__(self, "groups", dict(groups) if groups else None)
        object.__setattr__(self, "hint", bool(hint))
