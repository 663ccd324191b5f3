"""SDAR-M's grounding with more than two arms: what it checks in pairs and what it remembers.

:class:`KArmChecks` holds, for one run, the :class:`~solvers.sdar.failure_memo.FailureMemo` and
the pairwise checks of :mod:`~solvers.sdar.arm_pairs`, and answers the
:class:`~solvers.sdar.grounding.Grounder`'s three questions about a candidate step:

* :meth:`KArmChecks.skip`: is it known not to ground? Either no choice of grasps keeps its
  grippers clear of the other objects at their goals (a step of three goal moves or more;
  remembered without arms and without poses, since it depends on neither:
  :func:`~solvers.sdar.arm_pairs.grippers_can_clear`), or no assignment of arms grounded it
  at an earlier decision and no object near it has moved since (:meth:`KArmChecks.failed`
  remembers it, with :func:`~solvers.sdar.failure_memo.neighbourhood` within :data:`NEAR`).
* :meth:`KArmChecks.pairwise` / :meth:`KArmChecks.pair_table`: the options of a step of
  several moves checked in pairs of arms.

With one or two arms nothing here applies (every method answers as if it did not exist), so
their plans are those of the grounder alone.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Hashable, Mapping, Sequence

from solvers.sdar.arm_pairs import ArmPairs, Combine, PairTable, grippers_can_clear
from solvers.sdar.cache import StreamCache
from solvers.sdar.failure_memo import FailureMemo, neighbourhood
from solvers.sdar.move_option import Option
from solvers.sdar.options import SdarOptions
from solvers.sdar.tasks import Step

#: [m] Objects resting this close to a pose or a goal of a step belong to the world of its
#: remembered failure to ground (:meth:`KArmChecks.failed`).
NEAR = 0.2
NO_ARMS = "no assignment of arms grounds it"
NO_GRASPS = "no choice of grasps keeps every gripper clear of the other objects at their goals"


class KArmChecks:
    """Pairwise checks and remembered failures of one run (see the module docstring)."""

    def __init__(
        self,
        cache: StreamCache,
        options: SdarOptions,
        goals: Mapping[str, str],
        arms: int,
        combine: Combine,
    ) -> None:
        self.cache = cache
        self.options = options
        self.goals = goals
        self.arms = arms
        self.memo = FailureMemo()
        """Failures kept across assignments and decisions."""
        self.pairs = ArmPairs(combine, self.memo)
        self._located: dict[str, tuple[float, float] | None] = {}  # pose -> (x, y) on the plane

    def pairwise(self, step: Step) -> bool:
        """Options of ``step`` are checked in pairs: more than two arms, moves at once."""
        return self.arms > 2 and len(step.moves) > 1 and not self.options.one_arm_at_a_time

    def pair_table(
        self,
        step: Step,
        arms: tuple[str, ...],
        per_move: Sequence[Sequence[Option]],
        misses: Counter[str],
        stage: Hashable,
    ) -> PairTable | str | None:
        """For a step checked in pairs: the option pairs whose arms are clear, or why two of
        its arms meet whatever their options (counted in ``misses``); None otherwise."""
        if not self.pairwise(step):
            return None
        table = self.pairs.table(step, arms, per_move, self.cache.current_poses(), stage)
        if isinstance(table, str):
            misses[table] += 1
        return table

    def skip(self, step: Step) -> str | None:
        """Why ``step`` is known not to ground (see the module docstring), or None."""
        world = self.world(step)
        if world is not None:
            why = self.memo.recall(("step", step.moves), self.cache.current_poses())
            if why is not None:
                return f"{why} (remembered)"
        return None if self._grippers_can_clear(step) else NO_GRASPS

    def failed(self, step: Step) -> None:
        """No assignment of arms grounded ``step`` (none was blocked as tried before):
        remembered while the objects near it rest (for a step :meth:`world` covers)."""
        world = self.world(step)
        if world is not None:
            self.memo.remember(("step", step.moves), NO_ARMS, world)

    def world(self, step: Step) -> dict[str, str] | None:
        """With more than two arms and a plane, for a step of goal moves: what its failure to
        ground depends on (:func:`~solvers.sdar.failure_memo.neighbourhood` within
        :data:`NEAR`); None otherwise (such a failure is not remembered)."""
        plane = self.options.plane
        if self.arms <= 2 or plane is None or any(m.to_buffer for m in step.moves):
            return None
        value = self.cache.table.value

        def locate(pose: str) -> tuple[float, float] | None:
            if pose not in self._located:
                self._located[pose] = plane.locate(value(pose))
            return self._located[pose]

        return neighbourhood(step.objects, self.cache.current_poses(), self.goals, locate, NEAR)

    def _grippers_can_clear(self, step: Step) -> bool:
        """False when a step of three goal moves or more has no choice of grasps (of the first
        ``SdarOptions.grasps``, those its options come from) keeping its grippers clear of the
        other objects at their goals; remembered without arms and without poses."""
        voc, cache = self.cache.voc, self.cache
        if (
            self.arms <= 2
            or len(step.moves) < 3
            or any(m.to_buffer for m in step.moves)
            or voc.grasp_cfree not in cache.streams
        ):
            return True
        key = ("grippers", step.moves)
        if self.memo.recall(key, {}) is not None:
            return False
        targets = [(o, self.goals[o]) for o in step.objects]
        grasps = [
            [g for (g,) in cache.outputs(voc.grasp, (o,), self.options.grasps)]
            for o in step.objects
        ]
        if grippers_can_clear(targets, grasps, lambda *args: cache.test(voc.grasp_cfree, args)):
            return True
        self.memo.remember(key, NO_GRASPS, {})
        return False
