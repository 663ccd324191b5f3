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
* **Near the end of the budget, in every cell** (:func:`finish_pace`): a run whose
  ``max_time`` is finite and at least ``finish_min_time`` sets the soft limit of its
  :class:`~solvers.sdar.budget.Deadline` before ``max_time`` by the reserve its remaining
  objects need at the pace measured in the run (:class:`~solvers.sdar.budget.Pace`: seconds
  per object times ``finish_safety``, ``finish_reserve`` per object before anything is
  measured; at most ``finish_share`` of ``max_time``). Once it passes, the run *finishes*:
  the task planner sees a view of at most ``finish_moves`` arms (one by default: SDAR-T's
  one-arm rules, ``n + |minimum FVS|`` moves for what is left; two: its two-arm rules, measured
  slower to finish with four arms), the first grounding found is executed and no decision
  compares groundings. One-move steps ground and plan quickly (one arm moving, the others
  going to or waiting at home; with three arms or more the optimiser sees only the moving
  arms), so the run returns a valid, perhaps longer, plan where it would have run out of time;
  it still ends at ``max_time`` if that is not enough. When the finish's own pace leaves
  room for a normal decision before the reserve again, the run goes back to the normal search
  (so a pessimistic first estimate costs a few finishing steps, not the plan's rest).

Candidates are so bounded: per decision, at most ``fewer_moves_after[1]`` groundings of steps of
several moves fail their motions (each family once) before the decision tries one-move steps
alone; per run, every step taken while finishing holds at most ``finish_moves`` moves.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Hashable, Mapping, Sequence
from typing import TYPE_CHECKING

from solvers.sdar.attempts import MotionMode
from solvers.sdar.budget import Pace
from solvers.sdar.tasks import Layout, Move, Step, TaskView

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


def finish_pace(options: SdarOptions) -> Pace | None:
    """The pace that sets the anytime finish's reserve (:class:`~solvers.sdar.budget.Pace`);
    None: no finish, when ``max_time`` is infinite or under ``finish_min_time``, or
    ``finish_reserve`` is 0."""
    if (
        options.finish_reserve <= 0
        or options.max_time == float("inf")
        or options.max_time < options.finish_min_time
    ):
        return None
    return Pace(
        options.max_time, options.finish_reserve, options.finish_safety, options.finish_share
    )


def finishing_view(view: TaskView, moves: int) -> TaskView:
    """The view the task planner sees while the run finishes: at most ``moves`` arms (a
    step of at most ``moves`` moves), no layout."""
    return dataclasses.replace(view, arms=min(view.arms, moves), layout=None)


def plane_seating(layout: Layout, moves: Sequence[Move]) -> tuple[int, ...]:
    """Arms (indices into ``layout.bases``) for ``moves`` in order: each the arm of least plane
    reach (:meth:`~solvers.sdar.tasks.Layout.reach`, a buffer move's at its object's pose
    alone: :func:`moves_layout`) not taken by an earlier one (the first of equals); shorter
    than ``moves`` when the arms run out."""
    plane = moves_layout(layout, moves)
    free = list(range(len(layout.bases)))
    seats: list[int] = []
    for move in moves:
        if not free:
            break
        arm = min(free, key=lambda k: (plane.reach(k, move.obj), k))
        seats.append(arm)
        free.remove(arm)
    return tuple(seats)


def moves_layout(layout: Layout, moves: Sequence[Move]) -> Layout:
    """``layout`` with each object moved to a buffer in ``moves`` at its pose at both ends (its
    buffer is not chosen yet; the arm reaches for the object first)."""
    buffered = {m.obj for m in moves if m.to_buffer}
    if not buffered:
        return layout
    places = {
        o: (here, here) if o in buffered else (here, goal)
        for o, (here, goal) in layout.places.items()
    }
    return dataclasses.replace(layout, places=places)


def spread_steps(view: TaskView, singles: Sequence[Step], gap: float) -> list[Step]:
    """The finish's candidates with more than two arms: ``singles`` (the one-arm candidates,
    in their order) preceded by one step that makes several of their moves at once, each
    with the nearest arm still free (:func:`plane_seating`), when there is such a step; when
    that step holds buffer moves, then by the step grown from goal moves alone (the arm
    nearest an object may reach no buffer, and a spread step gets that one seating).

    Greedily from the first single's move, then the other singles' moves, then the goal moves of
    the other objects left, pass after pass while a pass added a move (a goal freed by a move
    added late: a chain's next link, lifted in the same step): a move joins while the step holds
    fewer moves than ``view.arms`` and its arm's plane segments stay ``gap`` [m] from every
    other arm of the step over the whole transfer (:meth:`~solvers.sdar.tasks.Layout.sweep_gap`:
    at the picks, the places and between; a buffer move at its object's pose); a goal move when
    its goal is free once the step's objects are lifted, it does not have to wait for an object
    still to be placed (:meth:`~solvers.sdar.tasks.TaskView.must_wait`) and no object of the
    step waits for it or it for one; a buffer move when its object lies on a dependency cycle
    that no other buffer move of the step breaks (one buffer per cycle, as the one-arm rules
    spend). Arms so far apart rarely meet, so the step's motion is found about as quickly as one
    arm's, and up to ``view.arms`` one-move steps execute in the time of one. Without a layout,
    with two arms or fewer, with ``gap`` 0 or with nothing to join: ``singles`` alone."""
    layout = view.layout
    if layout is None or view.arms <= 2 or gap <= 0 or not singles:
        return list(singles)
    if len(singles[0].moves) != 1:
        return list(singles)
    names = view.graph.names
    cycle = {
        names[i]: k for k, part in enumerate(view.graph.components()) if len(part) > 1 for i in part
    }
    pool = [s.moves[0] for s in singles if len(s.moves) == 1]
    pool += [Move(o) for o in names if all(m.obj != o for m in pool)]
    group = _grow(view, layout, pool, cycle, gap)
    if len(group) < 2:
        return list(singles)
    steps = [Step(tuple(group), "spread", singles[0].rank)]
    if any(m.to_buffer for m in group):
        to_goals = list(dict.fromkeys(Move(m.obj) for m in pool))
        goals = _grow(view, layout, to_goals, cycle, gap, check_first=True)
        if len(goals) >= 2 and set(goals) != set(group):
            steps.append(Step(tuple(goals), "spread", singles[0].rank))
    return [*steps, *singles]


def _grow(
    view: TaskView,
    layout: Layout,
    pool: Sequence[Move],
    cycle: Mapping[str, int],
    gap: float,
    check_first: bool = False,
) -> list[Move]:
    """The moves of ``pool`` that join one step (:func:`_fits`), in pool order, pass after
    pass while a pass added one (a goal freed by a move added late joins on the next pass: a
    chain's next link), at most ``view.arms``. The first move is a one-arm candidate's,
    taken as it is, unless ``check_first``."""
    group: list[Move] = []
    grown = True
    while grown and len(group) < view.arms:
        grown = False
        for move in pool:
            if len(group) == view.arms:
                break
            if _fits(view, layout, group, move, cycle, gap, check_first):
                group.append(move)
                grown = True
    return group


def _fits(
    view: TaskView,
    layout: Layout,
    group: Sequence[Move],
    move: Move,
    cycle: Mapping[str, int],
    gap: float,
    check_first: bool = False,
) -> bool:
    """``move`` may join ``group`` (see :func:`spread_steps`): a new object the layout places,
    allowed with the group's moves, its arm ``gap`` [m] from theirs."""
    obj = move.obj
    if obj not in layout.places or any(m.obj == obj for m in group):
        return False
    if (group or check_first) and not _joins(view, group, move, cycle):
        return False
    trial = [*group, move]
    seats = plane_seating(layout, trial)
    plane = moves_layout(layout, trial)
    return len(seats) == len(trial) and all(
        plane.sweep_gap(seats[-1], obj, arm, m.obj) >= gap
        for arm, m in zip(seats, group, strict=False)
    )


def _joins(view: TaskView, group: Sequence[Move], move: Move, cycle: Mapping[str, int]) -> bool:
    """``move`` may join the moves of ``group`` (see :func:`spread_steps`), arms apart."""
    obj = move.obj
    if any((obj, m.obj) in view.waits or (m.obj, obj) in view.waits for m in group):
        return False
    if move.to_buffer:
        return obj in cycle and all(cycle.get(m.obj) != cycle[obj] for m in group if m.to_buffer)
    lifted = frozenset([obj, *(m.obj for m in group)])
    return view.goal_free_after(obj, lifted) and not view.must_wait(obj)


def finishing_options(options: SdarOptions) -> SdarOptions:
    """The grounder's options while the run finishes: the first grounding found is taken."""
    return dataclasses.replace(options, choose_among=1, peer_steps=0)
