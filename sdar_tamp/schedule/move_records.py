"""What the assignment of moves to arms (:mod:`.assignment`) works with: where an arm
stands, a move's planned motions, the planner of a cell's single-arm motions (a protocol the
application fills with its streams) and the search's options."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

from sdar_tamp.errors import ParameterError
from sdar_tamp.schedule.moves import Move, Pose
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True)
class Stand:
    """Where an arm stands: ``q`` ``(k,)`` [rad] and, when it stands at a grasp or release
    configuration, ``pre`` ``(k,)`` (the pre-grasp it must retreat through), else None;
    ``back``: the path (configurations ``(m, k)``) from ``q`` out to ``pre`` along the
    approach that brought the arm there, when known (else a straight joint-space segment is
    taken); ``event``: it stands where its gripper acted last, with no pre-grasp known (its
    next motion leaves slowly all the same)."""

    q: FloatArray
    pre: FloatArray | None = None
    back: FloatArray | None = None
    event: bool = False

    @property
    def leaving(self) -> bool:
        """Whether the arm's next motion leaves a gripper event."""
        return self.pre is not None or self.event


@dataclass(frozen=True)
class PlannedMove:
    """One arm's motions of a move: ``reach`` (from where it stands to the grasp) and
    ``carry`` (grasp to release), each as times ``(m,)`` [s] and configurations ``(m, k)``
    [rad]; ``T_tcp_object`` ``(4, 4)``: the grasp; ``end``: where the arm then stands."""

    reach: tuple[FloatArray, FloatArray]
    carry: tuple[FloatArray, FloatArray]
    T_tcp_object: FloatArray
    end: Stand


class MovePlanner(Protocol):
    """Grasps, inverse kinematics and single-arm motions of a cell (the streams)."""

    def estimate(self, arm: int, stand: Stand, move: Move) -> float | None:
        """Estimated duration [s] of ``move`` by arm ``arm`` (scene order) from ``stand``,
        motions only; None when the arm cannot grasp the object at both poses."""
        ...

    def plan(
        self,
        arm: int,
        stand: Stand,
        move: Move,
        resting: Mapping[str, Pose],
        others: Sequence[FloatArray] | None = None,
    ) -> Iterator[PlannedMove]:
        """The arm's motions for ``move``, best first, against the objects ``resting``
        (name -> pose; the moved object at its start) and the other arms standing at
        ``others`` (per arm, scene order; the arm's own entry is ignored), then at home."""
        ...

    def buffer(self, move: Move, moves: Sequence[Move]) -> Pose | None:
        """A free pose for ``move``'s object, clear of every pose of ``moves``, or None."""
        ...

    def park(
        self, arm: int, stand: Stand, resting: Mapping[str, Pose], others: Sequence[FloatArray]
    ) -> tuple[FloatArray, FloatArray] | None:
        """The arm's motion (times ``(m,)``, configurations ``(m, k)``) from ``stand`` to its
        home configuration, the other arms standing at ``others`` (per arm, scene order; the
        arm's own entry is ignored), or None."""
        ...


#: How the free arm chooses its next move: ``earliest``: the ready move it would finish first
#: (by the planner's estimate); ``clear``: the same, and an arm leaves every grasp or release
#: spot as soon as it has let go (its short retreat), and goes home when it finds no move, so
#: it does not stand where another arm's move must go; ``plan-order``: the ready move that
#: comes first in the synchronous plan (another order of the same moves); ``own-first``: the
#: arm's own next move of the synchronous plan, another arm's only where that ends it
#: earlier (:mod:`.own_first`), and it leaves every spot it lets go of at once, as ``clear``.
POLICIES = ("earliest", "clear", "plan-order", "own-first")


@dataclass(frozen=True)
class AssignmentOptions:
    """``candidates``: the ready moves tried per decision (best estimate first); ``stride``:
    ticks between the starts tried for a motion (a wait is rounded up to it); ``max_wait``
    [s]: the longest wait tried before a motion (past it the arm does something else);
    ``max_checks``: the collision queries of one policy's search that the collision world
    answers (a remembered answer costs none; past them no schedule);
    ``max_plans``: motion-planner calls of one policy's search; ``replans``: conflict-based
    retries per move (:meth:`~.move_commit.MoveCommit.take`); ``slack`` [s]: a move committed
    this much later than estimated is compared with the next candidates
    (:meth:`Assignment.choose`;
    ``inf``: the first that goes is kept); ``pauses``: a motion that another arm delays may
    stop on the way and wait there (:mod:`.move_commit`); ``policies``: the ways of choosing
    the next move (:data:`POLICIES`), each searched in turn, the shortest schedule kept;
    ``max_seconds`` [s]: the wall-clock time of the whole search, every policy together
    (past it the best schedule found so far is returned); ``sync_motions``: a move carried
    by its synchronous arm is offered the plan's own motion first (:mod:`.sync_motions`;
    always with policy ``own-first``)."""

    candidates: int = 3
    stride: int = 5
    max_wait: float = 4.0
    max_checks: int = 400_000
    max_plans: int = 400
    replans: int = 1
    slack: float = math.inf
    pauses: bool = True
    policies: tuple[str, ...] = ("earliest", "clear", "plan-order")
    max_seconds: float = 300.0
    sync_motions: bool = False

    def __post_init__(self) -> None:
        bad = [p for p in self.policies if p not in POLICIES]
        if bad or not self.policies or isinstance(self.policies, str):
            raise ParameterError(
                f"policies: expected some of {list(POLICIES)}, got {self.policies!r}"
            )
        seconds = self.max_seconds
        if isinstance(seconds, bool) or not (isinstance(seconds, (int, float)) and seconds > 0):
            raise ParameterError(f"max_seconds: expected a time > 0, got {self.max_seconds!r}")
        for name in ("candidates", "stride", "max_checks", "max_plans", "replans"):
            value = getattr(self, name)
            least = 0 if name == "replans" else 1
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ParameterError(f"{name}: expected an integer >= {least}, got {value!r}")
        for name in ("max_wait", "slack"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value >= 0.0) or math.isnan(value):
                raise ParameterError(f"{name}: expected a number >= 0, got {value!r}")


__all__ = ["POLICIES", "AssignmentOptions", "MovePlanner", "PlannedMove", "Stand"]
