"""Where two arms of a step meet: pairwise checks of the options of a step of several moves.

With more than two arms, a step of ``m`` moves grounds when one option per move (grasp, pick and
place configurations) puts every arm at its object at once, and then at its target, clear of the
others. Arms collide in pairs, so :class:`ArmPairs` checks each pair of options of two moves
once (the two arms at their configurations, every other arm at home, through the domain's
combine stream; when an option alone already meets an arm at home, its pairs are left to the
check of the whole cell, so that a pair fails only when its two arms meet), and a combination of
options is a grounding only when each of its pairs is clear at the objects and at the targets
(the check of the whole cell configuration then passes, since its arms are pairwise clear). A
pair of moves none of whose option pairs is clear dooms every combination at once; that failure
is remembered with its arms (:class:`~solvers.sdar.failure_memo.FailureMemo`, key ``("meet",
arm, move, arm, move, stage)``, the stage saying how many options of how many grasps) while the
two objects rest where they are, so that other assignments and later decisions skip it:
:meth:`ArmPairs.meets` (a meeting at a buffer only at the objects: buffers are sampled anew when
other objects move).

The checks cost ``m (m - 1) / 2`` pairs times the options of both moves, twice (objects,
targets), for every combination the product of the options: one cell check per pair and the
combinations filtered by table look-ups.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass

from solvers.sdar.failure_memo import FailureMemo
from solvers.sdar.move_option import Option
from solvers.sdar.tasks import Move, Step

#: The cell configuration of some arms' configurations, the others at home (None: collision).
Combine = Callable[[Mapping[str, str]], str | None]

AT_PICK = "the arms collide at the objects"
AT_PLACE = "the arms collide at the targets"


@dataclass(frozen=True)
class PairTable:
    """The clear option pairs of a step's moves: ``(i, a, j, b)`` for the ``a``-th option of
    move ``i`` and the ``b``-th of move ``j`` (``i < j``), at the objects and at the targets."""

    at_pick: frozenset[tuple[int, int, int, int]]
    at_place: frozenset[tuple[int, int, int, int]]

    def why_not(self, chosen: Sequence[int]) -> str | None:
        """None when the options ``chosen`` (an index per move) are pairwise clear; else the
        first failing check."""
        pairs = [
            (i, chosen[i], j, chosen[j]) for i, j in itertools.combinations(range(len(chosen)), 2)
        ]
        if not all(p in self.at_pick for p in pairs):
            return AT_PICK
        if not all(p in self.at_place for p in pairs):
            return AT_PLACE
        return None


class ArmPairs:
    """Pairwise checks of a step's options (see the module docstring)."""

    def __init__(self, combine: Combine, memo: FailureMemo) -> None:
        self.combine = combine
        self.memo = memo

    @staticmethod
    def key(arm: str, move: Move, other_arm: str, other: Move, stage: Hashable) -> Hashable:
        """The memo key of ``arm`` doing ``move`` meeting ``other_arm`` doing ``other`` with the
        options of ``stage`` (how many options of how many grasps), in a canonical order."""
        first, second = sorted(((arm, move), (other_arm, other)), key=repr)
        return ("meet", *first, *second, stage)

    def meets(
        self, step: Step, arms: Sequence[str], stage: Hashable, poses: Mapping[str, str]
    ) -> str | None:
        """Why two of the step's arms meet whatever their options of ``stage``, when
        remembered, else None."""
        for i, j in itertools.combinations(range(len(arms)), 2):
            key = self.key(arms[i], step.moves[i], arms[j], step.moves[j], stage)
            reason = self.memo.recall(key, poses)
            if reason is not None:
                return reason
        return None

    def table(
        self,
        step: Step,
        arms: Sequence[str],
        per_move: Sequence[Sequence[Option]],
        poses: Mapping[str, str],
        stage: Hashable = None,
    ) -> PairTable | str:
        """The clear pairs of options, or why a pair of moves has none (remembered for
        ``stage``, with the poses of its two objects in ``poses``)."""
        pick: set[tuple[int, int, int, int]] = set()
        place: set[tuple[int, int, int, int]] = set()
        alone = [
            [(self._alone(arms[i], o.pick), self._alone(arms[i], o.place)) for o in options]
            for i, options in enumerate(per_move)
        ]
        for i, j in itertools.combinations(range(len(arms)), 2):
            found_pick = found_place = False
            for (a, oa), (b, ob) in itertools.product(
                enumerate(per_move[i]), enumerate(per_move[j])
            ):
                (pick_a, place_a), (pick_b, place_b) = alone[i][a], alone[j][b]
                # an option that meets an arm at home is left to the check of the whole cell
                if pick_a and pick_b and not self._clear(arms[i], oa.pick, arms[j], ob.pick):
                    continue
                pick.add((i, a, j, b))
                found_pick = True
                if (
                    place_a
                    and place_b
                    and self.combine({arms[i]: oa.place, arms[j]: ob.place}) is None
                ):
                    continue
                place.add((i, a, j, b))
                found_place = True
            if not (found_pick and found_place):
                reason = AT_PICK if not found_pick else AT_PLACE
                mi, mj = step.moves[i], step.moves[j]
                if reason == AT_PICK or not (mi.to_buffer or mj.to_buffer):  # buffers vary
                    world = {o: poses[o] for o in (mi.obj, mj.obj) if o in poses}
                    key = self.key(arms[i], mi, arms[j], mj, stage)
                    self.memo.remember(key, reason, world)
                return reason
        return PairTable(frozenset(pick), frozenset(place))

    def _clear(self, arm: str, q: str, other_arm: str, other: str) -> bool:
        """The two arms at their configurations are clear (the others at home)."""
        return self.combine({arm: q, other_arm: other}) is not None

    def _alone(self, arm: str, q: str) -> bool:
        """``arm`` at ``q`` is clear of the other arms at home."""
        return self.combine({arm: q}) is not None


def grippers_can_clear(
    targets: Sequence[tuple[str, str]],
    grasps: Sequence[Sequence[str]],
    clear: Callable[[str, str, str, str, str], bool],
) -> bool:
    """Some choice of one grasp per object (``grasps[i]`` for the object and target
    ``targets[i]``) keeps every gripper clear of every other object at its target (``clear(o,
    p, g, o2, p2)``: the gripper holding ``o`` at ``p`` with ``g`` is clear of ``o2`` at
    ``p2``): a backtracking search over the objects in order. Whatever arms place them, objects
    placed at once with no such choice never ground; that depends on neither arms nor poses."""

    def pair_ok(i: int, gi: str, j: int, gj: str) -> bool:
        (oi, ti), (oj, tj) = targets[i], targets[j]
        return clear(oi, ti, gi, oj, tj) and clear(oj, tj, gj, oi, ti)

    def extend(chosen: list[str]) -> bool:
        i = len(chosen)
        if i == len(targets):
            return True
        for g in grasps[i]:
            if all(pair_ok(j, chosen[j], i, g) for j in range(i)):
                chosen.append(g)
                if extend(chosen):
                    return True
                chosen.pop()
        return False

    return extend([])
