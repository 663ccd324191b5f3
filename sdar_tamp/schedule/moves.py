"""The object moves of a synchronous plan and the order they must keep.

A move is one object carried from the pose where it is grasped to the pose where it is released
(its start, a buffer or its goal), as the synchronous plan does it (replayed by
:class:`~sdar_tamp.schedule.sweep.WorldSweep`). What any execution of those moves must keep:

* the moves of one object in their order (``previous``);
* a move's release only after every object resting under the released object's footprint has
  been lifted (``blockers``: the moves that lift them, read off the synchronous plan: the
  earlier grasps of objects whose pose overlaps the release pose).

Which arm carries an object, and when, is left open: :mod:`.assignment` decides it. A plan
whose blockers form a cycle (objects rotated by several arms at once, no buffer) has no such
order of whole moves: :func:`break_cycles` sends one object of each cycle through a buffer
(a free pose the caller finds), which :mod:`.assignment` needs, since it commits whole moves.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import NoReturn

import numpy as np

from sdar_tamp.errors import SdarError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.schedule.sweep import TimedEvent, WorldSweep
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Instance

Pose = tuple[float, float, float]  #: (x [m], y [m], yaw [rad]) on the table


class CyclicMoves(SdarError):
    """The plan's moves have no order in which each is done whole (a rotation of objects)."""


@dataclass(frozen=True)
class Move:
    """Object ``obj`` carried from ``start`` to ``end`` (poses on the table); ``index``: its
    name (the synchronous plan's moves are numbered in the order of their grasps). ``arm``: the arm
    (scene order) that carries it in the synchronous plan, at ``sync_t`` [s] (its grasp);
    ``previous``: the object's move before (index), if any; ``blockers``: the moves whose grasp
    must come before this move's release; ``placed_after``: the moves whose release must come
    before it (objects put down near the release pose first in the synchronous plan)."""

    index: int
    obj: str
    start: Pose
    end: Pose
    arm: int
    sync_t: float
    previous: int | None
    blockers: tuple[int, ...]
    placed_after: tuple[int, ...] = ()


def plan_moves(
    plan: PlanFile, instance: Instance, sweep: WorldSweep, margin: float = 0.0
) -> tuple[Move, ...]:
    """The moves of the synchronous ``plan`` of ``instance`` (assumed valid), in the order of
    their grasps there. ``margin`` [m]: an earlier lift is a blocker also when its pose is
    this close to the release pose, and an earlier release this close comes first
    (``placed_after``): the fingers need room beside an object to grasp or release it.
    The blockers may form cycles (:func:`stuck_moves`, :func:`break_cycles`)."""
    sweep.reset([])
    sizes = {o.name: np.array(o.size[:2]) for o in instance.objects}
    names = plan.arm_names
    open_moves: dict[str, tuple[int, Pose, int, float]] = {}  # object -> grasp's move data
    last: dict[str, int] = {}
    lifted: list[tuple[int, str, Pose]] = []  # (move, object, pose it was lifted from)
    placed: list[tuple[int, str, Pose]] = []  # (move, object, pose it was released at)
    moves: list[Move] = []
    for e in plan.events:
        row = int(np.argmin(np.abs(plan.t - e.t)))
        q_arm = plan.q[row, plan.layout.slice(names.index(e.arm))]
        if e.type == "grasp":
            pose = sweep.rest[e.object]
            index = len(moves) + len(open_moves)
            open_moves[e.object] = (index, pose, names.index(e.arm), e.t)
            lifted.append((index, e.object, pose))
        sweep.apply(TimedEvent(row, e, q_arm), check=False)
        if e.type == "release":
            index, start, arm, t = open_moves.pop(e.object)
            end = sweep.rest[e.object]
            here = corners(np.array([end]), sizes[e.object] + 2.0 * margin)
            blockers = tuple(
                m
                for m, name, pose in lifted
                if name != e.object
                and overlap_matrix(here, corners(np.array([pose]), sizes[name]))[0, 0]
            )
            near = corners(np.array([end]), sizes[e.object] + 2.0 * margin)
            placed_after = tuple(
                m
                for m, name, pose in placed
                if name != e.object
                and overlap_matrix(near, corners(np.array([pose]), sizes[name]))[0, 0]
            )
            moves.append(
                Move(
                    index, e.object, start, end, arm, t, last.get(e.object), blockers, placed_after
                )
            )
            placed.append((index, e.object, end))
            last[e.object] = index
    sweep.reset([])
    moves.sort(key=lambda m: m.index)
    return tuple(moves)


def _dependencies(m: Move) -> set[int]:
    return {*m.blockers, *m.placed_after, *(() if m.previous is None else (m.previous,))}


def stuck_moves(moves: Sequence[Move]) -> list[int]:
    """The moves (indices) that no order reaches: on a cycle of ``previous`` and ``blockers``
    or after one (Kahn's algorithm); empty when the moves have an order."""
    after = {m.index: _dependencies(m) for m in moves}
    done: set[int] = set()
    while True:
        free = [i for i, deps in after.items() if i not in done and deps <= done]
        if not free:
            return sorted(i for i in after if i not in done)
        done.update(free)


def _refuse(moves: Sequence[Move], stuck: list[int]) -> NoReturn:
    by_index = {m.index: m for m in moves}
    objects = sorted({by_index[i].obj for i in stuck})
    raise CyclicMoves(
        f"the moves of {', '.join(objects)} wait for each other (a rotation without "
        "a buffer) and no buffer is found: no order of whole moves"
    )


def _cycle(moves: Sequence[Move], stuck: list[int]) -> list[Move]:
    """A cycle among the ``stuck`` moves: each member's place waits for the next one's lift
    (or the next is its object's previous move)."""
    by_index = {m.index: m for m in moves}
    inside = set(stuck)
    path: list[int] = [stuck[0]]
    while True:
        nxt = min(d for d in _dependencies(by_index[path[-1]]) if d in inside)
        if nxt in path:
            return [by_index[i] for i in path[path.index(nxt) :]]
        path.append(nxt)


def break_cycles(
    moves: Sequence[Move], buffer: Callable[[Move, Sequence[Move]], Pose | None]
) -> tuple[Move, ...]:
    """``moves`` with every rotation broken by a buffer: on each cycle, the member first
    grasped in the synchronous plan whose place waits for another member's lift is split into
    a move to ``buffer(member, moves)`` (a free pose: no blockers) and a move from there to
    its end (its blockers and ``placed_after``). Raises :class:`CyclicMoves` when ``buffer``
    finds no pose."""
    out = list(moves)
    while stuck := stuck_moves(out):
        cycle = _cycle(out, stuck)
        members = [
            m
            for k, m in enumerate(cycle)
            if cycle[(k + 1) % len(cycle)].index in (*m.blockers, *m.placed_after)
        ]
        m = min(members or cycle, key=lambda x: (x.sync_t, x.index))
        pose = buffer(m, out) if members else None
        if pose is None:
            _refuse(out, stuck)
        later = len(out)
        first = dataclasses.replace(m, end=pose, blockers=(), placed_after=())
        second = Move(
            later, m.obj, pose, m.end, m.arm, m.sync_t, m.index, m.blockers, m.placed_after
        )
        out = [
            first
            if x is m
            else dataclasses.replace(x, previous=later)
            if x.previous == m.index
            else x
            for x in out
        ]
        out.append(second)
    return tuple(out)


__all__ = ["CyclicMoves", "Move", "Pose", "break_cycles", "plan_moves", "stuck_moves"]
