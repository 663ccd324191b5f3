"""Dead-end recovery: evict objects at their goals that crowd a remaining object.

When no candidate step works, an object already at its goal may be in the way of a remaining
one (no arm can grasp the remaining object where it rests, or at its goal, while it is there).
Such objects are sent to buffers (with the object they unblock when possible); they are not
brought back before the object they blocked is at its goal.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from solvers.sdar.budget import Deadline
from solvers.sdar.cache import StreamCache
from solvers.sdar.tasks import Move, Step, TaskView

if TYPE_CHECKING:
    from solvers.sdar.options import SdarOptions


class Recovery:
    """The evictions of a run: how many were executed, and which evicted object waits for
    which blocked one."""

    def __init__(
        self,
        cache: StreamCache,
        options: SdarOptions,
        goals: Mapping[str, str],
        arms: Sequence[str],
        deadline: Deadline,
    ) -> None:
        self.cache = cache
        self.options = options
        self.goals = goals
        self.arms = tuple(arms)
        self.deadline = deadline
        self.evictions = 0
        self.deferred: dict[str, str] = {}  # evicted object -> the object it blocked

    @property
    def budget_left(self) -> bool:
        """Fewer evictions so far than twice the number of objects."""
        return self.evictions < 2 * len(self.goals)

    def candidates(self, view: TaskView) -> list[Step]:
        """Objects at their goals whose absence would let a remaining object be grasped where
        it rests or at its goal (found by asking the IK stream without them), moved to a
        buffer, together with the object they unblock when possible."""
        steps: list[Step] = []
        current = self.cache.current_poses()
        for obj in view.remaining:
            if not self._reachable(obj, current[obj], frozenset()):
                pose, unblocks_goal = current[obj], False  # crowded where it rests
            elif not view.blockers(obj) and not self._reachable(
                obj, self.goals[obj], frozenset((obj,))
            ):
                pose, unblocks_goal = self.goals[obj], True  # crowded at its goal
            else:
                continue
            lifted = frozenset((obj,)) if unblocks_goal else frozenset()
            done = sorted(view.done)
            singles = [o for o in done if self._reachable(obj, pose, lifted | {o})]
            for other in singles:
                self.deferred[other] = obj
                if unblocks_goal:
                    steps.append(Step((Move(obj), Move(other, True)), "evict", 0))
                steps.append(Step((Move(other, True),), "evict", 1))
            if singles:
                continue
            for i, a in enumerate(done):  # boxed in from two sides: two objects make room
                if self.deadline.passed():
                    return steps
                for b in done[i + 1 :]:
                    if self._reachable(obj, pose, lifted | {a, b}):
                        self.deferred[a] = self.deferred[b] = obj
                        steps.append(Step((Move(a, True), Move(b, True)), "evict", 2))
        return steps

    def _reachable(self, obj: str, pose: str, lifted: frozenset[str]) -> bool:
        """Some arm grasps ``obj`` at ``pose`` with some grasp while ``lifted`` are away."""
        cache, voc = self.cache, self.cache.voc
        fluents = cache.fluents(voc.atpose, without=lifted)
        return any(
            cache.outputs(voc.ik, (arm, obj, pose, g), 1, fluents)
            for arm in self.arms
            for (g,) in cache.outputs(voc.grasp, (obj,), self.options.grasps)
        )

    def allowed(self, candidates: Sequence[Step]) -> list[Step]:
        """Candidates that do not bring an evicted object back before the one it blocked."""
        current = self.cache.current_poses()
        done = {o for o, g in self.goals.items() if current.get(o) == g}
        for other, obj in list(self.deferred.items()):
            if obj in done:
                del self.deferred[other]
        return [
            s
            for s in candidates
            if not any(not m.to_buffer and m.obj in self.deferred for m in s.moves)
        ] or list(candidates)
