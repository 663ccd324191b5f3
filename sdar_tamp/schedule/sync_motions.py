"""The synchronous plan's own motions, offered first to the assignment of moves.

The synchronous plan proved each of its motions collision-free against the static world and
the other arms at the synchronous times. When the assignment (:mod:`.assignment`) gives a
move to the arm that carried it in the synchronous plan, and that arm stands on the path the
plan took to it (where the plan had it after its previous gripper event, or anywhere further
along that path, e.g. at the pre-grasp it retreated to), the plan's own path is the first
option: the reach (from that point of the path to the grasp) and the carry (grasp to
release), with the plan's grasp. :class:`SeededPlanner` wraps any
:class:`~.move_records.MovePlanner` and yields that option before the wrapped planner's: no
motion planning is spent on it, and the path is the one the plan shaped (the sweep still times
it against the other arms' committed trajectories and the objects where they rest then, as any
other option). A move split through a buffer (:func:`~.moves.break_cycles`), or carried by
another arm, has no such option.

The arm then stands at the release configuration; its pre-grasp is the configuration where
the plan's last rest-to-rest motion into the release began (the approach), and the way back
out is that approach backwards.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.schedule.move_records import MovePlanner, PlannedMove, Stand
from sdar_tamp.schedule.moves import Move, Pose
from sdar_tamp.schedule.pieces import STEP_TOL
from sdar_tamp.world.transforms import FloatArray

#: [rad] an arm stands on a path when it is this close (every joint) to one of its samples
ON_PATH = 1e-6


@dataclass(frozen=True)
class SyncMove:
    """A move as the synchronous plan made it: ``reach`` (times ``(m,)`` [s], configurations
    ``(m, k)``) from the arm's previous gripper event (or the plan's start) to the grasp,
    ``carry`` from the grasp to the release, the grasp ``T_tcp_object`` and where the arm then
    stands (``end``)."""

    reach: tuple[FloatArray, FloatArray]
    carry: tuple[FloatArray, FloatArray]
    T_tcp_object: FloatArray
    end: Stand

    def from_stand(self, q: FloatArray) -> PlannedMove | None:
        """The planned move from configuration ``q`` when the arm stands on the reach (its
        last sample that close), else None."""
        t, path = self.reach
        near = np.flatnonzero(np.abs(path - q).max(axis=1) <= ON_PATH)
        if not len(near):
            return None
        i = int(near[-1])
        if i == len(path) - 1:  # at the grasp already: a still reach
            i = len(path) - 2
        reach = (t[i:] - t[i], np.array(path[i:]))
        return PlannedMove(reach, self.carry, self.T_tcp_object, self.end)


def _last_rest(t: FloatArray, q: FloatArray) -> int | None:
    """The last sample inside ``q`` ``(m, k)`` at ``t`` where a rest-to-rest motion begins
    (the sampling step changes there, :mod:`.pieces`) and from which the arm moves on; None
    when there is none."""
    h = np.diff(t)
    change = np.flatnonzero(np.abs(np.diff(h)) > STEP_TOL) + 1
    for k in change[::-1]:
        if np.abs(q[-1] - q[int(k)]).max() > ON_PATH:
            return int(k)
    return None


def sync_moves(plan: PlanFile, moves: Sequence[Move], made: Sequence[Move]) -> dict[int, SyncMove]:
    """The synchronous motions of ``moves`` (by index), those of them that ``made`` (the
    moves read off ``plan``, :func:`~.moves.plan_moves`) holds unchanged: same object, start
    and end (a move split through a buffer is not)."""
    original = {m.index: m for m in made}
    names = plan.arm_names
    out: dict[int, SyncMove] = {}
    for m in moves:
        o = original.get(m.index)
        if o is None or (o.obj, o.start, o.end, o.arm) != (m.obj, m.start, m.end, m.arm):
            continue
        arm = names[m.arm]
        mine = [e for e in plan.events if e.arm == arm]
        k = next(
            (
                k
                for k, e in enumerate(mine)
                if e.type == "grasp" and e.object == m.obj and abs(e.t - m.sync_t) < 1e-9
            ),
            None,
        )
        if k is None or k + 1 >= len(mine):
            continue
        grasp, release = mine[k], mine[k + 1]
        if release.type != "release" or release.object != m.obj:
            continue
        rows = [int(np.argmin(np.abs(plan.t - e.t))) for e in (grasp, release)]
        first = 0 if k == 0 else int(np.argmin(np.abs(plan.t - mine[k - 1].t)))
        g, r = rows
        if not first < g < r:
            continue
        q = plan.q[:, plan.layout.slice(m.arm)]
        carry = (plan.t[g : r + 1] - plan.t[g], np.array(q[g : r + 1]))
        reach = (plan.t[first : g + 1] - plan.t[first], np.array(q[first : g + 1]))
        pre = _last_rest(*carry)
        end = (
            Stand(np.array(q[r]))
            if pre is None
            else Stand(np.array(q[r]), np.array(carry[1][pre]), carry[1][pre:][::-1].copy())
        )
        out[m.index] = SyncMove(reach, carry, np.array(grasp.T_tcp_object), end)
    return out


class SeededPlanner:
    """``planner`` with the synchronous plan's own motion of a move (``motions``, by move
    index) offered first when the move's synchronous arm stands on its path (see the module
    docstring); everything else is ``planner``'s. ``offered``: the options given (by
    identity)."""

    def __init__(self, planner: MovePlanner, motions: Mapping[int, SyncMove]) -> None:
        self.planner, self.motions = planner, motions
        self.offered: set[int] = set()

    def estimate(self, arm: int, stand: Stand, move: Move) -> float | None:
        return self.planner.estimate(arm, stand, move)

    def plan(
        self,
        arm: int,
        stand: Stand,
        move: Move,
        resting: Mapping[str, Pose],
        others: Sequence[FloatArray] | None = None,
    ) -> Iterator[PlannedMove]:
        sync = self.motions.get(move.index)
        if sync is not None and arm == move.arm:
            own = sync.from_stand(stand.q)
            if own is not None:
                self.offered.add(id(own))
                yield own
        yield from self.planner.plan(arm, stand, move, resting, others)

    def buffer(self, move: Move, moves: Sequence[Move]) -> Pose | None:
        return self.planner.buffer(move, moves)

    def park(
        self, arm: int, stand: Stand, resting: Mapping[str, Pose], others: Sequence[FloatArray]
    ) -> tuple[FloatArray, FloatArray] | None:
        return self.planner.park(arm, stand, resting, others)


__all__ = ["ON_PATH", "SeededPlanner", "SyncMove", "sync_moves"]
