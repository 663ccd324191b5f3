"""``pddlstream.algorithms.common``: the solutions of the last ``solve`` call.

:data:`SOLUTIONS` is PDDLStream's one piece of module state that programs read (its ``tamp``
example prints cost over time from it): after every ``solve``/``solve_*`` call of this tree it
holds that call's plans, best last, as ``Solution(plan, cost, time)`` records (``time`` [s]
since the call started). It is the compatibility tree's only module-level mutable value; the
core solvers never touch it. PDDLStream's ``SolutionStore`` and evaluation bookkeeping are not
provided.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__ = ["SOLUTIONS"]


class Solution(NamedTuple):
    """One plan found by a ``solve`` call: the plan, its cost and when [s] it was found."""

    plan: Any
    cost: float
    time: float


#: the plans of the last solve call, best last (see the module's docstring)
SOLUTIONS: list[Solution] = []


def record_solutions(found: list[Solution]) -> None:
    """Replace :data:`SOLUTIONS` in place (programs hold a reference to the list)."""
    SOLUTIONS[:] = found


__getattr__ = not_provided(
    __name__,
    "PDDLStream's SolutionStore and evaluation bookkeeping (the solvers here keep their own)",
)
