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

An arm whose own next move is not ready yet may go ahead along that move's reach to its
pre-grasp and wait there (:meth:`SyncMove.to_pre_grasp`); an arm in the way of another's
move goes ahead along its reach to where the plan had it when that move released its object
(:meth:`SyncMove.until`): either way it leaves the spot it let go of, as in the plan.

The arm then stands at the release configuration; its pre-grasp is the configuration where
the plan's last rest-to-rest motion into the release began (the approach: a rest point of
the path within :data:`APPROACH` of the release), and the way back out is that approach
backwards. A plan whose carry is one smooth motion into the release has no such point: the
arm's next motion (the plan's next reach, which leaves the spot as the plan did) leaves it.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.schedule.move_records import MovePlanner, PlannedMove, Stand
from sdar_tamp.schedule.moves import Move, Pose
from sdar_tamp.world.transforms import FloatArray

#: [rad] an arm stands on a path when it is this close (every joint) to one of its samples
ON_PATH = 1e-6
#: a sample where the arm's steps on both sides are under this share of its largest step
#: is a rest point of the path
SLOW = 0.02
#: [rad] the least path (summed largest joint steps) after a rest point taken for a
#: pre-grasp (the slow straight end of an approach is shorter)
REST_TRAVEL = 0.06
#: [rad] a pre-grasp is this close to the grasp (every joint); a path without a rest point
#: that close (one smooth motion into the grasp) has none
APPROACH = 0.5


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
    t0: float = 0.0  #: [s] when the reach began in the plan

    @property
    def released(self) -> float:
        """When the plan released the object [s]."""
        return self.t0 + float(self.reach[0][-1] + self.carry[0][-1])

    def until(self, q: FloatArray, t: float) -> tuple[FloatArray, FloatArray] | None:
        """The reach from configuration ``q`` on it up to where the plan had the arm at time
        ``t`` [s] (at most the sample before the grasp), or None when the arm stands there
        already or not on the reach."""
        planned = self.from_stand(q)
        if planned is None:
            return None
        times, path = planned.reach
        start = self.t0 + float(self.reach[0][-1] - times[-1])  # when the plan had it at q
        j = min(int(np.searchsorted(times, t - start, side="right")) - 1, len(path) - 2)
        if j <= 0:
            return None
        return times[: j + 1], np.array(path[: j + 1])

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

    def to_pre_grasp(self, q: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """The reach from configuration ``q`` on it up to the pre-grasp (where the plan's last
        rest-to-rest motion into the grasp began), or None when the arm does not stand on the
        reach before that point."""
        planned = self.from_stand(q)
        if planned is None:
            return None
        t, path = planned.reach
        k = _last_rest(t, path)
        if k is None or k == 0:
            return None
        return t[: k + 1], np.array(path[: k + 1])


def _last_rest(t: FloatArray, q: FloatArray) -> int | None:
    """The last sample inside ``q`` ``(m, k)`` (times ``t``) where the arm comes to rest
    (its steps on both sides under :data:`SLOW` of its largest, a local minimum) with more
    than :data:`REST_TRAVEL` [rad] of its path still ahead: where its last rest-to-rest motion
    into the end began; None when there is none."""
    steps = np.abs(np.diff(q, axis=0)).max(axis=1)
    peak = float(steps.max(initial=0.0))
    ahead = np.cumsum(steps[::-1])[::-1]  # path left from each sample
    for k in range(len(q) - 2, 0, -1):
        if ahead[k] <= REST_TRAVEL:
            continue
        if np.abs(q[-1] - q[k]).max() > APPROACH:
            return None
        around = steps[k - 1] + steps[k]
        if (
            max(steps[k - 1], steps[k]) <= SLOW * peak
            and around <= (steps[k - 2] + steps[k - 1] if k >= 2 else np.inf)
            and around <= steps[k] + steps[k + 1]
        ):
            return k
    return None


def _moving(q: FloatArray) -> FloatArray:
    """The rows of ``q`` ``(m, k)`` without those equal to the one before (the arm still)."""
    keep = np.concatenate([[True], np.abs(np.diff(q, axis=0)).max(axis=1) > 0.0])
    return np.array(q[keep])


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
            Stand(np.array(q[r]), event=True)
            if pre is None
            else Stand(np.array(q[r]), np.array(carry[1][pre]), _moving(carry[1][pre:][::-1]))
        )
        t0 = float(plan.t[first])
        out[m.index] = SyncMove(reach, carry, np.array(grasp.T_tcp_object), end, t0)
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


__all__ = ["APPROACH", "ON_PATH", "REST_TRAVEL", "SLOW", "SeededPlanner", "SyncMove", "sync_moves"]
