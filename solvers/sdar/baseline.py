"""The baseline task planner: our reconstruction of Gao & Yu (IROS 2022), "GaoYu22IROS".

The original code is not public; this follows the paper's description of it (section IV-A:
"first searches for an optimal plan for a single robot arm", then splits it over the arms):

1. :func:`optimal_single_arm_plan`: with free buffer space, the fewest pick-and-places of one
   arm are ``n + |minimum feedback vertex set|`` (objects outside the set go start -> goal
   once, which needs their dependency graph to be acyclic). The set is exact
   (:func:`minimum_feedback_vertex_set`, branch and bound per strongly connected component).
   The sequence repeats: an object on a buffer goes to its goal as soon as the goal is free;
   else an object on its start with a free goal goes there (so ``j`` before ``i`` when
   ``i -> j``); else a member of the set goes to a buffer (the one blocking most goals).
2. :func:`group_consecutive`: up to ``k`` consecutive actions of different objects that form a
   valid synchronous step (all picked, then all placed) share a step, greedily from the front
   (:func:`pair_consecutive` for two arms); otherwise one arm moves alone.

:class:`BaselineTaskPlanner` proposes the next planned step first, then valid one-move
fallbacks. When SDAR-M executes only part of a pair, :meth:`~BaselineTaskPlanner.commit` drops
exactly the executed moves; a queue that no longer fits the view is replanned from the view.
A component too large for ``node_budget`` uses a greedy set: ``exact`` turns ``False``.
"""

from __future__ import annotations

from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph
from solvers.sdar.abstract import view_of
from solvers.sdar.buffer_sets import feedback_vertex_set, minimum_feedback_vertex_set
from solvers.sdar.tasks import Move, Step, TaskView, step_is_valid

__all__ = [
    "BaselineTaskPlanner",
    "group_consecutive",
    "minimum_feedback_vertex_set",
    "optimal_single_arm_plan",
    "pair_consecutive",
]


def optimal_single_arm_plan(
    graph: DependencyGraph,
    in_buffer: frozenset[str] = frozenset(),
    feedback: frozenset[str] | None = None,
) -> list[Move]:
    """The single-arm move sequence (``n + |feedback|`` moves, objects in ``graph`` order).

    ``graph`` holds the objects not at their goals (those in ``in_buffer`` rest on buffers);
    ``feedback`` must break every cycle (default: the minimum feedback vertex set).
    """
    fvs = minimum_feedback_vertex_set(graph) if feedback is None else feedback
    at_goal: frozenset[str] = frozenset()
    buffered = in_buffer
    moves: list[Move] = []
    while len(at_goal) < graph.n:
        view = view_of(graph, at_goal, buffered)
        free = [x for x in view.remaining if not view.blockers(x)]
        waiting = [x for x in free if x in buffered]
        if waiting or free:
            obj = (waiting or free)[0]
            moves.append(Move(obj))
            at_goal |= {obj}
            continue
        stuck = [x for x in view.remaining if x in fvs and x not in buffered]
        if not stuck:
            raise ParameterError(f"feedback: {sorted(fvs)} does not break the cycles of {graph}")
        obj = max(stuck, key=lambda x: len(view.graph.predecessors(view.remaining.index(x))))
        moves.append(Move(obj, to_buffer=True))
        buffered |= {obj}
    return moves


def pair_consecutive(
    moves: list[Move], graph: DependencyGraph, in_buffer: frozenset[str] = frozenset()
) -> list[Step]:
    """Split a valid single-arm sequence into synchronous steps of one or two moves (``plan``):
    :func:`group_consecutive` for two arms."""
    return group_consecutive(moves, graph, in_buffer, arms=2)


def group_consecutive(
    moves: list[Move],
    graph: DependencyGraph,
    in_buffer: frozenset[str] = frozenset(),
    arms: int = 2,
) -> list[Step]:
    """Split a valid single-arm sequence into synchronous steps of up to ``arms`` moves
    (``plan``).

    Move ``k + 1`` joins the step of moves ``k...`` when it moves an object the step does not
    and the longer step is valid from the arrangement before the step; grouping is greedy from
    the front.
    """
    if arms < 1:
        raise ParameterError(f"arms must be >= 1, got {arms}")
    at_goal: frozenset[str] = frozenset()
    buffered = in_buffer
    steps: list[Step] = []
    k = 0
    while k < len(moves):
        view = view_of(graph, at_goal, buffered, arms)
        step = Step((moves[k],), "plan")
        while k + len(step.moves) < len(moves) and len(step.moves) < arms:
            following = moves[k + len(step.moves)]
            if following.obj in step.objects:
                break
            longer = Step((*step.moves, following), "plan")
            if not step_is_valid(longer, view):
                break
            step = longer
        for m in step.moves:
            if m.to_buffer:
                buffered |= {m.obj}
            else:
                at_goal |= {m.obj}
        steps.append(step)
        k += len(step.moves)
    return steps


def _fits(queue: list[Move], view: TaskView) -> bool:
    """The queue, run one move at a time from ``view``, is valid and ends with all at goal."""
    graph = view.graph
    at_goal: frozenset[str] = frozenset()
    buffered = view.in_buffer
    for move in queue:
        current = view_of(graph, at_goal, buffered)
        if move.obj not in current.remaining or not step_is_valid(Step((move,), "plan"), current):
            return False
        if move.to_buffer:
            buffered |= {move.obj}
        else:
            at_goal |= {move.obj}
    return len(at_goal) == graph.n


class BaselineTaskPlanner:
    """Optimal single-arm plan, split over the view's arms by grouping consecutive actions."""

    def __init__(self, node_budget: int | None = 200_000) -> None:
        self.node_budget = node_budget
        self.exact = True
        """``False`` once a feedback set came from the greedy fallback."""
        self._queue: list[Move] = []

    @property
    def name(self) -> str:
        return "baseline"

    def candidates(self, view: TaskView) -> list[Step]:
        if not view.remaining:
            return []
        if not _fits(self._queue, view):
            fvs = feedback_vertex_set(view.graph, node_budget=self.node_budget)
            self.exact = self.exact and fvs.exact
            self._queue = optimal_single_arm_plan(view.graph, view.in_buffer, fvs.members)
        planned = group_consecutive(
            self._queue[: view.arms], view.graph, view.in_buffer, view.arms
        )[0]
        out = [planned]
        seen = {planned.moves}
        fallbacks = [Step((m,), "plan", 1) for m in planned.moves]
        fallbacks += [Step((Move(x),), "single", 2) for x in view.remaining]
        movable = [x for x in view.remaining if x not in view.in_buffer]
        fallbacks += [Step((Move(x, to_buffer=True),), "buffer", 3) for x in movable]
        for step in fallbacks:
            if step.moves not in seen and step_is_valid(step, view):
                seen.add(step.moves)
                out.append(step)
        return out

    def commit(self, step: Step, view: TaskView) -> None:
        """Drop the executed moves from the queue (a fallback move forces a replan)."""
        for move in step.moves:
            if move not in self._queue:
                self._queue = []
                return
            self._queue.remove(move)
