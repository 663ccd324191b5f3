"""What SDAR-M still spends time on: within one decision, and near the end of its budget.

Two rules bound the time a run spends on groundings whose motions fail, on top of the tabu
lists of :mod:`~solvers.sdar.attempts` (which never retry one grounding):

* **Within a decision, with more than two arms** (:class:`DecisionSpend`). A *family* is a
  step's moves with one assignment of arms, in the decision's arrangement. Once a grounding
  of a family fails its motion, the other groundings of that family (other grasps, other IK
  branches of the same arms for the same objects, nothing else moved) are not tried in that
  decision: with the full motion stream, in any mode; with the quick one, with the quick one.
  And steps of fewer moves are preferred as soon as the larger ones keep failing: after
  ``SdarOptions.fewer_moves_after[0]`` failed motions of steps of three moves or more, the
  decision tries steps of at most two moves; after ``fewer_moves_after[1]`` failed motions in
  all, steps of one move. So a decision tries at most ``fewer_moves_after[1]`` groundings of
  several moves before it falls back to one arm at a time, instead of the 15 to 41 it could
  try before. With one or two arms neither rule applies (their plans are unchanged).
* **Near the end of the budget, in every cell** (:func:`finish_reserve`): a run whose
  ``max_time`` is finite and at least ``finish_min_time`` sets the soft limit of its
  :class:`~solvers.sdar.budget.Deadline` to ``finish_reserve`` [s] per remaining object before
  ``max_time`` (at most ``finish_share`` of ``max_time``). Once it passes, the run *finishes*:
  the task planner sees a view of at most ``finish_moves`` arms (one by default: SDAR-T's
  one-arm rules, ``n + |minimum FVS|`` moves for what is left; two: its two-arm rules, measured
  slower to finish with four arms), the first grounding found is executed and no decision
  compares groundings. One-move steps ground and plan quickly (one arm moving, the others
  going to or waiting at home; with three arms or more the optimiser sees only the moving
  arms), so the run returns a valid, perhaps longer, plan where it would have run out of time;
  it still ends at ``max_time`` if that is not enough.

Candidates are so bounded: per decision, at most ``fewer_moves_after[1]`` groundings of steps of
several moves fail their motions (each family once) before the decision tries one-move steps
alone; per run, everything after the soft limit is steps of at most ``finish_moves`` moves.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Hashable, Sequence
from typing import TYPE_CHECKING

from solvers.sdar.attempts import MotionMode
from solvers.sdar.tasks import Step, TaskView

if TYPE_CHECKING:
    from solvers.sdar.options import SdarOptions


class DecisionSpend:
    """The families blocked and the step sizes still allowed in one decision (see the module
    docstring); with ``arms <= 2`` everything is allowed."""

    def __init__(self, arms: int, fewer_moves_after: tuple[int, int]) -> None:
        self.active = arms > 2
        self.arms = arms
        self.fewer_moves_after = fewer_moves_after
        self._blocked_full: set[Hashable] = set()
        self._blocked_quick: set[Hashable] = set()
        self.failed_by_size: Counter[int] = Counter()
        """Failed motions of the decision by the number of moves of their step."""

    @property
    def most_moves(self) -> int:
        """The most moves a step tried in this decision may hold."""
        if not self.active:
            return self.arms
        large = sum(n for size, n in self.failed_by_size.items() if size >= 3)
        if sum(self.failed_by_size.values()) >= self.fewer_moves_after[1]:
            return 1
        if large >= self.fewer_moves_after[0]:
            return 2
        return self.arms

    def allowed(self, candidates: Sequence[Step]) -> list[Step]:
        """The candidates of at most :attr:`most_moves` moves."""
        most = self.most_moves
        return [s for s in candidates if len(s.moves) <= most]

    def blocked(self, step: Step, arms: tuple[str, ...], mode: MotionMode) -> bool:
        """A grounding of ``step`` with ``arms`` failed its motion in this decision (with the
        full motion stream; or with the quick one, for a quick attempt)."""
        key = (step.moves, arms)
        return self.active and (
            key in self._blocked_full or (mode is MotionMode.QUICK and key in self._blocked_quick)
        )

    def failed(self, step: Step, arms: tuple[str, ...], mode: MotionMode) -> None:
        """A grounding of ``step`` with ``arms`` failed its motion in ``mode``."""
        if not self.active:
            return
        key = (step.moves, arms)
        (self._blocked_quick if mode is MotionMode.QUICK else self._blocked_full).add(key)
        self.failed_by_size[len(step.moves)] += 1


def finish_reserve(options: SdarOptions, remaining: int) -> float:
    """The reserve [s] the anytime finish keeps for ``remaining`` objects (``inf``: no
    finish, when ``max_time`` is infinite or under ``finish_min_time``, or the reserve per
    object is 0)."""
    if (
        options.finish_reserve <= 0
        or options.max_time == float("inf")
        or options.max_time < options.finish_min_time
    ):
        return float("inf")
    return min(options.finish_reserve * remaining, options.finish_share * options.max_time)


def finishing_view(view: TaskView, moves: int) -> TaskView:
    """The view the task planner sees while the run finishes: at most ``moves`` arms (a
    step of at most ``moves`` moves), no layout."""
    return dataclasses.replace(view, arms=min(view.arms, moves), layout=None)


def finishing_options(options: SdarOptions) -> SdarOptions:
    """The grounder's options while the run finishes: the first grounding found is taken."""
    return dataclasses.replace(options, choose_among=1, peer_steps=0)
