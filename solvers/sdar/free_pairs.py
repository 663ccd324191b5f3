"""The grasps of a two-goal-move step that can work in any arrangement (the pair search).

Two grippers placing touching objects at once need a compatible pair of grasps, often two
grasps tilted away from each other. :class:`FreePairs` gives, per move, the grasps that
belong to such a pair with no other object on the table; other objects only remove IK
options, so a grasp outside these sets is never part of a grounding
(:class:`~solvers.sdar.grounding.Grounder`'s last stage searches within them).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence

from solvers.sdar.cache import StreamCache
from solvers.sdar.tasks import Step

#: ``arm -> configuration`` -> the cell configuration (the other arms at home), or None
Combine = Callable[[Mapping[str, str]], str | None]
#: IK solutions asked per grasp and pose when no other object is on the table (every branch,
#: and every branch of the half-turn twin where the IK stream offers it).
BRANCHES = 16


class FreePairs:
    """The free grasp sets of two-goal-move steps, kept while their objects rest where they
    are."""

    def __init__(self, cache: StreamCache, goals: Mapping[str, str], combine: Combine) -> None:
        self.cache = cache
        self.goals = goals
        self.combine = combine
        self._known: dict[Hashable, tuple[frozenset[str], ...]] = {}

    def __call__(
        self, step: Step, arms: tuple[str, ...], grasps: int
    ) -> tuple[frozenset[str], ...] | None:
        """Per move of a step of two goal moves, the grasps (of the first ``grasps``) that
        belong to a pair whose grippers clear the other object at its target and whose arms
        clear each other at the objects and at the targets, with no other object on the table
        (IK without fluents, every branch). None for other steps."""
        if len(step.moves) != 2 or any(m.to_buffer for m in step.moves):
            return None
        cache, voc = self.cache, self.cache.voc
        current = cache.current_poses()
        key = (step.moves, arms, tuple(current[o] for o in step.objects), grasps)
        if key in self._known:
            return self._known[key]
        confs: list[dict[str, tuple[list[str], list[str]]]] = []
        for arm, m in zip(arms, step.moves, strict=True):
            here, goal = current[m.obj], self.goals[m.obj]
            by_grasp: dict[str, tuple[list[str], list[str]]] = {}
            for (g,) in cache.outputs(voc.grasp, (m.obj,), grasps):
                picks = [q for (q,) in cache.outputs(voc.ik, (arm, m.obj, here, g), BRANCHES)]
                places = [q for (q,) in cache.outputs(voc.ik, (arm, m.obj, goal, g), BRANCHES)]
                if picks and places:
                    by_grasp[g] = (picks, places)
            confs.append(by_grasp)
        (a, b), (arm_a, arm_b) = step.objects, arms
        ta, tb = self.goals[a], self.goals[b]
        ok_a: set[str] = set()
        ok_b: set[str] = set()
        test = voc.grasp_cfree if voc.grasp_cfree in cache.streams else None

        def clear(x: Sequence[str], y: Sequence[str]) -> bool:
            return any(self.combine({arm_a: qa, arm_b: qb}) for qa in x for qb in y)

        for ga, (pick_a, place_a) in confs[0].items():
            for gb, (pick_b, place_b) in confs[1].items():
                if ga in ok_a and gb in ok_b:
                    continue
                if test is not None and not (
                    cache.test(test, (a, ta, ga, b, tb)) and cache.test(test, (b, tb, gb, a, ta))
                ):
                    continue
                if clear(pick_a, pick_b) and clear(place_a, place_b):
                    ok_a.add(ga)
                    ok_b.add(gb)
        result = (frozenset(ok_a), frozenset(ok_b))
        self._known[key] = result
        return result
