"""Committing one move's motions against the other arms' committed trajectories, in time.

A move is the reach (from where the arm stands to the grasp) and the carry (grasp to release).
Each motion is a path planned in space; :meth:`MoveCommit.place_motion` gives it its timing
against the other arms' committed, time-parameterised trajectories (a path-velocity
decomposition, prioritised in time):

1. the whole path, re-timed for the arm alone, at the earliest start whose replay
   (:mod:`.sweep`) is clear of every arm's committed trajectory (the start-time search of
   :meth:`~sdar_tamp.schedule.scheduler.Placement.place`);
2. when that start is later than the earliest because another arm is in the way at some
   point of the path, the path is cut a little before that point into two rest-to-rest
   motions: the first part starts at once, the arm stops clear of the other arm and waits
   there, and the rest follows at its own earliest start. The pause is kept when the motion
   then ends earlier than in 1. (The arm decelerates to rest and accelerates again, so each
   part keeps the arm's limits; the sweep checks the standing arm too.)

:meth:`MoveCommit.commit_move` commits the reach, then the carry; when the carry finds no
start because the arm, holding the object, stands in another arm's way, the grasp is tried
later. What a move's commit reports back (the conflict that delayed it) drives the
conflict-based retry of :meth:`MoveCommit.take` (plan the move, commit it, plan it again
around the arm that delayed it).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import numpy as np

from sdar_tamp.plan_file import PlanEvent, StepRecord
from sdar_tamp.schedule.move_records import AssignmentOptions, PlannedMove
from sdar_tamp.schedule.moves import Move
from sdar_tamp.schedule.room import Room, block_of
from sdar_tamp.schedule.scheduler import Entry, NoPlacement
from sdar_tamp.schedule.sweep import Conflict, TimedEvent
from sdar_tamp.world.transforms import FloatArray

Mark = tuple[list[int], list[TimedEvent], dict[int, int], int]  #: what ``undo`` restores
#: what was committed since a mark: per arm the new samples, then the events, their ticks and
#: the steps
Placed = tuple[list[list[FloatArray]], list[TimedEvent], dict[int, int], list[StepRecord]]

#: starts tried for a move's grasp when the carry after it finds none
REGRASPS = 3
#: [s] a move whose reach or carry waits this long for another arm is planned again with
#: that arm where the wait met it (:meth:`MoveCommit.take`)
DETOUR_AFTER = 0.2
#: [s] how far before the point where another arm is met a paused motion stops (tried in turn)
PAUSE_BACK = (0.1, 0.3)
#: [s] the least motion worth making before a pause
PAUSE_LEAST = 0.1
#: planned paths tried in a conflict-based retry (:meth:`MoveCommit.take`)
PAIRS_TRIED = 2


class MoveCommit(Room):
    """Commits moves' motions (see the module docstring); the state is set up by the
    subclass (``pauses``: whether motions may pause on the way)."""

    not_before: int
    pauses: bool
    paused: int
    move_of: dict[int, Move]  # id(event) -> its move
    options: AssignmentOptions
    grasp_tick: dict[int, int]
    release_tick: dict[int, int]
    carrier: dict[int, int]  # move -> arm
    planning_time: float
    detours: int
    detours_kept: int
    own: int  # moves committed along the synchronous plan's own motions

    def take(self, arm: int, m: Move) -> bool:
        """Plan and commit ``m`` by ``arm``; False when no planned path can be committed.

        The motions are planned against the other arms standing where their committed
        timelines end. When the first path that commits has to wait for another arm (the
        sweep meets that arm at the earliest start), the move is planned once more with
        that arm standing where the sweep met it (a conflict-based retry, up to
        ``replans`` times) and the path that releases the object first is kept."""
        resting = {o: p for o, p in self.rest.items() if o != m.obj}
        resting[m.obj] = m.start
        others = [np.array(self.traj[a][-1]) for a in self.arms]
        started = time.perf_counter()
        mark = self.mark()
        try:
            got = self.commit_first(
                arm, m, self.planner.plan(arm, self.stand[arm], m, resting, others)
            )
            for _ in range(self.options.replans):
                if got is None or got[1] is None or self.is_own(got[0][0]):
                    break  # the plan's own motion is not planned again
                release, conflict = self.tick_of(got[0][2]), got[1]
                dodge = list(others)
                for a in self.arms:
                    if a != arm and self.plan.arm_names[a] in conflict.arms:
                        dodge[a] = np.array(self.rows(a, conflict.tick, conflict.tick)[0])
                self.undo(mark)
                self.detours += 1
                plans = self.planner.plan(arm, self.stand[arm], m, resting, dodge)
                alt = self.commit_first(arm, m, plans, limit=PAIRS_TRIED)
                if alt is not None and self.tick_of(alt[0][2]) < release:
                    got = alt
                    self.detours_kept += 1
                    continue
                if alt is not None:
                    self.undo(mark)
                got = self.commit_first(arm, m, iter([got[0][0]]))
                break
        finally:
            self.planning_time += time.perf_counter() - started
        if got is None:
            return False
        planned, grasp, release_event = got[0]
        self.grasp_tick[m.index] = self.tick_of(grasp)
        self.release_tick[m.index] = self.tick_of(release_event)
        self.carrier[m.index] = arm
        self.own += self.is_own(planned)
        self.rest[m.obj] = m.end
        self.stand[arm] = planned.end
        self.parked[arm] = False
        return True

    def is_own(self, planned: PlannedMove) -> bool:
        """Whether ``planned`` is the synchronous plan's own motion (:mod:`.sync_motions`)."""
        return id(planned) in getattr(self.planner, "offered", ())

    def commit_first(
        self, arm: int, m: Move, options: Iterator[PlannedMove], limit: int | None = None
    ) -> tuple[tuple[PlannedMove, PlanEvent, PlanEvent], Conflict | None] | None:
        """Commit the first of the planned ``options`` (at most ``limit`` tried) that the
        sweep lets through: the planned move, its grasp and release events, and the conflict
        with another arm that delayed it (None: not delayed by another arm, or less than
        :data:`DETOUR_AFTER`); None when none goes."""
        name = self.plan.arm_names[arm]
        timer = self.retimers[arm]
        for n, planned in enumerate(options):
            if limit is not None and n >= limit:
                break
            self.plans += 1
            leaving = self.stand[arm].leaving
            reach = timer.retime(*planned.reach, leaving, True)
            carry = timer.retime(*planned.carry, True, True)
            grasp = PlanEvent(0.0, name, "grasp", m.obj, planned.T_tcp_object)
            release = PlanEvent(0.0, name, "release", m.obj, planned.T_tcp_object)
            self.move_of[id(grasp)] = self.move_of[id(release)] = m
            delayed = self.commit_move(arm, (reach, grasp, leaving), (carry, release, True))
            if delayed is False:
                continue
            return (planned, grasp, release), (None if delayed is True else delayed)
        return None

    def tick_of(self, event: PlanEvent) -> int:
        """The tick of a committed event (by identity)."""
        return next(e.tick for e in self.events if e.event is event)

    def commit_move(
        self,
        arm: int,
        reach: tuple[FloatArray, PlanEvent, bool],
        carry: tuple[FloatArray, PlanEvent, bool],
    ) -> bool | Conflict:
        """Commit the reach (samples, the grasp, whether it leaves a gripper event), then the
        carry (ending in the release); when the carry finds no start because the arm, holding
        the object, stands in another arm's way, the grasp is tried later (up to
        :data:`REGRASPS` times). False: nothing committed; else the conflict with another arm
        that delayed the reach or the carry by :data:`DETOUR_AFTER` or more (True: none)."""
        self.not_before = 0
        least = math.ceil(DETOUR_AFTER / self.tick - 1e-9)
        in_way: Conflict | None = None  # another arm in the carry's way at an earlier grasp
        try:
            for _ in range(REGRASPS):
                mark = self.mark()
                try:
                    delayed = self.place_motion(arm, *reach, least)
                except NoPlacement as exc:
                    self.undo(mark)
                    self.note_in_way(arm, exc.conflict)
                    return False
                try:
                    later = self.place_motion(arm, *carry, least)
                except NoPlacement as exc:
                    grasped = self.tick_of(reach[1])
                    self.undo(mark)
                    self.note_in_way(arm, exc.conflict)
                    if exc.conflict is None or exc.conflict.tick < grasped or not exc.conflict.arms:
                        return False  # not another arm in the way: a later grasp is no better
                    in_way = exc.conflict
                    start = grasped - (len(reach[0]) - 1)
                    self.not_before = max(start + 1, exc.conflict.tick - len(reach[0]) + 2)
                    continue
                found = delayed or later or in_way
                return True if found is None else found
            return False
        finally:
            self.not_before = 0

    def place_motion(
        self, arm: int, q: FloatArray, event: PlanEvent | None, leaving: bool, least: int
    ) -> Conflict | None:
        """Commit the motion ``q`` ``(n + 1, k)`` ending in ``event`` (if any) at its
        earliest start, or paused on the way when that ends it earlier (see the module
        docstring); the conflict with another arm that delayed the whole motion by ``least``
        ticks or more, else None. Raises :class:`NoPlacement` when no start is found."""
        mark = self.mark()
        whole = Entry(arm, block_of(arm, q, event), q, 0)
        self.place([whole])
        delayed = self.arm_delay(least)
        if not self.pauses or delayed is None:
            return delayed
        end = self.horizon(arm)
        met = delayed.tick - (end - self.length(whole) - self.delay)  # at the earliest start
        for back in PAUSE_BACK:
            cut = min(met, len(q) - 1) - math.ceil(back / self.tick - 1e-9)
            if cut * self.tick < PAUSE_LEAST or cut >= len(q) - 1:
                continue
            if self.paused_motion(arm, q, event, leaving, cut, end, mark):
                self.paused += 1
                return None
        return delayed

    def paused_motion(
        self,
        arm: int,
        q: FloatArray,
        event: PlanEvent | None,
        leaving: bool,
        cut: int,
        end: int,
        mark: Mark,
    ) -> bool:
        """Replace the committed motion (placed since ``mark``, ending at tick ``end``) by
        its first ``cut`` samples and the rest, each from rest to rest and started as early
        as the sweep lets it, when that ends earlier; whether it did (else the committed
        motion is put back as it was)."""
        timer = self.retimers[arm]
        t = np.arange(len(q), dtype=np.float64) * self.tick
        first = timer.retime(t[: cut + 1], q[: cut + 1], leaving, False)
        rest = timer.retime(t[cut:] - t[cut], q[cut:], False, True)
        kept, delay = self.since(mark), (self.delay, self.delayed_by)
        self.undo(mark)
        try:
            self.place([Entry(arm, block_of(arm, first), first, 0)])
            self.place([Entry(arm, block_of(arm, rest, event), rest, 0)])
        except NoPlacement:
            self.put_back(mark, kept)
            self.delay, self.delayed_by = delay
            return False
        if self.horizon(arm) < end:
            return True
        self.put_back(mark, kept)
        self.delay, self.delayed_by = delay
        return False

    def since(self, mark: Mark) -> Placed:
        """What was committed since ``mark`` (for :meth:`put_back`)."""
        tails = [list(traj[n:]) for traj, n in zip(self.traj, mark[0], strict=True)]
        return tails, list(self.events), dict(self.event_tick), list(self.steps[mark[3] :])

    def put_back(self, mark: Mark, placed: Placed) -> None:
        """Take back everything since ``mark`` and commit ``placed`` (:meth:`since`) again as
        it was: the same motions at the same ticks (a placement is a function of the state,
        so searching again would find them)."""
        self.undo(mark)
        tails, events, event_tick, steps = placed
        for traj, tail in zip(self.traj, tails, strict=True):
            traj.extend(tail)
        self.events, self.event_tick = list(events), dict(event_tick)
        self.steps.extend(steps)

    def arm_delay(self, least: int) -> Conflict | None:
        """The conflict with another arm that delayed the last placement by ``least`` ticks
        or more, else None."""
        c = self.delayed_by
        return c if self.delay >= least and c is not None and c.arms else None


__all__ = ["DETOUR_AFTER", "PAIRS_TRIED", "PAUSE_BACK", "REGRASPS", "MoveCommit"]
