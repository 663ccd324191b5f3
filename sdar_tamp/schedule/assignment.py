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
   :data:`TIE` of each other. The ``candidates`` best are tried in turn.
3. The move's single-arm motions (free arm -> grasp, grasp -> release, each with the retreat
   and approach of a grasp) come from the planner (:meth:`MovePlanner.plan`: the motion
   planner against the static world of resting objects, the other arms at home), re-timed for
   the arm alone by the time-optimal path timing, and are committed at the earliest start
   whose replay (:mod:`.sweep`) is clear of every arm's committed, time-parameterised
   trajectory, the table and the objects where they rest then (an arm whose timeline has ended
   stands where it ends), after the dependencies: the object's previous release and the
   blockers' grasps, a dwell before; when the arm, holding the object, would stand in another
   arm's way before the carry can start, the grasp is moved later. A planned path that never
   clears within ``max_wait`` is dropped for the planner's next one, then for the next move.
   When none of the ``candidates`` goes, the other arms standing in the workspace where their
   timelines end go home and the best move is tried once more.
4. An arm that finds no move to take goes to its home configuration (out of the workspace)
   when it is not there, else waits until the next arm's timeline ends (the next event).
   When every arm has come to one time, the arms still in the workspace go home; when every
   arm is home and no move can be committed, there is no schedule
   (:class:`~sdar_tamp.schedule.scheduler.NoPlacement`); the caller keeps another one.

A move is committed whole (grasp and release together), so no arm ever holds an object while
it waits for another arm: the only order is the moves' own, which the synchronous plan proves
acyclic once every rotation without a buffer (objects that trade places, all held at once) has
one object sent through a buffer (:func:`~.moves.break_cycles`, :meth:`MovePlanner.buffer`).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sdar_tamp.plan_file import PlanEvent, PlanFile
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.schedule.moves import CyclicMoves, Move, Pose, break_cycles, plan_moves
from sdar_tamp.schedule.pieces import Block
from sdar_tamp.schedule.retiming import ArmRetimer
from sdar_tamp.schedule.scheduler import (
    Entry,
    NoPlacement,
    Placement,
    Schedule,
    ScheduleOptions,
    retimer,
)
from sdar_tamp.schedule.sweep import WorldSweep
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

#: [s] two moves whose estimated finishing times are this close count as equal (the
#: synchronous plan's arm is preferred then)
TIE = 0.05
#: [m] the room beside an object that fingers need to grasp or release it: moves whose poses
#: come this close keep their synchronous order (:func:`~sdar_tamp.schedule.moves.plan_moves`)
FINGER_ROOM = 0.03
#: starts tried for a move's grasp when the carry after it finds none
REGRASPS = 3


@dataclass(frozen=True)
class Stand:
    """Where an arm stands: ``q`` ``(k,)`` [rad] and, when it stands at a grasp or release
    configuration, ``pre`` ``(k,)`` (the pre-grasp it must retreat through), else None."""

    q: FloatArray
    pre: FloatArray | None = None


@dataclass(frozen=True)
class PlannedMove:
    """One arm's motions of a move: ``reach`` (from where it stands to the grasp) and
    ``carry`` (grasp to release), each as times ``(m,)`` [s] and configurations ``(m, k)``
    [rad]; ``T_tcp_object`` ``(4, 4)``: the grasp; ``end``: where the arm then stands."""

    reach: tuple[FloatArray, FloatArray]
    carry: tuple[FloatArray, FloatArray]
    T_tcp_object: FloatArray
    end: Stand


class MovePlanner(Protocol):
    """Grasps, inverse kinematics and single-arm motions of a cell (the streams)."""

    def estimate(self, arm: int, stand: Stand, move: Move) -> float | None:
        """Estimated duration [s] of ``move`` by arm ``arm`` (scene order) from ``stand``,
        motions only; None when the arm cannot grasp the object at both poses."""
        ...

    def plan(
        self, arm: int, stand: Stand, move: Move, resting: Mapping[str, Pose]
    ) -> Iterator[PlannedMove]:
        """The arm's motions for ``move``, best first, against the objects ``resting``
        (name -> pose; the moved object at its start)."""
        ...

    def buffer(self, move: Move, moves: Sequence[Move]) -> Pose | None:
        """A free pose for ``move``'s object, clear of every pose of ``moves``, or None."""
        ...

    def park(
        self, arm: int, stand: Stand, resting: Mapping[str, Pose], others: Sequence[FloatArray]
    ) -> tuple[FloatArray, FloatArray] | None:
        """The arm's motion (times ``(m,)``, configurations ``(m, k)``) from ``stand`` to its
        home configuration, the other arms standing at ``others`` (per arm, scene order; the
        arm's own entry is ignored), or None."""
        ...


@dataclass(frozen=True)
class AssignmentOptions:
    """``candidates``: the ready moves tried per decision (best estimate first); ``stride``:
    ticks between the starts tried for a motion (a wait is rounded up to it); ``max_wait``
    [s]: the longest wait tried before a motion (past it the arm does something else);
    ``max_checks``: the collision queries of the whole search (past them no schedule);
    ``max_plans``: motion-planner calls of the whole search."""

    candidates: int = 3
    stride: int = 5
    max_wait: float = 4.0
    max_checks: int = 400_000
    max_plans: int = 400


class Assignment(Placement):
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
    ) -> None:
        super().__init__(plan, [[] for _ in plan.arms], sweep, options, "objects")
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
            if self.sweep.checks >= self.options.max_checks or self.plans >= self.options.max_plans:
                raise NoPlacement(_no_block(0), None, "out of collision checks or motion plans")
            arm = min(self.arms, key=lambda a: (self.horizon(a), a))
            ranked = self.rank(arm, [m for m in pending if self.ready_move(m)])
            done = next((m for m in ranked[: self.options.candidates] if self.take(arm, m)), None)
            if done is None and ranked and self.clear_way(arm):
                done = next((m for m in ranked[:1] if self.take(arm, m)), None)
            if done is not None:
                pending.remove(done)
            elif not self.parked[arm] and self.park(arm):
                continue
            else:
                self.wait(arm)
        return self.assemble()

    def rank(self, arm: int, ready: list[Move]) -> list[Move]:
        """``ready`` moves the arm can do, by estimated finishing time (ties: the arm's own)."""
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
            scored.append((round(finish / TIE), m.arm != arm, m.index, m))
        scored.sort(key=lambda s: s[:3])
        return [s[3] for s in scored]

    def take(self, arm: int, m: Move) -> bool:
        """Plan and commit ``m`` by ``arm``; False when no planned path can be committed."""
        resting = {o: p for o, p in self.rest.items() if o != m.obj}
        resting[m.obj] = m.start
        name = self.plan.arm_names[arm]
        timer = self.retimers[arm]
        started = time.perf_counter()
        options = self.planner.plan(arm, self.stand[arm], m, resting)
        try:
            for planned in options:
                self.plans += 1
                leaving = self.stand[arm].pre is not None
                reach = timer.retime(*planned.reach, leaving, True)
                carry = timer.retime(*planned.carry, True, True)
                grasp = PlanEvent(0.0, name, "grasp", m.obj, planned.T_tcp_object)
                release = PlanEvent(0.0, name, "release", m.obj, planned.T_tcp_object)
                self.move_of[id(grasp)] = self.move_of[id(release)] = m
                if not self.commit_move(arm, (reach, grasp), (carry, release)):
                    continue
                self.grasp_tick[m.index] = self.tick_of(grasp)
                self.release_tick[m.index] = self.tick_of(release)
                self.carrier[m.index] = arm
                self.rest[m.obj] = m.end
                self.stand[arm] = planned.end
                self.parked[arm] = False
                return True
        finally:
            self.planning_time += time.perf_counter() - started
        return False

    def tick_of(self, event: PlanEvent) -> int:
        """The tick of a committed event (by identity)."""
        return next(e.tick for e in self.events if e.event is event)

    def commit_move(
        self, arm: int, reach: tuple[FloatArray, PlanEvent], carry: tuple[FloatArray, PlanEvent]
    ) -> bool:
        """Commit the reach (ending in the grasp), then the carry (ending in the release);
        when the carry finds no start because the arm, holding the object, stands in another
        arm's way, the grasp is tried later (up to :data:`REGRASPS` times). False: nothing
        committed."""
        self.not_before = 0
        try:
            for _ in range(REGRASPS):
                mark = self.mark()
                try:
                    self.place([Entry(arm, _block(arm, reach[0], reach[1]), reach[0], 0)])
                except NoPlacement:
                    self.undo(mark)
                    return False
                try:
                    self.place([Entry(arm, _block(arm, carry[0], carry[1]), carry[0], 0)])
                except NoPlacement as exc:
                    grasped = self.tick_of(reach[1])
                    self.undo(mark)
                    if (
                        exc.conflict is None
                        or exc.conflict.tick < grasped
                        or not exc.conflict.message.startswith("arms ")
                    ):
                        return False  # not another arm in the way: a later grasp is no better
                    start = grasped - (len(reach[0]) - 1)
                    self.not_before = max(start + 1, exc.conflict.tick - len(reach[0]) + 2)
                    continue
                return True
            return False
        finally:
            self.not_before = 0

    def clear_way(self, arm: int) -> bool:
        """Send home the other arms that stand in the workspace where their timelines end
        (they stand in the way of every motion after that); whether any went."""
        return sum(self.park(a) for a in self.arms if a != arm and not self.parked[a]) > 0

    def park(self, arm: int) -> bool:
        """Send ``arm`` home from where it stands; False when that cannot be committed."""
        ends = [np.array(self.traj[a][-1]) for a in self.arms]
        motion = self.planner.park(arm, self.stand[arm], self.rest, ends)
        self.plans += 1
        if motion is None:
            return False
        q = self.retimers[arm].retime(*motion, self.stand[arm].pre is not None, False)
        mark = self.mark()
        try:
            self.place([Entry(arm, _block(arm, q, None), q, 0)])
        except NoPlacement:
            self.undo(mark)
            return False
        self.stand[arm] = Stand(np.array(q[-1]))
        self.parked[arm] = True
        self.parks += 1
        return True

    def wait(self, arm: int) -> None:
        """Let ``arm`` stand until the next arm's timeline ends; raises :class:`NoPlacement`
        when no arm's ends later (every arm waits: no move can be committed)."""
        h = self.horizon(arm)
        later = [self.horizon(a) for a in self.arms if self.horizon(a) > h]
        if not later:
            # every arm is at the same time: one that stands in the workspace goes home
            if any(self.park(a) for a in self.arms if not self.parked[a]):
                return
            raise NoPlacement(_no_block(arm), None, "every arm waits and no move can be committed")
        self.traj[arm].extend([self.traj[arm][-1]] * (min(later) - h))
        self.waits += 1

    def figures(self) -> tuple[tuple[str, float], ...]:
        """Moves committed and how many went to another arm than in the synchronous plan,
        motion plans made and their time [s], waits for the next event, trips home."""
        moved = {m.index: m.arm for m in self.moves}
        return (
            ("moves", float(len(self.carrier))),
            ("reassigned", float(sum(a != moved[i] for i, a in self.carrier.items()))),
            ("motion_plans", float(self.plans)),
            ("planning_time", self.planning_time),
            ("waits", float(self.waits)),
            ("parks", float(self.parks)),
        )


def _block(arm: int, q: FloatArray, event: PlanEvent | None) -> Block:
    return Block(arm, q, q, event, 0.0, 0.0, 0, None)


def _no_block(arm: int) -> Block:
    return Block(arm, np.zeros((1, 1)), np.zeros((1, 1)), None, 0.0, 0.0, 0, None)


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
        moves = break_cycles(plan_moves(plan, instance, sweep, margin), planner.buffer)
    except CyclicMoves as exc:
        return kept(str(exc), None)
    retimers = [retimer(scene, i, options) for i in range(len(scene.arms))]
    limited = dataclasses.replace(
        options, max_checks=assignment.max_checks, max_wait=assignment.max_wait
    )
    search = Assignment(plan, sweep, limited, moves, planner, retimers, assignment)
    try:
        result = search.run()
    except NoPlacement as exc:
        return kept(str(exc), None, search.figures())
    figures = search.figures()
    result = dataclasses.replace(result, metrics=result.metrics.updated({"execution": "assigned"}))
    limit = check_timeline(result, scene, options.dwell)
    if limit is not None:  # by construction this does not happen
        return kept(f"{limit.kind} at t={limit.t:.3f} s: {limit.message}", None, figures)
    if result.duration >= plan.duration - 1e-9:
        why = f"not shorter ({result.duration:.2f} s >= {plan.duration:.2f} s)"
        return kept(why, result.duration, figures)
    return Schedule(
        result, True, plan.duration, result.duration, "assigned", "", sweep.checks, figures
    )


__all__ = [
    "TIE",
    "Assignment",
    "AssignmentOptions",
    "MovePlanner",
    "PlannedMove",
    "Stand",
    "schedule_assigned",
]
