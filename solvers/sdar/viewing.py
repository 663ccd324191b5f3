"""The task planner's view of the current state: the dependency graph of the objects not at
their goals, and with more than two arms where they lie on the table.

Edges come from the domain's test streams alone: footprint overlap (the overlap test) and,
when the domain has the grasp-blocking test, objects that leave one another no grasp (see
:class:`~solvers.sdar.tasks.TaskView`). The positions (a :class:`~solvers.sdar.tasks.Layout`)
come from the app's :class:`~solvers.sdar.options.Plane`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from sdar_tamp.graph import DependencyGraph
from solvers.sdar.cache import StreamCache
from solvers.sdar.options import Plane
from solvers.sdar.tasks import Layout, TaskView


def current_view(
    cache: StreamCache, goals: Mapping[str, str], arms: Sequence[str], plane: Plane | None
) -> TaskView:
    """The view of the arrangement in ``cache``: the objects not at their ``goals`` (object ->
    goal pose), their edges, the objects done and on buffers, which objects must wait for
    others (grasp blocking at both goals), the number of ``arms`` and the layout
    (:func:`layout`)."""
    voc = cache.voc
    current = cache.current_poses()
    remaining = tuple(sorted(o for o, g in goals.items() if current.get(o) != g))
    blocks = voc.blocks_grasps if voc.blocks_grasps in cache.streams else None
    edges = []
    waits: set[tuple[str, str]] = set()
    for i, a in enumerate(remaining):
        goal = goals[a]
        for j, b in enumerate(remaining):
            if i == j or b not in current:
                continue
            here = current[b]
            if cache.test(voc.overlap, (a, goal, b, here)) or (
                blocks is not None
                and (
                    cache.test(blocks, (a, goal, b, here))  # b could not be picked
                    or cache.test(blocks, (b, here, a, goal))  # a could not be placed
                    or (a in current and cache.test(blocks, (b, here, a, current[a])))
                )
            ):
                edges.append((i, j))
            if blocks is not None and cache.test(blocks, (a, goal, b, goals[b])):
                waits.add((a, b))
    buffered = frozenset(o for o, p in current.items() if cache.state.has(voc.buffer_pose, p))
    done = frozenset(o for o, g in goals.items() if current.get(o) == g)
    graph = DependencyGraph(remaining, tuple(edges))
    places = layout(cache, goals, arms, plane, remaining, current)
    return TaskView(graph, done, buffered, frozenset(waits), len(arms), places)


def layout(
    cache: StreamCache,
    goals: Mapping[str, str],
    arms: Sequence[str],
    plane: Plane | None,
    remaining: tuple[str, ...],
    current: Mapping[str, str],
) -> Layout | None:
    """With more than two ``arms`` and a :class:`~solvers.sdar.options.Plane`: the plane
    positions of the ``remaining`` objects' poses (``current``) and goals and of the arms'
    bases (arms in sorted order); None otherwise, or when a pose is not one the plane
    locates."""
    if plane is None or len(arms) <= 2:
        return None
    values = {a: cache.table.value(a) for a in sorted(arms)}
    if any(not isinstance(v, str) or v not in plane.bases for v in values.values()):
        return None
    places = {}
    for obj in remaining:
        if obj not in current:
            return None
        here = plane.locate(cache.table.value(current[obj]))
        goal = plane.locate(cache.table.value(goals[obj]))
        if here is None or goal is None:
            return None
        places[obj] = (here, goal)
    bases = tuple(plane.bases[str(v)] for v in values.values())
    return Layout(places, bases, plane.clearance)
