"""The vocabulary shared by rearrangement task planners (SDAR-T and the baseline) and SDAR-M.

A task planner looks at a :class:`TaskView` of the current arrangement (the dependency graph of
the objects not yet at their goals, which objects sit in buffers, and how many arms the cell
has) and proposes ranked :class:`Step` candidates: up to ``view.arms`` object moves done in one
synchronous step (every acting arm picks, then every one places). SDAR-M assigns arms, grounds
the candidates through the streams, picks one and reports it back with
:meth:`TaskPlanner.commit`.
"""

from __future__ import annotations

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
    ``cycle``, ``single``, ``buffer``, ``last``, ``plan``, ``evict``); ``rank`` orders candidates
    (lower is better).
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
class TaskView:
    """The current arrangement as a task planner sees it.

    ``graph`` is the dependency graph over the objects not at their goals (``i -> j``: ``i``
    cannot go to its goal while ``j`` rests where it does: the goal of ``i`` overlaps the
    current pose of ``j``, or one of them leaves the other no grasp); ``done`` are the objects
    at their goals; ``in_buffer`` the objects resting on a buffer; ``waits`` pairs ``(i, j)``:
    ``i`` at its goal would leave ``j`` no grasp at the goal of ``j``, so ``i`` goes to its
    goal after ``j``. ``arms``: the arms of the cell, the most moves a step may hold (>= 1).
    """

    graph: DependencyGraph
    done: frozenset[str]
    in_buffer: frozenset[str]
    waits: frozenset[tuple[str, str]] = frozenset()
    arms: int = 2

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
