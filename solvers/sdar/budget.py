"""The time budget of one SDAR-M run: the hard limit ``max_time`` and the soft one of the
anytime finish.

The soft limit (:meth:`Deadline.reserve`) is the time after which the run stops trying the
steps of the normal search and finishes the remaining objects with one-move steps (see
:mod:`solvers.sdar.spending`): ``max_time`` less a reserve for each remaining object. While
it is set, :meth:`Deadline.passed` answers for it, so every part that watches the clock (the
grounder, the recovery, the decision loop) stops at it; :meth:`Deadline.expired` answers for
``max_time`` alone.
"""

from __future__ import annotations

import math
import time


class Deadline:
    """``max_time`` [s] from :meth:`start`; never passed before it is started."""

    def __init__(self, max_time: float) -> None:
        self.max_time = max_time
        self._at = math.inf
        self._soft = math.inf

    def start(self) -> float:
        """Start the clock; returns the start time [s] (``time.perf_counter``)."""
        now = time.perf_counter()
        self._at = now + self.max_time
        return now

    def reserve(self, seconds: float) -> None:
        """Set the soft limit ``seconds`` [s] before ``max_time`` (``inf`` or a negative
        reserve: none)."""
        self._soft = self._at - seconds if 0 <= seconds < math.inf else math.inf

    def left(self) -> float:
        """Seconds [s] until ``max_time`` (``inf`` before :meth:`start` or without a limit)."""
        return self._at - time.perf_counter()

    def passed(self) -> bool:
        """The soft limit, when set, or ``max_time`` has passed."""
        return time.perf_counter() > min(self._at, self._soft)

    def soft_passed(self) -> bool:
        """A soft limit is set and has passed."""
        return self._soft < math.inf and time.perf_counter() > self._soft

    def expired(self) -> bool:
        """``max_time`` has passed."""
        return time.perf_counter() > self._at
