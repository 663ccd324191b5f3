"""SDAR-T: dependency-driven task planning for k synchronous arms (paper, section IV-A, Alg. 1).

Alg. 1 returns a task list; here it is a ranked list of :class:`~solvers.sdar.tasks.Step`
candidates which SDAR-M grounds best first, falling back down the list. ``B(x)`` are the objects
whose current poses block the goal of ``x``. Rank classes (lower is better):

0. ``last``: one object left: it goes to its goal.
1. ``pair`` / ``chain`` / ``swap``: two objects both to their goals, each blocked only by the
   other (``B(i) <= {j}``, ``B(j) <= {i}``): two independent objects, the terminal pair of a
   chain (``i -> j``, ``j`` a leaf) or a 2-cycle swapped by the two arms. Pairs that free more
   objects, then remove more edges, come first, so chains are consumed from the leaf.
2. ``cycle``: cycle breaking: ``x`` of a component of three or more objects goes to a buffer
   and an object ``i`` with ``B(i) = {x}`` (adjacent in the cycle) to its goal.
3. ``cycle``: ``x`` to a buffer paired with an object whose goal is free anyway; also ``x``
   of a 2-cycle proposed as a swap, paired with any object whose goal it alone blocks or
   that is free, for when the swap is geometrically impossible (two grippers closing on two
   neighbouring objects collide). Such a step costs one buffer move, as the single-arm
   optimum does for that cycle.
4. ``cycle``: when no step of classes 1-3 exists, two objects ``x``, ``y`` to buffers, if one
   minimum buffer set holds both (``x`` among the three best optimal objects).
5. ``cycle``: ``x`` alone, when no object can go to its goal in the same step.
6. ``single``: one object to its free goal (the one-arm-at-a-time fallback).
7. ``cycle``: as 2-3, for an ``x`` known to cost an extra buffer move (a detour).
8. ``buffer``: one object to a buffer; objects already on a buffer only if nothing else is
   possible (no ping-pong).
9. any of the above that brings an object to its goal while that goal would leave another
   object still to be placed no grasp at its own goal (:meth:`TaskView.must_wait`): last
   resorts, since the other object could then never be placed.

Edges of the view's graph come from footprints and from grasps alike: ``i -> j`` also when
``i`` at its goal leaves ``j`` no grasp where ``j`` rests, or ``j`` where it rests leaves ``i``
no grasp (at its goal, or where ``i`` rests). Moves are ordered and cycles broken over all of
them.

Choosing ``x``: the objects that belong to a minimum *buffer set* of the current graph (the
fewest objects whose removal leaves components of at most two objects, see
:mod:`solvers.sdar.buffer_sets`) are the optimal ones; goal moves never add to it, so taking the
first candidate always uses ``n + |minimum buffer set|`` actions, never more than a single arm
optimum (``n + |minimum FVS|``). Among them (or all of them, greedily, when the exact search
exceeds ``node_budget``, which sets :attr:`SdarTaskPlanner.exact` to ``False``), objects that
free more objects and have more predecessors come first. Ties break by object order, so the
list is a function of the view. Candidates whose keys differ only in object order get the
same :attr:`~solvers.sdar.tasks.Step.tie` (e.g. pairs freeing as many objects and edges,
cycle breaks of one ``x`` with partners of as many predecessors), so that SDAR-M may choose
among them by expected motion time. Steps of two moves are capped at ``max_candidates``; one-move
steps are always kept. :meth:`~SdarTaskPlanner.commit` does nothing: SDAR-T replans from the
view at every step.

The number of arms is the view's (:attr:`~solvers.sdar.tasks.TaskView.arms`); the list above is
the list for two arms. With one arm a step holds one move: classes 1 (an object to its free
goal; objects waiting on a buffer first), 5 (``x`` of a minimum feedback vertex set to a
buffer), 7 (another object of a cycle to a buffer), 8 and 9 as above; a first-candidate run
takes ``n + |minimum FVS|`` actions, the single-arm optimum. With ``k > 2`` arms the buffer sets
leave components of up to ``k`` objects (:mod:`solvers.sdar.buffer_sets`, ``arms=k``), and the
candidates are bounded so (:mod:`solvers.sdar.k_steps`): the first ``max_candidates`` two-move
steps of the ranked list and its one-move steps (class 6 included) are each extended greedily
with goal moves of units whose goals are free once the step's objects are lifted, up to ``k``
moves; the extended
step and its base are both kept (the base is the fallback when the larger step cannot be
grounded); closed components of ``3..k`` objects are proposed as ``rotate`` steps of class 1 (an
``m``-cycle rotated by ``m`` arms without a buffer; a component of ``3..k`` objects can still be
broken at class 7, for when the rotation is geometrically impossible); with four arms or more
and a layout, each of the first four two-move steps is also merged with a later one of other
components whose arms it does not cross (:func:`~solvers.sdar.k_steps.merges`: two cycle breaks
in far parts of the table in one step). Within a class, steps bringing more objects to their
goals come first. So a list holds at most ``2 max_candidates + 4`` steps of several moves, plus
one rotation per component, plus the one-move steps; no set of ``k`` objects is enumerated.
"""

from __future__ import annotations

from itertools import combinations

from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph
from solvers.sdar.buffer_sets import extending_minimum, optimal_choices
from solvers.sdar.k_steps import TaskScene, extensions, merges, rotations
from solvers.sdar.tasks import Move, Step, TaskView

_Edges = tuple[tuple[int, int], ...]
_DOUBLE_FIRSTS = 3  # double buffer moves are sought for the best three first objects
(LAST, GOAL_PAIR, CYCLE, CYCLE_FREE, CYCLE_DOUBLE, CYCLE_ALONE, SINGLE, DETOUR, BUFFER,
 WAIT) = range(10)  # fmt: skip

_Key = tuple[int, ...]
_Ranked = list[tuple[_Key, Step]]
_Scene = TaskScene


class SdarTaskPlanner:
    """The SDAR-T task planner (see the module docstring for its rules)."""

    def __init__(self, max_candidates: int = 24, node_budget: int | None = 50_000) -> None:
        if max_candidates < 1:
            raise ParameterError(f"max_candidates must be >= 1, got {max_candidates}")
        if node_budget is not None and node_budget < 1:
            raise ParameterError(f"node_budget must be None or >= 1, got {node_budget}")
        self.max_candidates = max_candidates
        self.node_budget = node_budget
        self.exact = True
        """``False`` once a cycle was broken by the greedy score (exact search over budget)."""
        self._choices: dict[tuple[tuple[str, ...], _Edges, int], frozenset[str]] = {}

    @property
    def name(self) -> str:
        return "sdar"

    def commit(self, step: Step, view: TaskView) -> None:
        """Nothing to do: the next candidates are computed from the next view."""

    def candidates(self, view: TaskView) -> list[Step]:
        names = view.remaining
        if len(names) <= 1:
            return [Step((Move(x, bool(view.blockers(x))),), "last", LAST, ()) for x in names]
        scene = _Scene(view)
        if view.arms == 1:
            kept = self._one_arm(scene, view)
        else:
            goal_pairs = self._goal_pairs(scene)
            ranked = goal_pairs + self._cycle_breaks(scene, view, bool(goal_pairs))
            ranked.sort(key=lambda item: item[0])
            kept = [item for item in ranked if len(item[1].moves) == 2][: self.max_candidates]
            kept += [item for item in ranked if len(item[1].moves) == 1]
            for x in names:
                if not scene.blockers[x]:
                    key: _Key = (SINGLE, -scene.preds[x], scene.order[x])
                    kept.append((key, Step((Move(x),), "single", SINGLE, key[1:-1])))
            if view.arms > 2:
                kept = self._more_arms(scene, view.arms, kept)
        movable = [x for x in names if x not in view.in_buffer]
        if not movable and not kept:
            movable = list(names)  # nothing else is possible: allow a buffer-to-buffer move
        proposed = {step.moves for _, step in kept}
        for x in movable:
            if (Move(x, to_buffer=True),) not in proposed:
                key = (BUFFER, scene.order[x])
                kept.append((key, Step((Move(x, to_buffer=True),), "buffer", BUFFER)))
        if view.waits:
            kept = [self._wait(item, view) for item in kept]
        kept.sort(key=lambda item: item[0])
        return [step for _, step in kept]

    @staticmethod
    def _wait(item: tuple[_Key, Step], view: TaskView) -> tuple[_Key, Step]:
        """Class 9 for a step placing an object whose goal would leave another object still to
        be placed (the other object of a pair too: both are placed at once) no grasp."""
        key, step = item
        if not any(not m.to_buffer and view.must_wait(m.obj) for m in step.moves):
            return item
        return (WAIT, *key), Step(step.moves, step.kind, WAIT)

    def _one_arm(self, scene: _Scene, view: TaskView) -> _Ranked:
        """One arm: an object to its free goal (class 1), else a cycle broken by one buffer
        move (class 5 for an object of a minimum feedback vertex set, 7 for another)."""
        out: _Ranked = []
        for x in scene.names:
            if not scene.blockers[x]:
                key: _Key = (GOAL_PAIR, int(x not in view.in_buffer), -scene.preds[x],
                             scene.order[x])  # fmt: skip
                out.append((key, Step((Move(x),), "single", GOAL_PAIR, key[1:-1])))
        optimal, breakable = self._break_choices(view)
        for x in breakable:
            freed, removed = scene.frees(frozenset((x,)))
            rank = CYCLE_ALONE if x in optimal else DETOUR
            key = (rank, -freed, -scene.preds[x], -removed, scene.order[x])
            out.append((key, Step((Move(x, to_buffer=True),), "cycle", rank, key[1:-1])))
        return out

    @staticmethod
    def _more_arms(scene: _Scene, arms: int, kept: _Ranked) -> _Ranked:
        """More than two arms: every kept step extended greedily (its base kept too), the
        first two-move steps merged with another each (four arms or more), plus the
        rotations of closed components; within a class more goal moves first; one step
        per set of moves (the best ranked). See :mod:`solvers.sdar.k_steps`."""
        out: _Ranked = []
        for key, step in kept:
            for wider in extensions(scene, step, arms):
                out.append(((key[0], -wider.progress, *key[1:]), wider))
            out.append(((key[0], -step.progress, *key[1:]), step))
        keys = {step.moves: key for key, step in kept}
        for merged in merges(scene, [step for _, step in kept], arms):
            key = keys[merged.moves[:2]]
            out.append(((key[0], -merged.progress, *key[1:]), merged))
        for key, step in rotations(scene, arms):
            rotate = Step(step.moves, step.kind, GOAL_PAIR, step.tie)
            out.append(((GOAL_PAIR, -rotate.progress, *key), rotate))
        out.sort(key=lambda item: item[0])
        best: dict[frozenset[Move], tuple[_Key, Step]] = {}
        for item in out:
            best.setdefault(frozenset(item[1].moves), item)
        return list(best.values())

    def _goal_pairs(self, scene: _Scene) -> _Ranked:
        """Class 1: both objects to their goals."""
        out: _Ranked = []
        for i, j in combinations(scene.names, 2):
            bi, bj = scene.blockers[i], scene.blockers[j]
            if bi <= {j} and bj <= {i}:
                kind = "swap" if bi and bj else "chain" if bi or bj else "pair"
                freed, removed = scene.frees(frozenset((i, j)))
                key = (GOAL_PAIR, -freed, -removed, scene.order[i], scene.order[j])
                out.append((key, Step((Move(i), Move(j)), kind, GOAL_PAIR, key[1:-2])))
        return out

    def _cycle_breaks(self, scene: _Scene, view: TaskView, goal_pairs: bool) -> _Ranked:
        """Classes 2-5 and 7: an object of a large component goes to a buffer."""
        optimal, breakable = self._break_choices(view)
        out: _Ranked = []
        x_keys: dict[str, _Key] = {}
        for x in breakable:
            freed, removed = scene.frees(frozenset((x,)))
            x_key = x_keys[x] = (-freed, -scene.preds[x], -removed, scene.order[x])
            partners = [i for i in scene.names if i != x and scene.blockers[i] <= {x}]
            for i in partners:
                linked = bool(scene.blockers[i])
                rank = (CYCLE if linked else CYCLE_FREE) if x in optimal else DETOUR
                key: _Key = (rank, int(not linked), *x_key, -scene.preds[i], scene.order[i])
                step = Step((Move(i), Move(x, to_buffer=True)), "cycle", rank, key[1:-1])
                out.append((key, step))
            if not partners and x in optimal:
                key = (CYCLE_ALONE, *x_key)
                out.append((key, Step((Move(x, to_buffer=True),), "cycle", CYCLE_ALONE)))
        for x in self._swappable(scene, view):
            freed, removed = scene.frees(frozenset((x,)))
            x_key = (-freed, -scene.preds[x], -removed, scene.order[x])
            for i in (i for i in scene.names if i != x and scene.blockers[i] <= {x}):
                key = (CYCLE_FREE, 1, *x_key, -scene.preds[i], scene.order[i])
                step = Step((Move(i), Move(x, to_buffer=True)), "cycle", CYCLE_FREE, key[1:-1])
                out.append((key, step))
        if all(key[0] >= CYCLE_ALONE for key, _ in out) and not goal_pairs:
            firsts = sorted((x for x in breakable if x in optimal), key=x_keys.__getitem__)
            for x, y in self._double_buffers(view, firsts[:_DOUBLE_FIRSTS], firsts):
                key = (CYCLE_DOUBLE, *x_keys[x], *x_keys[y])
                moves = (Move(x, to_buffer=True), Move(y, to_buffer=True))
                out.append((key, Step(moves, "cycle", CYCLE_DOUBLE)))
        return out

    def _break_choices(self, view: TaskView) -> tuple[frozenset[str], list[str]]:
        """Objects whose buffering is optimal, and all objects of components above two."""
        graph = view.graph
        optimal: set[str] = set()
        breakable: list[str] = []
        for comp in graph.components():
            if len(comp) < min(3, view.arms + 1):
                continue
            local = {v: k for k, v in enumerate(comp)}
            sub = DependencyGraph(
                tuple(graph.names[v] for v in comp),
                tuple((local[i], local[j]) for i, j in graph.edges if i in local and j in local),
            )
            breakable.extend(sub.names)
            key = (sub.names, sub.edges, view.arms)
            if key not in self._choices:
                found = optimal_choices(
                    sub, allow_swaps=True, node_budget=self.node_budget, arms=view.arms
                )
                if found is None:
                    self.exact = False
                    found = frozenset(sub.names)
                self._choices[key] = found
            optimal |= self._choices[key]
        return frozenset(optimal), breakable

    @staticmethod
    def _swappable(scene: _Scene, view: TaskView) -> list[str]:
        """Objects of the 2-cycles proposed as swaps (blocked by nothing else). The swap comes
        first; breaking the cycle is for when two grippers cannot close on the two
        neighbouring objects at once, and then costs the buffer move any plan needs."""
        graph = view.graph
        out: list[str] = []
        for comp in graph.components():
            if len(comp) == 2:
                i, j = (graph.names[v] for v in comp)
                if scene.blockers[i] <= {j} and scene.blockers[j] <= {i}:
                    out += [i, j]
        return out

    def _double_buffers(
        self, view: TaskView, firsts: list[str], optimal: list[str]
    ) -> list[tuple[str, str]]:
        """Pairs ``(x, y)``, ``x`` in ``firsts``, that one minimum buffer set holds together."""
        options: dict[frozenset[str], tuple[str, str]] = {}
        for x in firsts:
            for y in optimal:
                if y != x:
                    options.setdefault(frozenset((x, y)), (x, y))
        if not options:
            return []
        found = extending_minimum(
            view.graph,
            list(options),
            allow_swaps=True,
            node_budget=self.node_budget,
            arms=view.arms,
        )
        if found is None:
            self.exact = False
            return list(options.values())
        return [options[k] for k in found]
