"""``pddlstream.language.temporal``: timing of plans of ``DurativeAction`` steps (``solve``
returns them for a domain with durative actions, which run one after the other) and of
sequential plans. Temporal Fast Downward (``solve_tfd``) is not provided."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from sdar_tamp.compat.pddlstream.language.constants import DurativeAction

__all__ = [
    "DurativeAction",
    "apply_start",
    "compute_duration",
    "compute_end",
    "compute_start",
    "get_end",
    "retime_plan",
]


def get_end(action: DurativeAction) -> float:
    return action.start + action.duration


def compute_start(plan: Sequence[DurativeAction]) -> float:
    return min((action.start for action in plan), default=0.0)


def compute_end(plan: Sequence[DurativeAction]) -> float:
    return max((get_end(action) for action in plan), default=0.0)


def compute_duration(plan: Sequence[DurativeAction] | None) -> float:
    """The time from the first start to the last end (0 for an empty or missing plan)."""
    if not plan:
        return 0.0
    return compute_end(plan) - compute_start(plan)


def apply_start(plan: Sequence[DurativeAction], new_start: float) -> list[DurativeAction]:
    """``plan`` shifted so that it starts at ``new_start``."""
    if not plan:
        return list(plan)
    delta = new_start - compute_start(plan)
    return [DurativeAction(a.name, a.args, a.start + delta, a.duration) for a in plan]


def retime_plan(plan: Sequence[Any] | None, duration: float = 1) -> list[DurativeAction] | None:
    """A sequential plan as durative actions, one after the other, each lasting ``duration``."""
    if plan is None:
        return None
    return [
        DurativeAction(action[0], tuple(action[1]), index * duration, duration)
        for index, action in enumerate(plan)
    ]
