"""The time budget of one SDAR-M run."""

from __future__ import annotations

import math
import time


class Deadline:
    """``max_time`` [s] from :meth:`start`; never passed before it is started."""

    def __init__(self, max_time: float) -> None:
        self.max_time = max_time
        self._at = math.inf

    def start(self) -> float:
        """Start the clock; returns the start time [s] (``time.perf_counter``)."""
        now = time.perf_counter()
        self._at = now + self.max_time
        return now

    def passed(self) -> bool:
        return time.perf_counter() > self._at
