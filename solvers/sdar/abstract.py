"""Rearrangement without geometry: run a task planner on a dependency graph and count actions.

Model: object ``i`` rests on its start ``S_i``, on its goal ``G_i`` or on a buffer. The
instance is the dependency graph of the start arrangement: edge ``i -> j`` iff ``G_i`` overlaps
``S_j``. Goals never overlap each other and buffers overlap nothing, so an edge ``i -> j``
holds only while ``j`` is still on its start: moving ``j`` (to its goal or to a buffer) deletes
every edge into ``j``. The current :class:`~solvers.sdar.tasks.TaskView` is the graph induced on
the objects not at their goals.

:func:`run_abstract` plays a planner to the end, executing the candidate that ``choose`` picks
(the first by default, i.e. what SDAR-M does when every grounding succeeds); every
pick-and-place counts one action. This is how SDAR-T and the baseline are compared on action
counts without motion planning (paper, section V-A).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from sdar_tamp.errors import SdarError
from sdar_tamp.graph import DependencyGraph
from solvers.sdar.tasks import Step, TaskPlanner, TaskView, step_is_valid

Chooser = Callable[[Sequence[Step], TaskView], Step]
"""Picks the step to execute among the ranked candidates (it may return a part of a pair)."""


class AbstractRunError(SdarError):
    """A task planner proposed an invalid step, nothing, or did not finish in time."""


@dataclass(frozen=True)
class AbstractRun:
    """The executed steps and their action count (``buffer_moves`` of which go to buffers)."""

    steps: tuple[Step, ...]
    actions: int
    buffer_moves: int


def view_of(
    graph: DependencyGraph, at_goal: frozenset[str], in_buffer: frozenset[str], arms: int = 2
) -> TaskView:
    """The view of ``graph`` (edges over start poses) once some objects have moved, for a cell
    of ``arms`` arms."""
    keep = [i for i, name in enumerate(graph.names) if name not in at_goal]
    index = {old: new for new, old in enumerate(keep)}
    moved = at_goal | in_buffer
    edges = tuple(
        (index[i], index[j])
        for i, j in graph.edges
        if i in index and j in index and graph.names[j] not in moved
    )
    names = tuple(graph.names[i] for i in keep)
    return TaskView(DependencyGraph(names, edges), at_goal, in_buffer - at_goal, arms=arms)


def first_candidate(candidates: Sequence[Step], view: TaskView) -> Step:
    """The default chooser: the planner's best candidate."""
    return candidates[0]


def run_abstract(
    planner: TaskPlanner,
    graph: DependencyGraph,
    choose: Chooser = first_candidate,
    max_steps: int | None = None,
    arms: int = 2,
) -> AbstractRun:
    """Run ``planner`` for a cell of ``arms`` arms until every object of ``graph`` is at its
    goal.

    Raises :class:`AbstractRunError` if a chosen step is invalid (more moves than arms
    included), the planner proposes nothing while objects remain, or more than ``max_steps``
    (default ``4 n + 4``) steps are taken.
    """
    limit = 4 * graph.n + 4 if max_steps is None else max_steps
    at_goal: frozenset[str] = frozenset()
    in_buffer: frozenset[str] = frozenset()
    steps: list[Step] = []
    while len(at_goal) < graph.n:
        if len(steps) >= limit:
            raise AbstractRunError(f"{planner.name}: not finished after {limit} steps")
        view = view_of(graph, at_goal, in_buffer, arms)
        candidates = planner.candidates(view)
        if not candidates:
            raise AbstractRunError(f"{planner.name}: no candidate for {view.remaining}")
        step = choose(candidates, view)
        if not step_is_valid(step, view):
            raise AbstractRunError(f"{planner.name}: invalid step {step} in {view}")
        planner.commit(step, view)
        steps.append(step)
        goal = frozenset(m.obj for m in step.moves if not m.to_buffer)
        at_goal |= goal
        in_buffer = (in_buffer - goal) | frozenset(m.obj for m in step.moves if m.to_buffer)
    buffers = sum(1 for s in steps for m in s.moves if m.to_buffer)
    return AbstractRun(tuple(steps), sum(len(s.moves) for s in steps), buffers)


def count_actions(
    planner_factory: Callable[[], TaskPlanner], graph: DependencyGraph, arms: int = 2
) -> int:
    """Pick-and-places a fresh planner needs on ``graph`` when its first choice always works."""
    return run_abstract(planner_factory(), graph, arms=arms).actions
