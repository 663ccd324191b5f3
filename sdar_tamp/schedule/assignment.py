"""Asynchronous execution with the moves assigned anew: a free arm takes the next ready move.

:mod:`.timelines` keeps the synchronous plan's task assignment (which arm carries which
object, in which order) and its paths. :func:`schedule_assigned` keeps only the plan's moves
(:mod:`.moves`: each object from the pose where it is grasped to the pose where it is released,
with the order those moves must keep) and decides, event by event, which arm carries which:

1. The arm whose timeline ends first is the free arm. The moves that are *ready* are those
   whose object's previous move is committed and whose blockers (the moves that lift the objects
   resting under or right beside the release pose) and earlier neighbours (the moves that put
   objects down right beside it first in the synchronous plan) are committed.
2. The free arm takes the ready move it would finish earliest, by the planner's estimate
   (:meth:`MovePlanner.estimate`: rest-to-rest times between the arm's configuration and the
   move's grasp and release configurations) from the end of its timeline and the dependencies'
   times; a move the synchronous plan gave this arm is preferred when two finish within
   :data:`TIE` of each other. The ``candidates`` best are tried in turn (with a finite
   ``slack``, one that releases its object more than ``slack`` later than estimated is
   compared with the next and the earliest release kept; by default the first that goes).
3. The move's single-arm motions (free arm -> grasp, grasp -> release, each with the retreat
   and approach of a grasp) come from the planner (:meth:`MovePlanner.plan`: the motion
   planner against the static world of resting objects and the other arms standing where
   their committed timelines end, then with the other arms at home), re-timed for the arm
   alone by the time-optimal path timing, and are committed at the earliest start whose
   replay (:mod:`.sweep`) is clear of every arm's committed, time-parameterised trajectory
   (sampled at the same ticks: a motion may pass where another arm was, once it has left),
   the table and the objects where they rest then (an arm whose timeline has ended stands
   where it ends), after the dependencies: the object's previous release and the blockers'
   grasps, a dwell before; when the arm, holding the object, would stand in another arm's
   way before the carry can start, the grasp is moved later. When the earliest start meets
   another arm and the motion waits :data:`~.move_commit.DETOUR_AFTER` or more, the move is
   planned again with that arm standing where the sweep met it (a conflict-based retry) and
   the path that releases the object first is kept. A planned path that never clears within
   ``max_wait`` is dropped for the planner's next one, then for the next move. When none of the
   ``candidates`` goes, the other arms that the attempts met (every other arm when they met
   none) retreat from the grasp or release configuration where they stand to its pre-grasp
   (back out along their approach, a few cm off the object) and the best move is tried once
   more; then those arms go home and it is tried again.
4. An arm that finds no move to take retreats to its pre-grasp when it stands at a grasp or
   release configuration, else waits until the next arm's timeline ends (the next event); it
   goes home only when another arm needs the room (step 3). When every arm has come to one
   time, the arms still in the workspace go home; when every arm is home and no move can be
   committed, there is no schedule (:class:`~sdar_tamp.schedule.scheduler.NoPlacement`); the
   caller keeps another one.

How the free arm chooses (step 2) is the search's *policy* (:data:`POLICIES`); the search is
run once per policy of :attr:`AssignmentOptions.policies` and the shortest schedule kept,
within :attr:`AssignmentOptions.max_seconds` of wall-clock time for all of them (a search
past it stops at its next decision; the best schedule found so far is returned). How a
motion is committed in time, pausing on the way when another arm delays it, is
:mod:`.move_commit`'s.

A move is committed whole (grasp and release together), so no arm ever holds an object while
it waits for another arm: the only order is the moves' own, which the synchronous plan proves
acyclic once every rotation without a buffer (objects that trade places, all held at once) has
one object sent through a buffer (:func:`~.moves.break_cycles`, :meth:`MovePlanner.buffer`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable

import numpy as np

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.schedule.move_commit import MoveCommit
from sdar_tamp.schedule.move_records import (
    POLICIES,
    AssignmentOptions,
    MovePlanner,
    PlannedMove,
    Stand,
)
from sdar_tamp.schedule.moves import CyclicMoves, Move, Pose, break_cycles, plan_moves
from sdar_tamp.schedule.own_first import advance, free_arm, go_ahead, own_first, sync_spans
from sdar_tamp.schedule.retiming import ArmRetimer
from sdar_tamp.schedule.room import no_block
from sdar_tamp.schedule.scheduler import (
    Entry,
    NoPlacement,
    Schedule,
    ScheduleOptions,
    retimer,
)
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.schedule.sync_motions import SeededPlanner, sync_moves
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene

#: [s] two moves whose estimated finishing times are this close count as equal (the
#: synchronous plan's arm is preferred then)
TIE = 0.05
#: [m] the room beside an object that fingers need to grasp or release it: moves whose poses
#: come this close keep their synchronous order (:func:`~sdar_tamp.schedule.moves.plan_moves`)
FINGER_ROOM = 0.03


class Assignment(MoveCommit):
    """The event-driven assignment of moves to arms (see the module docstring)."""

    def __init__(
        self,
        plan: PlanFile,
        sweep: WorldSweep,
        options: ScheduleOptions,
        moves: tuple[Move, ...],
        planner: MovePlanner,
        retimers: list[ArmRetimer],
        assignment: AssignmentOptions,
        policy: str = "earliest",
        deadline: float = math.inf,
    ) -> None:
        super().__init__(plan, [[] for _ in plan.arms], sweep, options, "objects")
        self.policy, self.deadline = policy, deadline
        self.pauses, self.paused = assignment.pauses, 0
        self.queries_before = sweep.queries  # the sweep is shared by the policies' searches
        self.moves, self.planner, self.retimers = moves, planner, retimers
        self.options = assignment
        self.stand = [Stand(np.array(plan.q[0, self.columns[a]])) for a in self.arms]
        self.parked = [True for _ in self.arms]
        self.rest: dict[str, Pose] = dict(sweep.start)
        self.move_of: dict[int, Move] = {}  # id(event) -> its move
        self.grasp_tick: dict[int, int] = {}
        self.release_tick: dict[int, int] = {}
        self.carrier: dict[int, int] = {}  # move -> arm
        self.plans = 0
        self.planning_time = 0.0
        self.waits = 0
        self.parks = 0
        self.retreats = 0
        self.slack = assignment.slack
        self.estimated: dict[int, int] = {}  # move -> its estimated release [ticks]
        self.spans = sync_spans(plan, moves)  # move -> its synchronous arm's time for it [s]
        self.in_way: set[int] = set()  # arms met by the failed attempts of the decision
        self.detours = 0
        self.detours_kept = 0
        self.own = 0  # moves committed along the synchronous plan's own motions
        self.not_before = 0  # the least start of the reach being committed [ticks]
        self.stride = assignment.stride
        self.give_up_standing = True

    # -- the order of moves -----------------------------------------------------------------
    def ready_move(self, m: Move) -> bool:
        before = (*m.blockers, *m.placed_after, *([] if m.previous is None else [m.previous]))
        return m.index not in self.carrier and all(b in self.carrier for b in before)

    def bound(self, m: Move) -> tuple[int, int]:
        """The earliest grasp and release ticks the dependencies allow."""
        grasp = 0 if m.previous is None else self.release_tick[m.previous] + self.dwell
        release = max(
            [
                *(self.grasp_tick[b] + self.dwell for b in m.blockers),
                *(self.release_tick[b] + self.dwell for b in m.placed_after),
            ],
            default=0,
        )
        return grasp, release

    def earliest(self, entry: Entry) -> int:
        s = self.horizon(entry.arm)
        e = entry.block.event
        if e is not None and id(e) in self.move_of:
            grasp, release = self.bound(self.move_of[id(e)])
            if e.type == "grasp":
                s = max(s, self.not_before)
            s = max(s, (grasp if e.type == "grasp" else release) - (len(entry.q) - 1))
        return s - entry.offset

    # -- the search -------------------------------------------------------------------------
    def run(self) -> PlanFile:
        pending = list(self.moves)
        while pending:
            if (
                self.sweep.queries - self.queries_before >= self.options.max_checks
                or self.plans >= self.options.max_plans
            ):
                raise NoPlacement(no_block(0), None, "out of collision checks or motion plans")
            if time.perf_counter() > self.deadline:
                raise NoPlacement(no_block(0), None, "out of time")
            arm, ranked = self.free_arm([m for m in pending if self.ready_move(m)])
            self.in_way = set()
            done = self.choose(arm, ranked[: self.options.candidates])
            clears: tuple[Callable[[int], bool], ...] = (self.back_off, self.clear_way)
            if self.policy == "own-first":  # the arms in the way go ahead, as in the plan
                clears = (lambda a: go_ahead(self, a), *clears)
            for clear in clears:
                if done is None and ranked and clear(arm):
                    done = next((m for m in ranked[:1] if self.take(arm, m)), None)
            if done is not None:
                pending.remove(done)
                if self.policy == "clear":  # leave the spot at once
                    self.retreat(arm)
            elif not self.make_room(arm):
                self.wait(arm)
        return self.assemble()

    def free_arm(self, ready: list[Move]) -> tuple[int, list[Move]]:
        """The arm whose timeline ends first and its ranked candidates (policy
        ``own-first``: :func:`~.own_first.free_arm`)."""
        if self.policy == "own-first":
            return free_arm(self, ready)
        first = min(self.arms, key=lambda a: (self.horizon(a), a))
        return first, self.rank(first, ready)

    def make_room(self, arm: int) -> bool:
        """``arm`` found no move: it retreats when it stands at a grasp or release
        configuration, and (policy ``clear``) goes home when it stands elsewhere in the
        workspace; whether it moved."""
        if self.stand[arm].pre is not None and self.retreat(arm):
            return True
        if self.policy == "own-first" and advance(self, arm):
            return True
        return self.policy == "clear" and not self.parked[arm] and self.park(arm)

    def choose(self, arm: int, ranked: list[Move]) -> Move | None:
        """Commit the first of ``ranked`` that releases its object within ``slack`` [s] of
        the estimate; when each is later than that (it waits for other arms), the one that
        releases first (None when none can be committed)."""
        late: list[tuple[int, int, Move]] = []
        for n, m in enumerate(ranked):
            mark, before = self.mark(), (self.stand[arm], self.parked[arm], self.rest[m.obj])
            if not self.take(arm, m):
                continue
            release = self.release_tick[m.index]
            on_time = release * self.tick <= self.estimated[m.index] * self.tick + self.slack
            if (on_time or n + 1 == len(ranked)) and (not late or release <= min(late)[0]):
                return m
            late.append((release, n, m))
            self.undo(mark)
            self.stand[arm], self.parked[arm], self.rest[m.obj] = before
            for book in (self.carrier, self.grasp_tick, self.release_tick):
                del book[m.index]
        for _, _, m in sorted(late, key=lambda x: x[:2]):
            if self.take(arm, m):
                return m
        return None

    def rank(self, arm: int, ready: list[Move], policy: str | None = None) -> list[Move]:
        """``ready`` moves the arm can do, by estimated finishing time (ties: the arm's own;
        policy ``plan-order``: by their order in the synchronous plan; ``own-first``: see
        :mod:`.own_first`)."""
        policy = policy or self.policy
        if policy == "own-first":
            return own_first(self, arm, ready)
        h = self.horizon(arm) * self.tick
        scored: list[tuple[float, int, int, Move]] = []
        for m in ready:
            est = self.planner.estimate(arm, self.stand[arm], m)
            if est is None:
                continue
            grasp, release = (k * self.tick for k in self.bound(m))
            finish = (
                max(max(h, grasp) + est + self.dwell * self.tick, release) + self.dwell * self.tick
            )
            first = m.index if policy == "plan-order" else round(finish / TIE)
            scored.append((first, m.arm != arm, m.index, m))
            self.estimated[m.index] = math.ceil((finish - self.dwell * self.tick) / self.tick)
        scored.sort(key=lambda s: s[:3])
        return [s[3] for s in scored]

    def figures(self) -> tuple[tuple[str, float], ...]:
        """Moves committed and how many went to another arm than in the synchronous plan,
        motion plans made and their time [s], waits for the next event, trips home, moves
        done along the synchronous plan's own motions."""
        moved = {m.index: m.arm for m in self.moves}
        return (
            ("moves", float(len(self.carrier))),
            ("reassigned", float(sum(a != moved[i] for i, a in self.carrier.items()))),
            ("motion_plans", float(self.plans)),
            ("planning_time", self.planning_time),
            ("waits", float(self.waits)),
            ("parks", float(self.parks)),
            ("retreats", float(self.retreats)),
            ("collision_queries", float(self.sweep.queries)),
            ("detours", float(self.detours)),
            ("detours_kept", float(self.detours_kept)),
            ("paused", float(self.paused)),
            ("sync_motions", float(self.own)),
        )


def schedule_assigned(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    options: ScheduleOptions,
    planner: MovePlanner,
    assignment: AssignmentOptions | None = None,
    margin: float = FINGER_ROOM,
) -> Schedule:
    """The moves of the synchronous ``plan`` assigned anew to the arms (see the module
    docstring); the input plan (``asynchronous`` False, with the reason) when no schedule is
    found or it is not shorter. ``margin`` [m]: the room fingers need beside an object
    (:func:`~sdar_tamp.schedule.moves.plan_moves`)."""
    assignment = assignment or AssignmentOptions()
    sweep = WorldSweep(instance, scene, options.max_tcp_step)

    def kept(
        why: str, duration: float | None, figures: tuple[tuple[str, float], ...] = ()
    ) -> Schedule:
        return Schedule(
            plan, False, plan.duration, duration, "assigned", why, sweep.checks, figures
        )

    try:
        made = plan_moves(plan, instance, sweep, margin)
        moves = break_cycles(made, planner.buffer)
    except CyclicMoves as exc:
        return kept(str(exc), None)
    if assignment.sync_motions or "own-first" in assignment.policies:
        planner = SeededPlanner(planner, sync_moves(plan, moves, made))
    retimers = [retimer(scene, i, options) for i in range(len(scene.arms))]
    limited = dataclasses.replace(
        options, max_checks=assignment.max_checks, max_wait=assignment.max_wait
    )
    deadline = time.perf_counter() + assignment.max_seconds
    best: tuple[PlanFile, str, tuple[tuple[str, float], ...]] | None = None
    reasons: list[str] = []
    found: list[tuple[str, float]] = []
    figures: tuple[tuple[str, float], ...] = ()
    for policy in assignment.policies:
        if time.perf_counter() > deadline:
            reasons.append(f"{policy}: not tried (out of time)")
            continue
        search = Assignment(
            plan, sweep, limited, moves, planner, retimers, assignment, policy, deadline
        )
        try:
            result = search.run()
        except NoPlacement as exc:
            reasons.append(f"{policy}: {exc}")
            figures = figures or search.figures()
            continue
        result = dataclasses.replace(
            result, metrics=result.metrics.updated({"execution": "assigned"})
        )
        limit = check_timeline(result, scene, options.dwell)
        if limit is not None:  # by construction this does not happen
            reasons.append(f"{policy}: {limit.kind} at t={limit.t:.3f} s: {limit.message}")
            continue
        found.append((f"duration_{policy}", result.duration))
        if best is None or result.duration < best[0].duration:
            best = (result, policy, search.figures())
    if best is None:
        return kept("; ".join(reasons), None, figures)
    result, policy, figures = best
    figures = (*figures, ("policy", float(POLICIES.index(policy))), *found)
    if result.duration >= plan.duration - 1e-9:
        why = f"not shorter ({result.duration:.2f} s >= {plan.duration:.2f} s)"
        return kept(why, result.duration, figures)
    return Schedule(
        result, True, plan.duration, result.duration, "assigned", "", sweep.checks, figures
    )


__all__ = [
    "POLICIES",
    "TIE",
    "Assignment",
    "AssignmentOptions",
    "MovePlanner",
    "PlannedMove",
    "Stand",
    "schedule_assigned",
]
