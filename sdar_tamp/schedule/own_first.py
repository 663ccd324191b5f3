"""The assignment's ``own-first`` policy: keep the synchronous plan's tasks, give a task to an
idle arm only where that ends it earlier.

The free arm (:mod:`.assignment`, step 1) takes its own next move, the first of the moves the
synchronous plan gave it that is not committed yet, when that move is ready: with the plan's
own motions (:mod:`.sync_motions`) the arms then run the plan's tasks, each on its own
timeline, without the synchronous steps; when that move is not ready, it waits for the next
event. When it has no move of its own left (an arm the plan left idle, or one done with its
share), it may take another arm's ready move, a whole task planned for it against the others'
committed trajectories as any other move: only a move it would finish earlier than its owner
by :data:`STEAL_GAIN` or more. The owner finishes the move after
its own moves before it, each taking as long as in the synchronous plan (from the owner's
previous release to the move's release; :func:`sync_spans`), from where the owner's timeline
ends; the free arm finishes it after its rest-to-rest estimate (:meth:`MovePlanner.estimate`,
collisions ignored, so stretched by :data:`STEAL_STRETCH`) and two dwells, from where its own
timeline ends or when the move's dependencies allow. The candidates are those moves, earliest
finish first; none: the free arm waits for the next event (or retreats).

:func:`free_arm` chooses the free arm among those whose timelines end first;
:func:`advance` and :func:`go_ahead` move an arm (or the arms in another's way) along its own
next move's synchronous reach, as the plan had it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Protocol

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.schedule.move_records import MovePlanner, Stand
from sdar_tamp.schedule.moves import Move
from sdar_tamp.schedule.retiming import ArmRetimer
from sdar_tamp.schedule.sync_motions import SyncMove
from sdar_tamp.world.transforms import FloatArray

#: [s] a move goes to another arm than its own only when that ends it this much earlier
STEAL_GAIN = 0.5
#: the rest-to-rest estimate of a move by another arm, stretched by this (paths are not
#: straight in joint space; approaches are slow)
STEAL_STRETCH = 1.5


class Search(Protocol):
    """What the policy reads of the search (:class:`~.assignment.Assignment`)."""

    tick: float
    dwell: int
    planner: MovePlanner
    stand: list[Stand]
    carrier: dict[int, int]
    moves: tuple[Move, ...]
    spans: dict[int, float]
    estimated: dict[int, int]

    def horizon(self, arm: int) -> int: ...

    def bound(self, m: Move) -> tuple[int, int]: ...


class Advancing(Search, Protocol):
    """What :func:`free_arm`, :func:`advance` and :func:`go_ahead` read and do."""

    arms: range
    retimers: list[ArmRetimer]

    def rank(self, arm: int, ready: list[Move], policy: str | None = None) -> list[Move]: ...

    def blocking(self, arm: int) -> list[int]: ...

    def _commit(self, arm: int, q: FloatArray) -> bool: ...


def sync_spans(plan: PlanFile, moves: Sequence[Move]) -> dict[int, float]:
    """Per move (index): how long its synchronous arm took for it in ``plan`` [s], from its
    previous release (or the plan's start) to the move's release (a move split through a
    buffer: each part the whole span)."""
    releases: dict[tuple[str, str], list[float]] = {}
    for e in plan.events:
        if e.type == "release":
            releases.setdefault((e.arm, e.object), []).append(e.t)
    out: dict[int, float] = {}
    names = plan.arm_names
    for m in moves:
        after = [t for t in releases.get((names[m.arm], m.obj), []) if t > m.sync_t]
        end = min(after, default=m.sync_t)
        before = [
            e.t for e in plan.events if e.arm == names[m.arm] and e.type == "release" and e.t < end
        ]
        out[m.index] = end - max(before, default=0.0)
    return out


def own_first(search: Search, arm: int, ready: list[Move]) -> list[Move]:
    """The candidates of the free ``arm`` among the ``ready`` moves (see the module
    docstring), best first."""
    pending = sorted(
        (m for m in search.moves if m.index not in search.carrier), key=lambda m: m.index
    )
    own = [m for m in pending if m.arm == arm]
    tick = search.tick
    dwell = search.dwell * tick
    h = search.horizon(arm) * tick
    if own:  # its own next move, when it is ready
        if not any(m is own[0] for m in ready):
            return []
        search.estimated[own[0].index] = math.ceil((h + search.spans.get(own[0].index, 0.0)) / tick)
        return [own[0]]
    scored: list[tuple[float, int, Move]] = []
    for m in ready:
        if m.arm == arm:
            continue
        owner = search.horizon(m.arm) * tick + sum(
            search.spans.get(x.index, 0.0) for x in pending if x.arm == m.arm and x.index <= m.index
        )
        est = search.planner.estimate(arm, search.stand[arm], m)
        if est is None:
            continue
        grasp, release = (k * tick for k in search.bound(m))
        finish = max(max(h, grasp) + STEAL_STRETCH * est + dwell, release) + dwell
        if finish + STEAL_GAIN <= owner:
            scored.append((finish, m.index, m))
            search.estimated[m.index] = math.ceil((finish - dwell) / tick)
    scored.sort(key=lambda s: s[:2])
    return [s[2] for s in scored]


def free_arm(search: Advancing, ready: list[Move]) -> tuple[int, list[Move]]:
    """Of the arms whose timelines end first, the first whose candidate is its own move,
    else the first that has any, with its ranked candidates; when every arm's timeline ends
    there and none has any, the first one's by the ``earliest`` policy."""
    first = sorted(search.arms, key=lambda a: (search.horizon(a), a))
    now = [
        (a, search.rank(a, ready)) for a in first if search.horizon(a) == search.horizon(first[0])
    ]
    own = [(a, r) for a, r in now if r and r[0].arm == a]
    some = [(a, r) for a, r in now if r]
    if own or some:
        return (own or some)[0]
    if len(now) < len(first):
        return first[0], now[0][1]
    return first[0], search.rank(first[0], ready, "earliest")  # none would move: any


def _next_own(search: Advancing, arm: int) -> SyncMove | None:
    """The synchronous motions of ``arm``'s own next move not committed yet (None: none)."""
    own = min((m for m in search.moves if m.arm == arm and m.index not in search.carrier),
              key=lambda m: m.index, default=None)  # fmt: skip
    motions: Mapping[int, SyncMove] = getattr(search.planner, "motions", {})
    return None if own is None else motions.get(own.index)


def advance(search: Advancing, arm: int, until: float | None = None) -> bool:
    """Move ``arm`` along its own next move's synchronous reach to the pre-grasp
    (:meth:`~.sync_motions.SyncMove.to_pre_grasp`), or to where the plan had it at time
    ``until`` [s] (:meth:`~.sync_motions.SyncMove.until`); whether it did."""
    sync = _next_own(search, arm)
    q = search.stand[arm].q
    if sync is None:
        return False
    path = sync.to_pre_grasp(q) if until is None else sync.until(q, until)
    if path is None:
        return False
    leaving = search.stand[arm].leaving
    return search._commit(arm, search.retimers[arm].retime(path[0], path[1], leaving, False))


def go_ahead(search: Advancing, arm: int) -> bool:
    """Let the other arms in the way (:meth:`~.room.Room.blocking`) go ahead along their own
    next move's reach to where the plan had them when ``arm``'s next move released its object
    (:func:`advance`); whether any did."""
    sync = _next_own(search, arm)
    if sync is None:
        return False
    return sum(advance(search, a, sync.released) for a in search.blocking(arm)) > 0


__all__ = [
    "STEAL_GAIN",
    "STEAL_STRETCH",
    "Advancing",
    "advance",
    "free_arm",
    "go_ahead",
    "own_first",
    "sync_spans",
]
