"""Arms that make room: an arm standing where its last move left it (at a grasp or release
configuration, in the workspace) is in the way of the others' motions. The assignment of moves
(:mod:`.assignment`) lets it retreat a few cm back out along its approach to the pre-grasp
(:meth:`Room.retreat`, cheap: a fraction of the way home), sends it home when that is not
enough (:meth:`Room.park`), or lets it wait for the next event (:meth:`Room.wait`). Only the
arms that a failed attempt met move (:meth:`Room.blocking`)."""

from __future__ import annotations

import numpy as np

from sdar_tamp.plan_file import PlanEvent
from sdar_tamp.schedule.move_records import MovePlanner, Stand
from sdar_tamp.schedule.moves import Pose
from sdar_tamp.schedule.pieces import Block
from sdar_tamp.schedule.retiming import ArmRetimer
from sdar_tamp.schedule.scheduler import Entry, NoPlacement, Placement
from sdar_tamp.schedule.sweep import Conflict
from sdar_tamp.world.transforms import FloatArray


class Room(Placement):
    """Where the arms stand (``stand``, ``parked``: at home) and the motions that make room;
    the state is set up by the subclass."""

    planner: MovePlanner
    retimers: list[ArmRetimer]
    stand: list[Stand]
    parked: list[bool]
    rest: dict[str, Pose]
    in_way: set[int]  # arms met by the failed attempts of the current decision
    plans: int
    waits: int
    parks: int
    retreats: int

    def note_in_way(self, arm: int, conflict: Conflict | None) -> None:
        """Remember the other arms that ``conflict`` names (they stood in ``arm``'s way)."""
        if conflict is not None:
            names = self.plan.arm_names
            self.in_way.update(a for a in self.arms if a != arm and names[a] in conflict.arms)

    def back_off(self, arm: int) -> bool:
        """Let the other arms in the way (:meth:`blocking`) that stand at a grasp or release
        configuration where their timelines end retreat to its pre-grasp (:meth:`retreat`);
        whether any did."""
        others = [a for a in self.blocking(arm) if self.stand[a].pre is not None]
        return sum(self.retreat(a) for a in others) > 0

    def retreat(self, arm: int) -> bool:
        """Move ``arm`` from the grasp or release configuration where it stands back out
        along its approach to the pre-grasp (a few cm off the object, out of the others'
        way), when the sweep lets it; False when it stands elsewhere or cannot go."""
        stand = self.stand[arm]
        if stand.pre is None:
            return False
        q_path = stand.back if stand.back is not None else np.linspace(stand.q, stand.pre, 9)
        q = self.retimers[arm].retime(rest_to_rest(q_path), q_path, True, False)
        if not self._commit(arm, q):
            return False
        self.retreats += 1
        return True

    def clear_way(self, arm: int) -> bool:
        """Send home the other arms in the way (:meth:`blocking`) that stand in the workspace
        where their timelines end (they stand in the way of every motion after that);
        whether any went."""
        return sum(self.park(a) for a in self.blocking(arm) if not self.parked[a]) > 0

    def blocking(self, arm: int) -> list[int]:
        """The other arms that the failed attempts of this decision met (every other arm
        when they met none)."""
        met = sorted(self.in_way)
        return met or [a for a in self.arms if a != arm]

    def park(self, arm: int) -> bool:
        """Send ``arm`` home from where it stands; False when that cannot be committed."""
        ends = [np.array(self.traj[a][-1]) for a in self.arms]
        motion = self.planner.park(arm, self.stand[arm], self.rest, ends)
        self.plans += 1
        if motion is None:
            return False
        q = self.retimers[arm].retime(*motion, self.stand[arm].pre is not None, False)
        if not self._commit(arm, q):
            return False
        self.parked[arm] = True
        self.parks += 1
        return True

    def _commit(self, arm: int, q: FloatArray) -> bool:
        """Commit ``arm``'s timed motion ``q`` where its timeline ends, the arm then standing at
        its last configuration; False (nothing committed) when it cannot be placed."""
        mark = self.mark()
        try:
            self.place([Entry(arm, block_of(arm, q), q, 0)])
        except NoPlacement:
            self.undo(mark)
            return False
        self.stand[arm] = Stand(np.array(q[-1]))
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
            raise NoPlacement(no_block(arm), None, "every arm waits and no move can be committed")
        self.traj[arm].extend([self.traj[arm][-1]] * (min(later) - h))
        self.waits += 1


def rest_to_rest(q: FloatArray) -> FloatArray:
    """Times ``(m,)`` [s] that play the path ``q`` ``(m, k)`` from rest to rest on a slow
    cosine profile of its length (at least 1 s, 4 s per radian of the largest joint step):
    the path's own timing (a stretch cut out of a motion) need not start or end at rest."""
    steps = np.abs(np.diff(q, axis=0)).max(axis=1)
    s = np.concatenate([[0.0], np.cumsum(steps)])
    total = float(s[-1])
    if total <= 0.0:
        return np.linspace(0.0, 1.0, len(q))
    duration = max(1.0, 4.0 * float(np.abs(q[-1] - q[0]).max()), 4.0 * total)
    return duration * np.arccos(np.clip(1.0 - 2.0 * s / total, -1.0, 1.0)) / np.pi


def block_of(arm: int, q: FloatArray, event: PlanEvent | None = None) -> Block:
    """A motion ``q`` of ``arm`` to place, ending in ``event`` when given."""
    return Block(arm, q, q, event, 0.0, 0.0, 0, None)


def no_block(arm: int) -> Block:
    """The block a :class:`NoPlacement` of the whole search names."""
    return Block(arm, np.zeros((1, 1)), np.zeros((1, 1)), None, 0.0, 0.0, 0, None)


__all__ = ["Room", "block_of", "no_block", "rest_to_rest"]
