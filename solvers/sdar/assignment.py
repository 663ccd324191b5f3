"""Which arms do a step's moves: the assignments of arms SDAR-M grounds for a candidate step.

With two arms every assignment (two at most). With more, bounded: for each move the arms that
reach its object and its target (the first grasp option of that arm, from the grounder's
``move_options``; with the view's layout the arms are asked nearest by plane reach first, and
no more once ``moves + 1`` reach), by the estimated time of that arm's pick and transfer, the
``moves + 1`` soonest; of their combinations with distinct arms the
``SdarOptions.assignments`` of least total estimate (with the view's
:class:`~solvers.sdar.tasks.Layout`, fewest crossing pairs of arms first). So at most
``(moves + 1) ** moves`` combinations are ranked, never every ``k``-tuple of arms. With
:attr:`ArmAssigner.by_plane` (the anytime finish of :mod:`~solvers.sdar.spending`) and a
layout, a one-move step's arms come in the order of their plane reach
(:meth:`~solvers.sdar.tasks.Layout.reach`), without asking IK first; a step of several moves
gets one assignment, each move the nearest arm not taken by an earlier move
(:func:`~solvers.sdar.spending.plane_seating`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

from solvers.sdar.cache import StreamCache
from solvers.sdar.move_option import Option
from solvers.sdar.report import Failures
from solvers.sdar.spending import moves_layout, plane_seating
from solvers.sdar.tasks import Layout, Move, Step

if TYPE_CHECKING:
    from solvers.sdar.options import SdarOptions

#: ``(arm, move, lifted, limit, grasps, only, moves)`` -> that arm's options for the move.
MoveOptions = Callable[
    [str, Move, frozenset[str], int, int, frozenset[str] | None, tuple[Move, ...]],
    list[Option],
]


class ArmAssigner:
    """Ranks the assignments of arms to a step's moves (see the module docstring)."""

    def __init__(
        self,
        cache: StreamCache,
        options: SdarOptions,
        home: Mapping[str, str],
        failures: Failures,
        move_options: MoveOptions,
    ) -> None:
        self.cache = cache
        self.options = options
        self.home = home
        self.failures = failures
        self.move_options = move_options
        self.by_plane = False
        """One-move steps: every arm, nearest by the layout's plane reach first, no IK asked."""

    def assignments(self, step: Step, layout: Layout | None = None) -> list[tuple[str, ...]]:
        """Arms for the step's moves, in order, best first; empty (and the reason recorded in
        :attr:`failures`) when no arm reaches a move or no assignment gives the moves distinct
        arms that reach them."""
        arms = sorted(self.home)
        m = len(step.moves)
        if len(arms) <= 2:
            return list(itertools.permutations(arms, m))
        if self.by_plane and layout is not None and all(o in layout.places for o in step.objects):
            if m == 1:
                obj = step.objects[0]
                order = sorted(range(len(arms)), key=lambda k: (layout.reach(k, obj), k))
                return [(arms[k],) for k in order]
            nearest = plane_seating(layout, step.moves)
            if len(nearest) == m:
                return [tuple(arms[k] for k in nearest)]
        cost = self.reach_costs(step, layout)
        per_move = [
            [a for _, a in sorted((cost[a, i], a) for a in arms if (a, i) in cost)][: m + 1]
            for i in range(m)
        ]
        alone = [step.moves[i] for i, reach in enumerate(per_move) if not reach]
        if alone:
            show = self.cache.show
            self.failures.unassigned(step, "no arm has a grasp with IK at " + ", ".join(
                f"{show(mv.obj)} and at {'a buffer' if mv.to_buffer else 'its goal'}"
                for mv in alone
            ))  # fmt: skip
            return []
        tuples = [t for t in itertools.product(*per_move) if len(set(t)) == m]
        if not tuples:
            self.failures.unassigned(
                step, "no assignment gives its moves distinct arms that reach them"
            )
        if layout is not None and all(mv.obj in layout.places for mv in step.moves):
            index = {a: k for k, a in enumerate(arms)}
            seats = {
                t: [(index[a], mv.obj) for a, mv in zip(t, step.moves, strict=True)] for t in tuples
            }
            crossings = {t: layout.conflicts(seats[t]) for t in tuples}
            tuples.sort(key=lambda t: (crossings[t], _total(cost, t), t))
        else:
            tuples.sort(key=lambda t: (_total(cost, t), t))
        return tuples[: self.options.assignments]

    def reach_costs(self, step: Step, layout: Layout | None = None) -> dict[tuple[str, int], float]:
        """(arm, move index) -> the estimated time of the arm's pick and transfer with its
        first option, for the arms that have one. With a layout placing the step's objects,
        each move asks the arms in the order of their plane reach
        (:meth:`~solvers.sdar.tasks.Layout.reach`, a buffer move's at its object's pose) and
        stops once ``moves + 1`` have an option (the assignment ranks no more per move)."""
        lifted = frozenset(step.objects)
        arms = sorted(self.home)
        m = len(step.moves)
        plane = None
        if layout is not None and all(o in layout.places for o in step.objects):
            plane = moves_layout(layout, step.moves)
        cost: dict[tuple[str, int], float] = {}
        for i, move in enumerate(step.moves):
            order = list(range(len(arms)))
            if plane is not None:
                order.sort(key=lambda k: (plane.reach(k, move.obj), k))
            found_for = 0
            for k in order:
                if plane is not None and found_for > m:
                    break
                a = arms[k]
                found = self.move_options(a, move, lifted, 1, self.options.grasps, None, step.moves)
                if found:
                    found_for += 1
                    here = self.cache.current_arm_conf(a)
                    pick, place = found[0].pick, found[0].place
                    cost[a, i] = self.cache.arm_distance(here, pick) + self.cache.arm_distance(
                        pick, place
                    )
        return cost


def _total(cost: Mapping[tuple[str, int], float], arms: Sequence[str]) -> float:
    return sum(cost[a, i] for i, a in enumerate(arms))
