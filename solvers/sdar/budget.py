"""The time budget of one SDAR-M run: the hard limit ``max_time``, the soft one of the anytime
finish, and the pace that sets the soft one.

The soft limit (:meth:`Deadline.reserve`) is the time after which the run stops trying the
steps of the normal search and finishes the remaining objects with small steps (see
:mod:`solvers.sdar.spending`): ``max_time`` less a reserve for the remaining objects. While
it is set, :meth:`Deadline.passed` answers for it, so every part that watches the clock (the
grounder, the recovery, the decision loop) stops at it; :meth:`Deadline.expired` answers for
``max_time`` alone.

The reserve is estimated from the run's own decisions (:class:`Pace`): the seconds per object
brought to its goal by the finish's decisions once some were measured; before that by the normal
decisions (in either case over the whole run, or over its last :data:`RECENT` decisions when
those were slower: a machine whose load rises during the run, where the run's mean would start
the finish too late), and at least the mean time of one executed attempt of theirs (a finishing
step of one move plans about the motions a normal step plans for several); before any decision
``SdarOptions.finish_reserve``. Measured rates are multiplied by a safety factor; added is the
longest single attempt of the normal search (a decision stops at the soft limit only between
attempts, so one attempt may run past it). The reserve never exceeds ``finish_reserve`` per
object (nor ``finish_share`` of ``max_time``): on a loaded machine the measured pace would start
the finish earlier than that, and a finish's steps are not much quicker per object than a
two-arm cell's normal ones, so the paper suite would lose plans it still completes in time
(measured: docs/benchmarks.md). So the finish starts when the objects left need the time left at
the pace measured, up to that ceiling, not always at the ceiling; and once its own pace shows
room for a normal decision again, the run goes back to the normal search
(:meth:`Pace.room_for_normal`).
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

Clock = Callable[[], float]
"""A monotonic clock [s] (``time.perf_counter``; tests pass a fake one)."""


class Deadline:
    """``max_time`` [s] from :meth:`start` on ``clock``; never passed before it is started."""

    def __init__(self, max_time: float, clock: Clock = time.perf_counter) -> None:
        self.max_time = max_time
        self.clock = clock
        self._at = math.inf
        self._soft = math.inf

    def start(self) -> float:
        """Start the clock; returns the start time [s] (of ``clock``)."""
        now = self.clock()
        self._at = now + self.max_time
        return now

    def reserve(self, seconds: float) -> None:
        """Set the soft limit ``seconds`` [s] before ``max_time`` (``inf`` or a negative
        reserve: none)."""
        self._soft = self._at - seconds if 0 <= seconds < math.inf else math.inf

    def left(self) -> float:
        """Seconds [s] until ``max_time`` (``inf`` before :meth:`start` or without a limit)."""
        return self._at - self.clock()

    def passed(self) -> bool:
        """The soft limit, when set, or ``max_time`` has passed."""
        return self.clock() > min(self._at, self._soft)

    def soft_passed(self) -> bool:
        """A soft limit is set and has passed."""
        return self._soft < math.inf and self.clock() > self._soft

    def expired(self) -> bool:
        """``max_time`` has passed."""
        return self.clock() > self._at


#: The last decisions of a mode whose own pace :meth:`Pace.per_object` also reads.
RECENT = 3


@dataclass
class _Tally:
    """Decisions of one mode: their time [s], count, objects brought to their goals, and the
    last :data:`RECENT` of them ``(seconds, objects)``; the longest single attempt [s]; the
    time [s] and count of the attempts that succeeded."""

    seconds: float = 0.0
    decisions: int = 0
    objects: int = 0
    longest_attempt: float = 0.0
    executed_seconds: float = 0.0
    executed: int = 0
    recent: deque[tuple[float, int]] = field(default_factory=lambda: deque(maxlen=RECENT))

    def per_object(self) -> float | None:
        """Seconds per object over the run, or over the last decisions when slower (the
        machine got busier, or the objects left are harder); None before any object."""
        if not self.objects:
            return None
        rate = self.seconds / self.objects
        recent = sum(n for _, n in self.recent)
        if recent:
            rate = max(rate, sum(t for t, _ in self.recent) / recent)
        return rate

    def per_execution(self) -> float:
        return self.executed_seconds / self.executed if self.executed else 0.0


class Pace:
    """The measured pace of a run and the reserve the anytime finish needs from it (see the
    module docstring). ``prior`` [s] per object before any decision brought an object to its
    goal, and the most per object ever kept; ``safety`` multiplies the measured seconds per
    object; ``share`` caps the reserve at that share of ``max_time``."""

    def __init__(self, max_time: float, prior: float, safety: float, share: float) -> None:
        self.max_time = max_time
        self.prior = prior
        self.safety = safety
        self.share = share
        self.normal = _Tally()
        self.finish = _Tally()

    def decided(self, seconds: float, objects: int, finishing: bool) -> None:
        """A decision took ``seconds`` [s] and brought ``objects`` to their goals (0: it
        buffered, or executed nothing), in the finish or in the normal search."""
        tally = self.finish if finishing else self.normal
        tally.seconds += seconds
        tally.decisions += 1
        tally.objects += objects
        tally.recent.append((seconds, objects))

    def attempted(self, seconds: float, executed: bool, finishing: bool) -> None:
        """One grounding's attempt (its motions planned) took ``seconds`` [s]; ``executed``:
        its motions were found and it was executed."""
        tally = self.finish if finishing else self.normal
        tally.longest_attempt = max(tally.longest_attempt, seconds)
        if executed:
            tally.executed_seconds += seconds
            tally.executed += 1

    def per_object(self) -> float:
        """The finish's estimated seconds [s] per object, times ``safety``: measured in the
        finish; else in the normal search, and at least the mean executed attempt there (a
        finishing step moves one object with about the motions a normal step plans for
        several); else ``prior``."""
        rate = self.finish.per_object()
        if rate is not None:
            return self.safety * rate
        rate = self.normal.per_object()
        if rate is not None:
            return self.safety * max(rate, self.normal.per_execution())
        return self.prior

    def reserve(self, remaining: int) -> float:
        """The seconds [s] to keep for ``remaining`` objects: the measured need, at most
        ``prior`` per object and ``share`` of ``max_time``."""
        need = self.per_object() * remaining + self.normal.longest_attempt
        return min(need, self.prior * remaining, self.share * self.max_time)

    def room_for_normal(self, left: float, remaining: int) -> bool:
        """With ``left`` [s] to go, a normal decision of the average measured time fits before
        the reserve for ``remaining`` objects."""
        normal = self.normal.seconds / self.normal.decisions if self.normal.decisions else 0.0
        return left - self.reserve(remaining) > normal
