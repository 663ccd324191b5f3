"""The vocabulary shared by rearrangement task planners (SDAR-T and the baseline) and SDAR-M.

A task planner looks at a :class:`TaskView` of the current arrangement (the dependency graph of
the objects not yet at their goals, which objects sit in buffers, and how many arms the cell
has) and proposes ranked :class:`Step` candidates: up to ``view.arms`` object moves done in one
synchronous step (every acting arm picks, then every one places). SDAR-M assigns arms, grounds
the candidates through the streams, picks one and reports it back with
:meth:`TaskPlanner.commit`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

from sdar_tamp.graph import DependencyGraph


@dataclass(frozen=True)
class Move:
    """Move ``obj`` to its goal, or to a buffer (a free temporary pose SDAR-M samples)."""

    obj: str
    to_buffer: bool = False


@dataclass(frozen=True)
class Step:
    """One synchronous step: one or more moves of distinct objects (at most one per arm of the
    cell, see :func:`step_is_valid`), arms not yet assigned.

    ``kind`` names the rule that proposed it (``pair``, ``chain``, ``swap``, ``rotate``,
    ``cycle``, ``single``, ``buffer``, ``last``, ``plan``, ``evict``, ``regrasp``); ``rank``
    orders candidates (lower is better).
    ``tie``: candidates of one rank with equal ties are alike to the task planner (their order
    is only by object name), so the motion planner may take whichever it expects to execute
    soonest; None: the task planner's order stands.
    """

    moves: tuple[Move, ...]
    kind: str
    rank: int = 0
    tie: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        if not self.moves:
            raise ValueError("a step has at least one move, got none")
        if len({m.obj for m in self.moves}) != len(self.moves):
            raise ValueError(f"a step moves distinct objects, got {self.moves}")

    @property
    def objects(self) -> tuple[str, ...]:
        return tuple(m.obj for m in self.moves)

    def peer_of(self, other: Step) -> bool:
        """Alike to the task planner: the same rank and the same (not None) tie."""
        return self.tie is not None and (self.rank, self.tie) == (other.rank, other.tie)

    @property
    def progress(self) -> int:
        """Objects this step brings to their goals."""
        return sum(1 for m in self.moves if not m.to_buffer)


@dataclass(frozen=True)
class Layout:
    """Where the objects and arms are, in the table plane, as plain numbers [m]: ``places``
    object -> ``(x, y)`` of its current pose and ``(x, y)`` of its goal; ``bases`` the arms'
    base positions; ``clearance`` the distance under which two objects count as neighbours
    (their grippers would meet). Built outside the solvers (the app knows the poses)."""

    places: Mapping[str, tuple[tuple[float, float], tuple[float, float]]]
    bases: tuple[tuple[float, float], ...]
    clearance: float = 0.08

    def __post_init__(self) -> None:
        if not self.bases:
            raise ValueError("a layout needs at least one arm base")
        if self.clearance < 0:
            raise ValueError(f"a layout needs clearance >= 0, got {self.clearance}")

    def reach(self, arm: int, obj: str) -> float:
        """How far arm ``arm`` (an index into ``bases``) reaches for ``obj``: the distances
        from its base to the object's current pose and to its goal, summed [m]."""
        here, goal = self.places[obj]
        return math.dist(self.bases[arm], here) + math.dist(self.bases[arm], goal)

    def side(self, obj: str) -> int:
        """The arm that reaches ``obj`` least far (:meth:`reach`; the first of equals)."""
        return min(range(len(self.bases)), key=lambda k: (self.reach(k, obj), k))

    def gap(self, group: Iterable[str], others: Iterable[str]) -> float:
        """The least distance between a pose or goal of ``group`` and one of ``others``."""
        mine = [p for x in group for p in self.places[x]]
        theirs = [p for y in others for p in self.places[y]]
        return min((math.dist(a, b) for a in mine for b in theirs), default=math.inf)

    def arm_gap(self, arm: int, obj: str, other_arm: int, other: str) -> float:
        """The least distance [m] between the plane segments from the bases of ``arm`` and
        ``other_arm`` to ``obj`` and ``other``, at the picks (current poses) and at the places
        (goals): how close the two arms come, seen from above, moving them in one step
        (``benchmarks/bench_layout.py`` measures how often arms so placed collide)."""
        return min(
            _segment_gap(
                self.bases[arm], self.places[obj][k], self.bases[other_arm], self.places[other][k]
            )
            for k in (0, 1)
        )

    def sweep_gap(self, arm: int, obj: str, other_arm: int, other: str) -> float:
        """The least distance [m] between the two arms' plane segments over their transfers:
        each from its base to the point a fraction ``s`` of the way from its object's pose to
        its goal, both at the same ``s`` (synchronous motions), for ``s`` in :data:`SWEEP`
        (0 and 1 are :meth:`arm_gap`'s picks and places)."""
        (a0, a1), (b0, b1) = self.places[obj], self.places[other]
        return min(
            _segment_gap(self.bases[arm], _lerp(a0, a1, s), self.bases[other_arm], _lerp(b0, b1, s))
            for s in SWEEP
        )

    def crosses(self, arm: int, obj: str, other_arm: int, other: str) -> bool:
        """Arm ``arm`` moving ``obj`` while ``other_arm`` moves ``other`` in the same step:
        their :meth:`sweep_gap` is under ``clearance``; two arms reaching so meet."""
        return self.sweep_gap(arm, obj, other_arm, other) < self.clearance

    def conflicts(self, assigned: Sequence[tuple[int, str]]) -> int:
        """Pairs of (arm, object) in ``assigned`` that :meth:`crosses`."""
        return sum(
            1 for (a, x), (b, y) in itertools.combinations(assigned, 2) if self.crosses(a, x, b, y)
        )


#: Fractions of a transfer at which :meth:`Layout.sweep_gap` compares two arms.
SWEEP = (0.0, 0.25, 0.5, 0.75, 1.0)


def _lerp(p: tuple[float, float], q: tuple[float, float], s: float) -> tuple[float, float]:
    return (p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1]))


def _segment_gap(
    p: tuple[float, float], q: tuple[float, float], r: tuple[float, float], s: tuple[float, float]
) -> float:
    """The distance between the plane segments ``pq`` and ``rs`` (0 when they cross)."""

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    d1, d2, d3, d4 = cross(r, s, p), cross(r, s, q), cross(p, q, r), cross(p, q, s)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return 0.0
    return min(_point_gap(p, r, s), _point_gap(q, r, s), _point_gap(r, p, q), _point_gap(s, p, q))


def _point_gap(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    """The distance from ``p`` to the segment ``ab``."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2
    t = min(1.0, max(0.0, t))
    return math.dist(p, (a[0] + t * dx, a[1] + t * dy))


@dataclass(frozen=True)
class TaskView:
    """The current arrangement as a task planner sees it.

    ``graph`` is the dependency graph over the objects not at their goals (``i -> j``: ``i``
    cannot go to its goal while ``j`` rests where it does: the goal of ``i`` overlaps the
    current pose of ``j``, or one of them leaves the other no grasp); ``done`` are the objects
    at their goals; ``in_buffer`` the objects resting on a buffer; ``waits`` pairs ``(i, j)``:
    ``i`` at its goal would leave ``j`` no grasp at the goal of ``j``, so ``i`` goes to its
    goal after ``j``. ``arms``: the arms of the cell, the most moves a step may hold (>= 1).
    ``layout``: where the remaining objects and the arms are (:class:`Layout`), when known;
    SDAR-T's steps of more than two moves use it (:mod:`solvers.sdar.k_steps`).
    """

    graph: DependencyGraph
    done: frozenset[str]
    in_buffer: frozenset[str]
    waits: frozenset[tuple[str, str]] = frozenset()
    arms: int = 2
    layout: Layout | None = None

    def __post_init__(self) -> None:
        if self.arms < 1:
            raise ValueError(f"a task view needs arms >= 1, got {self.arms}")

    @property
    def remaining(self) -> tuple[str, ...]:
        return self.graph.names

    def blockers(self, obj: str) -> frozenset[str]:
        """The objects whose current poses overlap the goal of ``obj``."""
        i = self.graph.names.index(obj)
        return frozenset(self.graph.names[j] for j in self.graph.successors(i))

    def must_wait(self, obj: str) -> bool:
        """``obj`` at its goal would leave an object still to be placed no grasp at its goal."""
        remaining = set(self.graph.names)
        return any(i == obj and j in remaining and j != obj for i, j in self.waits)

    def goal_free_after(self, obj: str, lifted: frozenset[str]) -> bool:
        """The goal of ``obj`` is free once the objects in ``lifted`` are picked up."""
        return self.blockers(obj) <= lifted


class TaskPlanner(Protocol):
    """Proposes the next synchronous steps; SDAR-M tells it which one was executed."""

    @property
    def name(self) -> str: ...

    def candidates(self, view: TaskView) -> list[Step]:
        """Ranked candidates (best first); empty only when every object is at its goal."""
        ...

    def commit(self, step: Step, view: TaskView) -> None:
        """``step`` was executed from ``view`` (a planner with a fixed plan advances)."""
        ...


def step_is_valid(step: Step, view: TaskView) -> bool:
    """The step has at most one move per arm, and every goal move of it lands on a free goal
    once the step's objects are lifted."""
    lifted = frozenset(step.objects)
    if len(step.moves) > view.arms:
        return False
    return all(m.obj in view.graph.names for m in step.moves) and all(
        m.to_buffer or view.goal_free_after(m.obj, lifted) for m in step.moves
    )
